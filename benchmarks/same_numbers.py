"""Whether two trees compute the same numbers for a job: every output array of every tile,
byte for byte.

    python benchmarks/same_numbers.py TREE BASE JOB.yaml [--set KEY=VALUE …]

runs the job's tiles (``run_tile``, no store) in one process per tree, each with that tree
on PYTHONPATH, and prints one line: the job, its cells, and "bit-identical" or the arrays
that differ with the number of cells where they do (NaN equal to NaN). ``--set`` changes
the job as ``campar run --set`` does. The exit status is 1 where an array differs.

    PYTHONPATH=TREE python benchmarks/same_numbers.py --child OUT.npz JOB.yaml [--set …]

is one such process: it writes the arrays to OUT.npz and prints its CPU seconds.
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def child(out: str, job_path: str, sets: list[str]) -> None:
    from campar.sweep.job import load_job
    from campar.sweep.overrides import parse_assignment, with_settings
    from campar.sweep.plan import plan_tiles
    from campar.sweep.tile import run_tile

    job = with_settings(load_job(job_path), dict(parse_assignment(s) for s in sets))
    parts: dict[str, list[np.ndarray]] = {}
    start = time.process_time()
    for tile in plan_tiles(job):
        for name, values in run_tile(job, tile).items():
            parts.setdefault(name, []).append(values)
    np.savez(out, **{name: np.concatenate(v) for name, v in parts.items()})
    print(f"{time.process_time() - start:.2f}")


def differing_cells(a: np.ndarray, b: np.ndarray) -> int:
    differ = ~((a == b) | (np.isnan(a) & np.isnan(b))) if a.dtype.kind == "f" else a != b
    return int(differ.reshape(differ.shape[0], differ.shape[1], -1).any(axis=-1).sum())


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("paths", nargs="+", help="TREE BASE JOB.yaml (--child: OUT.npz JOB.yaml)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--child", action="store_true", help="compute the job in this process")
    a = parser.parse_args()
    if a.child:
        child(*a.paths, a.set)
        return 0
    if len(a.paths) != 3:
        parser.error("name TREE, BASE and JOB.yaml")
    *trees, job = a.paths
    arrays = []
    with tempfile.TemporaryDirectory() as tmp:
        for k, tree in enumerate(trees):
            out = str(Path(tmp) / f"{k}.npz")
            env = dict(os.environ, PYTHONPATH=str(Path(tree).resolve()))
            sets = [f"--set={s}" for s in a.set]
            args = [sys.executable, __file__, "--child", out, job, *sets]
            subprocess.run(args, env=env, check=True, stdout=subprocess.DEVNULL)
            with np.load(out) as data:
                arrays.append({name: data[name] for name in data.files})
    mine, base = arrays
    differ = {name: "absent" for name in base.keys() - mine.keys()}
    differ |= {name: "new" for name in mine.keys() - base.keys()}
    differ |= {
        name: f"{differing_cells(mine[name], base[name])} cells"
        for name in base.keys() & mine.keys()
        if mine[name].tobytes() != base[name].tobytes()
    }
    cells = "×".join(str(n) for n in next(iter(base.values())).shape[:2])
    verdict = ", ".join(f"{n} ({c})" for n, c in sorted(differ.items())) or "bit-identical"
    print(f"{job} {' '.join(a.set)}: {cells} cells, {len(base)} arrays: {verdict}")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
