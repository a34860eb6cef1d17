"""``campar bench directions``: what does a map of both sweep directions cost?

A sub-plane of a job's plane (default jobs/mu_cn.yaml's ranges, N × N points, its
chain start and outputs) is run by the serial runner into a temporary store
three ways: ``chains.direction`` down, up, and both. A ``both`` job stores
``sections`` too (the hysteresis test needs them), so down and up are run with
the job's outputs plus ``sections``: the comparison is of the directions, not of
the outputs. The runs alternate (down, up, both, both, up, down, …) so all see
the same machine load; the fastest of each is kept in CPU seconds of this process (the
runner's compute thread included), wall seconds beside. The target is both ≤ 2.1 × down
(its two directions, and a twentieth for pairing them); ``both/(down+up)`` shows the
overhead of the pairing itself (≈ 1: a both map is its two directions' tiles, nothing
more).
The both store must equal the down and up stores bit for bit, and the share of
hysteretic cells is printed.
"""

import tempfile
from pathlib import Path

import numpy as np
import yaml

from ..sweep.job import Job
from ..sweep.runner import run_job
from ..sweep.store import read_store
from ..views.dataset import open as open_store
from .common import Timing, format_table, machine_line, timed

QUICK = {"size": 8, "repeat": 1}
TARGET = 2.1  # both / one direction at most: two directions' work, a twentieth for the pairing
RUNS = ("down", "up", "both")  # chains.direction of the three runs


def make_job(source: Path, size: int, direction: str) -> Job:
    """``source``'s plane at size × size points, chains run ``direction``, with sections."""
    data = yaml.safe_load(source.read_text())
    data["name"] = f"bench_directions_{direction}"
    data.pop("store", None)
    for axis in data["sweep"].values():
        axis["points"] = size
    data.setdefault("chains", {})["direction"] = direction
    outputs = data.get("outputs", ["label", "dc", "eps", "pn"])
    data["outputs"] = [*outputs, *(["sections"] if "sections" not in outputs else [])]
    return Job.from_dict(data, source=f"campar bench directions ({source})")


def measure(source: Path, size: int, repeat: int) -> dict:
    jobs = {d: make_job(source, size, d) for d in RUNS}
    best = {d: Timing(np.inf, np.inf) for d in RUNS}
    with tempfile.TemporaryDirectory(prefix="campar-bench-directions-") as tmp:
        stores = {d: Path(tmp) / f"{d}.zarr" for d in RUNS}
        run_job(make_job(source, 2, "down"), Path(tmp) / "warm.zarr")  # load the kernel
        for run in range(repeat):
            for d in RUNS[:: 1 if run % 2 == 0 else -1]:  # ABBA: no order bias
                took, _ = timed(lambda d=d: run_job(jobs[d], stores[d], overwrite=True))
                best[d] = Timing(min(best[d].wall, took.wall), min(best[d].cpu, took.cpu))
        same = same_as_parts(stores)
        with open_store(stores["both"]) as ds:
            hysteretic = int(ds["hysteresis"].sum())
    return {"best": best, "same": same, "hysteretic": hysteretic, "cells": size * size}


def same_as_parts(stores: dict[str, Path]) -> bool:
    """The both store's arrays are the down and up stores' arrays, bit for bit."""
    with read_store(stores["both"]) as both:
        for layer, d in enumerate(("down", "up")):
            with read_store(stores[d]) as one:
                for name in one.names:
                    if not np.array_equal(both.read(name)[layer], one.read(name), equal_nan=True):
                        return False
    return True


def run(args) -> int:
    config = {"size": args.size, "repeat": args.repeat}
    if args.quick:
        config.update(QUICK)
    print(machine_line())
    r = measure(Path(args.job), **config)
    best, cells = r["best"], r["cells"]
    rows = [
        [
            d,
            cells * (2 if d == "both" else 1),
            best[d].cpu,
            best[d].wall,
            best[d].cpu / best["down"].cpu,
            best[d].wall / best["down"].wall,
        ]
        for d in RUNS
    ]
    headers = ["direction", "cells", "CPU s", "wall s", "CPU / down", "wall / down"]
    print(format_table(headers, rows))
    ratio = best["both"].cpu / best["down"].cpu
    pairing = best["both"].cpu / (best["down"].cpu + best["up"].cpu)
    print(
        f"\n{args.job}: {config['size']}×{config['size']} sub-plane, fastest of "
        f"{config['repeat']} alternating runs each; both / down = {ratio:.2f} CPU "
        f"({'within' if ratio <= TARGET else 'ABOVE'} the target {TARGET}), both / (down + up) "
        f"= {pairing:.2f}; both store = down and up stores bit for bit: "
        f"{'yes' if r['same'] else 'NO'}; hysteretic cells {r['hysteretic']} of {cells}"
    )
    print(f"load average at the end: {machine_line().rsplit('load average ', 1)[1]}")
    return 0 if r["same"] else 1
