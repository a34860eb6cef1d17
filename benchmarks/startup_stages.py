"""A one-process ``campar run``'s fixed cost, step by step: wall and CPU seconds of each.

    PYTHONPATH=TREE python -P benchmarks/startup_stages.py JOB STORE

does in this process, in order, what ``campar run JOB --store STORE`` does before and
after its cells (STORE must not exist): import the command line, validate the job,
import the runner (numba), load the kernel, import the store's backend, create the
store, compute and write the first tile; and prints each step's seconds.
"""

import sys
import time
from pathlib import Path


def main(job_path: str, store_path: str) -> None:
    marks = [("start", time.perf_counter(), time.process_time())]

    def mark(name: str) -> None:
        marks.append((name, time.perf_counter(), time.process_time()))

    import campar.cli  # noqa: F401 (the command line's imports)

    mark("import campar.cli")
    from campar.api import job_of

    job = job_of(job_path)
    mark("job")
    from campar.sweep import runner  # noqa: F401 (numba, the kernel's modules)

    mark("import runner")
    from campar.sweep.tile import compile_kernel, run_tile

    compile_kernel(job)
    mark("kernel load")
    from campar.sweep.store import _backend, open_store

    _backend(Path(store_path))
    mark("import store backend")
    store = open_store(store_path, job)
    mark("create store")
    from campar.sweep.plan import plan_tiles

    tile = plan_tiles(job)[0]
    arrays = run_tile(job, tile)
    mark("tile")
    store.write_tile(tile, arrays)
    store.close()
    mark("write and close")
    for (_, wall, cpu), (name, wall2, cpu2) in zip(marks, marks[1:], strict=False):
        print(f"{name:22s} wall {wall2 - wall:6.3f} s  cpu {cpu2 - cpu:6.3f} s")
    (_, wall, cpu), (_, wall2, cpu2) = marks[0], marks[-1]
    print(f"{'total':22s} wall {wall2 - wall:6.3f} s  cpu {cpu2 - cpu:6.3f} s")


if __name__ == "__main__":
    main(*sys.argv[1:3])
