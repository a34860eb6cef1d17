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
between the two counted. ``--adjudicate`` then runs each of those cells again, from each
tree's own hand-off (the final state of the cell before it along the chain: the warm
start unless the two cells before it are cycles of one period, which are counted), with
this tree's kernel for LONG_RUN revolutions and no early non-periodic verdict: a tree's
label is right where it is its long run's, and the counts of cells each tree has right
are printed.

    campar bench revolutions
    campar bench revolutions --baseline ../main --adjudicate
    campar bench revolutions --baseline ../main --set sweep.omega.points=200
"""

import math
import os
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

import numpy as np

import campar

from ..core.codes import Kind, cell_label
from ..sweep.store import read_store
from .common import format_table, machine_line

LONG = 20  # a periodic cell over this many revolutions counts as a long transient
BY_PERIOD = 4  # the mean revolutions of the cycles of each period up to this one (and longer)
LONG_RUN = 3000  # revolutions of an adjudicating run, which has no early non-periodic verdict
FIELDS = ("revolutions", "kind", "n", "p", "state")
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
    """The store's per-cell revolutions, kind, n, p and final state (flat over the cells),
    and the version of the kernel that wrote it."""
    with read_store(store) as reader:
        cells = {}
        for name in FIELDS:
            values = np.asarray(reader.read(name))
            cells[name] = values.reshape(-1, 2) if name == "state" else values.ravel()
        cells["kernel"] = reader.attrs.get("versions", {}).get("kernel", "?")
    return cells


def distribution(cells: dict) -> dict:
    """Mean, median, p90, p99 and max revolutions per cell; the shares of all revolutions
    taken by non-periodic cells and by periodic cells over LONG revolutions; their counts;
    the mean of the cycles of each period up to BY_PERIOD (the last row: that period and
    longer) and of the non-periodic cells (NaN where there are none)."""
    revs = cells["revolutions"].astype(float)
    total = revs.sum()
    periodic = cells["kind"] == Kind.PERIODIC
    long = periodic & (revs > LONG)
    period = np.where(periodic, np.minimum(cells["n"], BY_PERIOD), 0)
    means = {
        f"mean, period {n}{'+' if n == BY_PERIOD else ''}": mean_of(revs[period == n])
        for n in range(1, BY_PERIOD + 1)
    }
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
        **means,
        "mean, non-periodic": mean_of(revs[~periodic]),
    }


def mean_of(values: np.ndarray) -> float:
    return float(values.mean()) if values.size else math.nan


def labels_differ(a: dict, b: dict) -> np.ndarray:
    """Whether each cell's label (kind, and n, p where periodic) differs between two stores."""
    periodic = (a["kind"] == Kind.PERIODIC) & (b["kind"] == Kind.PERIODIC)
    return (a["kind"] != b["kind"]) | (periodic & ((a["n"] != b["n"]) | (a["p"] != b["p"])))


def label_at(cells: dict, i: int) -> str:
    return cell_label(int(cells["kind"][i]), int(cells["n"][i]), int(cells["p"][i]))


def adjudicate(job_path: str, sets: list[str], found: dict, differ: np.ndarray) -> dict:
    """The long runs of the cells whose label differs (module docstring): for each tree,
    how many of them it has right, and which label changes the long runs side with."""
    from ..sweep.job import load_job
    from ..sweep.overrides import parse_assignment, with_settings
    from ..sweep.plan import chain_order
    from ..views.point import simulate_point

    job = with_settings(load_job(job_path), dict(parse_assignment(item) for item in sets))
    shape = job.shape
    order = chain_order(job)
    place = np.empty(shape[1], int)
    place[order] = np.arange(shape[1])  # each column's place in its chain
    right = Counter()
    changes = Counter()
    for flat in np.flatnonzero(differ):
        row, col = np.unravel_index(flat, shape)
        k = place[col]
        if k == 0:
            right["first cells (not run)"] += 1
            continue
        before = np.ravel_multi_index((row, order[k - 1]), shape)
        two_before = np.ravel_multi_index((row, order[k - 2]), shape) if k >= 2 else None
        model = job.cell_model(row, col)
        verdicts = {}
        for name, cells in found.items():
            if two_before is not None and same_period(cells, before, two_before):
                right[f"{name}: start may be extrapolated (hand-off used)"] += 1
            start = tuple(float(v) for v in cells["state"][before])
            long = simulate_point(model, state=start, revolutions=LONG_RUN, chaos_after=0)
            verdicts[name] = long.label == label_at(cells, flat)
        for name, ok in verdicts.items():
            right[f"{name} right"] += ok
        change = (label_at(found["baseline"], flat), label_at(found["this"], flat))
        changes[(*change, verdicts["this"])] += 1
    right["cells"] = int(differ.sum())
    return {"counts": dict(right), "changes": changes}


def same_period(cells: dict, i: int, j: int) -> bool:
    """Cells i and j are cycles of one period: the chain extrapolates the next start
    through them (core.kernel.extrapolation_order)."""
    periodic = cells["kind"][i] == Kind.PERIODIC and cells["kind"][j] == Kind.PERIODIC
    return bool(periodic and cells["n"][i] == cells["n"][j])


def report_adjudication(found: dict) -> None:
    print(f"\nlong runs ({LONG_RUN} revolutions, no early verdict) from each tree's hand-off:")
    for key, count in found["counts"].items():
        print(f"  {key}: {count}")
    print("  label changes (baseline → this), with the long run siding with this tree:")
    for (baseline, this, right), count in found["changes"].most_common():
        print(f"    {baseline} → {this}: {count} ({'this' if right else 'not this'})")


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
            differ = labels_differ(a, b)
            print(f"cells whose label differs from the baseline's: {int(differ.sum())}")
            if args.adjudicate:
                report_adjudication(adjudicate(args.job, sets, found, differ))
    print(machine_line())
    return 0
