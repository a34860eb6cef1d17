"""The extrema's cost: CPU seconds of the computation alone of the first rows (8,000 cells
at 20 rows) of the (ω, μcn) plane, jobs/mu_cn.yaml at 400 × 400, tree against tree.

    python benchmarks/extrema_cost.py TREE BASE [BASE …] [--pairs 5] [--rows 20] [--passes 3]
                                      [--outputs label,dc]

runs, for each of ``--pairs`` rounds, one process per tree in turn (TREE first, then each
BASE), each with that tree on PYTHONPATH: a process computes every tile once (to compile
or load the kernel), then ``--passes`` times timed, and reports its fastest pass (CPU s;
the fastest of a few passes sheds other processes' load). Prints every round, each
tree's median, and the median over rounds of TREE's time over each BASE's (the paired
ratio), e.g. 1.03 for +3 %. ``--outputs`` replaces the job's outputs (e.g. ``label,dc``:
what a map that stores no extremum costs).

    PYTHONPATH=TREE python benchmarks/extrema_cost.py --child [--rows 20] [--passes 3] [--outputs …]

is one such process: it prints its CPU seconds.
"""

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

JOB = Path(__file__).resolve().parent.parent / "jobs" / "mu_cn.yaml"


def child(rows: int, passes: int, outputs: str | None) -> float:
    import yaml

    from campar.sweep.job import Job
    from campar.sweep.plan import plan_tiles
    from campar.sweep.tile import run_tile

    with open(JOB) as fh:
        spec = yaml.safe_load(fh)
    step = (0.95 - 0.70) / 399
    spec["sweep"]["mu_cn"] = {"from": 0.95, "to": 0.95 - (rows - 1) * step, "points": rows}
    spec.pop("store", None)
    if outputs:
        spec["outputs"] = outputs.split(",")
    job = Job.from_dict(spec)
    tiles = plan_tiles(job)
    run_tile(job, tiles[0])  # compiled or loaded from the cache
    best = float("inf")
    for _ in range(passes):
        start = time.process_time()
        for tile in tiles:
            run_tile(job, tile)
        best = min(best, time.process_time() - start)
    return best


def measure(tree: str, rows: int, passes: int, outputs: str | None) -> float:
    env = dict(os.environ, PYTHONPATH=str(Path(tree).resolve()))
    args = [sys.executable, __file__, "--child", "--rows", str(rows), "--passes", str(passes)]
    if outputs:
        args += ["--outputs", outputs]
    done = subprocess.run(args, env=env, capture_output=True, text=True, check=True)
    return float(done.stdout.split()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("trees", nargs="*", help="TREE, then the trees it is compared with")
    parser.add_argument("--child", action="store_true", help="time this process's campar")
    parser.add_argument("--rows", type=int, default=20)
    parser.add_argument("--passes", type=int, default=3)
    parser.add_argument("--pairs", type=int, default=5)
    parser.add_argument("--outputs", help="the job's outputs instead of its own, e.g. label,dc")
    a = parser.parse_args()
    if a.child:
        print(f"{child(a.rows, a.passes, a.outputs):.3f}")
        return
    if len(a.trees) < 2:
        parser.error("name a tree and at least one tree to compare it with")
    times: dict[str, list[float]] = {t: [] for t in a.trees}
    for r in range(a.pairs):
        row = [measure(t, a.rows, a.passes, a.outputs) for t in a.trees]
        for t, s in zip(a.trees, row, strict=True):
            times[t].append(s)
        print(f"round {r + 1}: " + "  ".join(f"{s:.3f}" for s in row), flush=True)
    tree = a.trees[0]
    for t in a.trees:
        lo, hi = min(times[t]), max(times[t])
        print(f"{t}: median {statistics.median(times[t]):.3f} s ({lo:.3f}–{hi:.3f})")
    for base in a.trees[1:]:
        ratios = [x / y for x, y in zip(times[tree], times[base], strict=True)]
        print(f"{tree} / {base}: median paired ratio {statistics.median(ratios):.3f}")


if __name__ == "__main__":
    main()
