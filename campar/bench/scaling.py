"""``campar bench scaling``: cells/s with one process and under ``mpirun -n 2`` / ``-n 3``.

Runs ``campar run`` on an N × N sub-plane of a plane (default the (ω, μcn)
plane of jobs/mu_cn.yaml: same ranges, N points on each axis) once per launch
configuration, each into a fresh store, and reads the run log the master
writes. Reported per configuration:

- cells/s of the run (store open to last tile written; process start-up and
  numba cache loading are shown apart as "start s");
- speed-up over one process: the fastest run of each launch against the fastest of the
  first, and "paired": the median over rounds of each round's ratio. With ``--repeat`` the
  launches take turns (1, 2, 3, 1, 2, 3, …), so a machine whose speed drifts over
  minutes moves both runs of a round alike; the fastest-of-each figure mixes minutes.
  Each round's own speed-up is printed below the table, so the spread behind the median
  shows;
- outside kernel: the share of (wall time × compute lanes) not spent inside
  ``run_tile`` — the runner's own cost plus lanes idle at the end of the run
  (target ≤ 3 %);
- cores busy: CPU seconds of all ranks / run seconds — below the core count
  on a machine shared with other work, which then caps the speed-up;
- peak RSS per rank (target ≤ 400 MB);
- revolutions per cell (mean) and the tiles each rank computed.

Every map is also checked against the first launch's, bit for bit.

    campar bench scaling                                  # 100 × 100, 1/2/3 ranks
    campar bench scaling --size 400 --ranks 2             # the full plane, mpirun -n 2
"""

import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

from ..errors import JobError
from .common import machine_line

MPIRUN = Path(sys.executable).parent / "mpirun"


QUICK = {"size": 8, "ranks": [1, 2], "repeat": 2}


def write_job(source: Path, directory: Path, size: int, rows: int | None) -> Path:
    """``source`` at size × size points (rows chains a tile, else the job's own) without a store."""
    if not source.is_file():
        raise JobError(f"{source}: no such job file (give --job PATH)")
    data = yaml.safe_load(source.read_text())
    data["name"] = f"bench_{size}"
    for axis in data["sweep"].values():
        axis["points"] = size
    if rows:
        data["tiles"] = {"rows": rows}
    data.pop("store", None)
    path = directory / "bench.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def launch(job: Path, store: Path, ranks: int) -> tuple[dict, float]:
    """`campar run` with this many ranks: (the run's log entry, wall seconds with start-up)."""
    launcher = [] if ranks == 1 else [str(MPIRUN), "-n", str(ranks)]
    command = [*launcher, sys.executable, "-m", "campar.cli", "run", str(job)]
    start = time.perf_counter()
    done = subprocess.run(
        [*command, "--store", str(store), "--overwrite"], capture_output=True, text=True
    )
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed ({done.returncode}):\n{done.stderr}")
    from campar.sweep.store import read_store

    with read_store(store) as reader:
        return reader.attrs["runs"][-1], wall


def mean_revolutions(store: Path) -> float:
    from campar.sweep.store import read_store

    with read_store(store) as reader:
        return float(np.mean(reader.read("revolutions")))


def same_maps(a: Path, b: Path) -> bool:
    from campar.sweep.store import read_store

    with read_store(a) as x, read_store(b) as y:
        return all(np.array_equal(x.read(n), y.read(n), equal_nan=True) for n in x.names)


def run(args) -> int:
    if args.quick:
        for key, value in QUICK.items():
            setattr(args, key, value)
    print(machine_line())
    with tempfile.TemporaryDirectory(prefix="campar-bench-") as tmp:
        tmp = Path(tmp)
        job = write_job(Path(args.job), tmp, args.size, args.rows)
        (tmp / "warm").mkdir()
        warm = write_job(Path(args.job), tmp / "warm", 2, 1)
        launch(warm, tmp / "warm.zarr", 1)  # compiles if the cache is cold
        # A fresh store each run, so that no run pays for deleting the last one's files: on a
        # file system that discards freed blocks (ext4 -o discard) an overwrite costs the
        # next run system time a rank (benchmarks/RESULTS.md).
        runs = {ranks: [] for ranks in args.ranks}  # ranks → [(entry, wall, store)] by round
        for round_ in range(args.repeat):
            for ranks in args.ranks:
                store = tmp / f"ranks{ranks}-{round_}{args.suffix}"
                runs[ranks].append((*launch(job, store, ranks), store))
        rows, first = [], runs[args.ranks[0]]
        first_best = max(first, key=lambda run: run[0]["cells_per_s"])
        by_round = {
            ranks: [
                r[0]["cells_per_s"] / f[0]["cells_per_s"]
                for r, f in zip(runs[ranks], first, strict=True)
            ]
            for ranks in args.ranks
        }
        for ranks in args.ranks:
            entry, wall, store = max(runs[ranks], key=lambda run: run[0]["cells_per_s"])
            lanes = entry["ranks"]
            outside = 1 - entry["compute_seconds"] / (entry["seconds"] * lanes)
            speedup = entry["cells_per_s"] / first_best[0]["cells_per_s"]
            paired = np.median(by_round[ranks])
            rows.append(
                (
                    "1 process" if ranks == 1 else f"mpirun -n {ranks}",
                    f"{entry['cells_per_s']:.1f}",
                    f"{speedup:.2f}×",
                    f"{paired:.2f}×",
                    f"{entry['seconds']:.1f}",
                    f"{wall - entry['seconds']:.1f}",
                    f"{100 * outside:.1f} %",
                    f"{sum(c or 0 for c in entry['cpu_seconds']) / entry['seconds']:.2f}",
                    " ".join("?" if mb is None else f"{mb:.0f}" for mb in entry["peak_rss_mb"]),
                    f"{mean_revolutions(store):.2f}",
                    " ".join(map(str, entry["tiles_per_rank"])),
                    "yes" if same_maps(store, first_best[2]) else "NO",
                )
            )
    cells = args.size * args.size
    chains = args.rows or "the job's"
    print(
        f"\n{args.job}: {args.size}×{args.size} = {cells} cells, {chains} chains a tile, "
        f"{args.suffix}\n"
    )
    header = (
        "launch",
        "cells/s",
        "speed-up",
        "paired",
        "run s",
        "start s",
        "outside kernel",
        "cores busy",
        "peak RSS MB/rank",
        "rev/cell",
        "tiles/rank",
        "same map",
    )
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(header)]
    for line in (header, *rows):
        print("  ".join(cell.rjust(w) for cell, w in zip(line, widths, strict=True)))
    if args.repeat > 1:  # the spread behind "paired": each round's speed-up, in order
        base = "one process" if args.ranks[0] == 1 else f"mpirun -n {args.ranks[0]}"
        print(f"\nspeed-up over {base}, by round:")
        for ranks in args.ranks[1:]:
            print(f"  mpirun -n {ranks}: " + " ".join(f"{x:.2f}×" for x in by_round[ranks]))
    return 0 if all(r[-1] == "yes" for r in rows) else 1
