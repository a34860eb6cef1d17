"""Where a ``campar run`` waits: each rank's timeline of the runner's steps.

    LAUNCH_T=$(date +%s.%N) PYTHONPATH=TREE mpirun -n 2 \\
        python -P benchmarks/startup_timeline.py run JOB --store STORE
    LAUNCH_T=$(date +%s.%N) PYTHONPATH=TREE python -P benchmarks/startup_timeline.py run …

runs ``campar`` with its arguments in this process (as ``campar.cli.main`` with a list)
and prints to stderr, at the end, one line per event: the rank, seconds since
``LAUNCH_T`` (the launcher's start), the process's CPU seconds, the thread and the event —
the imports done, then the start and end of the runner's steps (tile rows, the cache's
sharers, the store's opening, the kernel's loads, each tile, the writer, the master).
"""

import atexit
import os
import sys
import threading
import time

T0 = float(os.environ["LAUNCH_T"])
RANK = os.environ.get("PMI_RANK", os.environ.get("OMPI_COMM_WORLD_RANK", "0"))
EVENTS = []
STEPS = (
    "agreed_tile_rows",
    "cache_sharers",
    "open_store",
    "compile_kernel",
    "load_kernel",
    "run_tile",
    "run_master",
)


def mark(name: str) -> None:
    thread = threading.current_thread().name[:14]
    EVENTS.append((time.time() - T0, time.process_time(), thread, name))


def timed(module, name: str, label: str) -> None:
    """``module.name`` marks its start and end."""
    function = getattr(module, name)

    def wrapper(*args, **kwargs):
        mark(f"{label} start")
        try:
            return function(*args, **kwargs)
        finally:
            mark(f"{label} end")

    setattr(module, name, wrapper)


def report() -> None:
    mark("exit")
    for t, cpu, thread, name in EVENTS:
        print(f"rank {RANK} {t:7.3f} s  cpu {cpu:6.3f}  {thread:14s} {name}", file=sys.stderr)


def main() -> int:
    mark("python up")
    import campar.cli

    mark("campar.cli imported")
    from campar.sweep import runner, wire

    mark("runner imported")
    for step in STEPS:
        timed(runner, step, step)
    timed(wire, "WriterThread", "writer")
    atexit.register(report)
    code = campar.cli.main(sys.argv[1:])
    mark("main returned")
    return code


if __name__ == "__main__":
    sys.exit(main())
