"""``campar bench revolutions``: where a map's revolutions go.

A map job (default jobs/mu_cn.yaml, the paper's (ω, μcn) plane at 400 × 400; ``--set``
changes any key, e.g. ``--set sweep.omega.points=100 --set sweep.mu_cn.points=100`` to
shrink it) is computed with ``campar run`` in a child process, and its stored revolution
counts are summarised: the mean, median, 90th and 99th percentile and largest number of
revolutions per cell, the share of all revolutions taken by the non-periodic cells (QP,
chaos, unconverged) and by the periodic cells over 20 revolutions, and the count of each.

With ``--baseline DIR`` (another campar checkout, e.g. main's) the same job is also
computed by that tree (its child process runs with DIR first on PYTHONPATH) in the same
run, its distribution printed beside this tree's, and the cells whose label differs
between the two counted: the cells to adjudicate with a long run (``campar point --from
STORE`` with ``--set transient.chaos_after=0`` and a long budget).

    campar bench revolutions
    campar bench revolutions --baseline ../main --set sweep.omega.points=200
"""

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

import campar

from ..core.codes import Kind
from ..sweep.store import read_store
from .common import format_table, machine_line

LONG = 20  # a periodic cell over this many revolutions counts as a long transient
FIELDS = ("revolutions", "kind", "n", "p")
QUICK_SETS = ("sweep.omega.points=8", "sweep.mu_cn.points=3")


def compute(job: str, sets: list[str], store: Path, tree: str | None) -> None:
    """``campar run JOB --store STORE --set …`` in a child process, from ``tree`` (a
    checkout put first on PYTHONPATH) or this campar's; ``-P``: the working directory,
    which may hold another campar, is not on its path."""
    command = [sys.executable, "-P", "-m", "campar.cli", "run", job, "--store", str(store)]
    for item in sets:
        command += ["--set", item]
    env = dict(os.environ)
    root = tree or str(Path(campar.__file__).resolve().parents[1])
    env["PYTHONPATH"] = os.pathsep.join([root, *filter(None, [env.get("PYTHONPATH")])])
    done = subprocess.run(command, capture_output=True, text=True, env=env)
    if done.returncode != 0:
        who = tree or "this tree"
        raise RuntimeError(
            f"{' '.join(command)} ({who}) failed ({done.returncode}):\n{done.stderr}"
        )


def stored_cells(store: Path) -> dict:
    """The store's per-cell revolutions, kind, n and p (flat arrays), and the version of
    the kernel that wrote it."""
    with read_store(store) as reader:
        cells = {name: np.asarray(reader.read(name)).ravel() for name in FIELDS}
        cells["kernel"] = reader.attrs.get("versions", {}).get("kernel", "?")
    return cells


def distribution(cells: dict) -> dict:
    """Mean, median, p90, p99 and max revolutions per cell; the shares of all revolutions
    taken by non-periodic cells and by periodic cells over LONG revolutions; their counts."""
    revs = cells["revolutions"].astype(float)
    total = revs.sum()
    periodic = cells["kind"] == Kind.PERIODIC
    long = periodic & (revs > LONG)
    return {
        "kernel": cells.get("kernel", "?"),
        "cells": revs.size,
        "mean": revs.mean(),
        "median": float(np.median(revs)),
        "p90": float(np.percentile(revs, 90)),
        "p99": float(np.percentile(revs, 99)),
        "max": revs.max(),
        "non-periodic": int((~periodic).sum()),
        "non-periodic share": revs[~periodic].sum() / total,
        f"periodic > {LONG}": int(long.sum()),
        f"periodic > {LONG} share": revs[long].sum() / total,
    }


def labels_differ(a: dict, b: dict) -> int:
    """Cells whose label (kind, and n, p where periodic) differs between two stores."""
    periodic = (a["kind"] == Kind.PERIODIC) & (b["kind"] == Kind.PERIODIC)
    differ = (a["kind"] != b["kind"]) | (periodic & ((a["n"] != b["n"]) | (a["p"] != b["p"])))
    return int(differ.sum())


def run(args) -> int:
    sets = list(args.set or [])
    if args.quick:
        sets = [*QUICK_SETS, *sets]
    trees = {"this": None}
    if args.baseline:
        trees["baseline"] = str(Path(args.baseline).resolve())
    print(machine_line())
    found = {}
    with tempfile.TemporaryDirectory(prefix="campar-bench-") as tmp:
        for name, tree in trees.items():
            store = Path(tmp) / f"{name}.zarr"
            compute(args.job, sets, store, tree)
            found[name] = stored_cells(store)
    rows = {name: distribution(cells) for name, cells in found.items()}
    keys = list(rows["this"])
    print(f"\n{args.job}" + "".join(f" --set {s}" for s in sets))
    print(format_table(["", *rows], [[key, *(r[key] for r in rows.values())] for key in keys]))
    if "baseline" in found:
        a, b = found["this"], found["baseline"]
        if a["kind"].shape == b["kind"].shape:
            print(f"cells whose label differs from the baseline's: {labels_differ(a, b)}")
    print(machine_line())
    return 0
