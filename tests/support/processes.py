"""campar and mpirun as child processes: starting them, watching a run's store and its
ranks, killing a run as a node failure would. A test that uses these is marked
``process`` (and ``mpi`` where it starts mpirun); the tiers plugin checks that."""

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from support.stores import assert_same_store, stored

CAMPAR = [sys.executable, "-m", "campar.cli"]
MPIRUN = Path(sys.executable).parent / "mpirun"
NEEDS_MPIRUN = pytest.mark.skipif(not MPIRUN.exists(), reason=f"no mpirun at {MPIRUN}")
# (suffix, ranks) of a test that runs into each backend, in one process and under
# ``mpirun -n 2`` (marked mpi, skipped where there is no mpirun).
BACKENDS_AND_RANKS = [
    (".zarr", 1),
    (".h5", 1),
    *(pytest.param(s, 2, marks=[pytest.mark.mpi, NEEDS_MPIRUN]) for s in (".zarr", ".h5")),
]


def run_campar(*args, launcher=(), timeout=300, **kwargs) -> subprocess.CompletedProcess:
    """``campar ARGS`` (under ``launcher``, e.g. mpirun -n 2) in a child process, its
    output captured as text."""
    return subprocess.run(
        [*map(str, launcher), *CAMPAR, *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        **kwargs,
    )


def run_campar_mpi(ranks: int, *args, timeout=300) -> subprocess.CompletedProcess:
    """``mpirun -n RANKS campar ARGS``, its output captured as text."""
    launcher = (MPIRUN, "-n", ranks)
    return run_campar(*args, launcher=launcher, timeout=timeout, env=subprocess_env())


def subprocess_env() -> dict:
    # Unbuffered, so a test can read a child's progress while it runs.
    return {**os.environ, "PYTHONUNBUFFERED": "1"}


def tree_env() -> dict:
    """The environment of a ``python -c`` child that imports the test modules: the tests'
    folder and the tree under test come first on its path, so it runs this tree's campar
    whatever the working directory (an installed campar may be another checkout's)."""
    tests = Path(__file__).resolve().parents[1]
    path = [str(tests), str(tests.parent), os.environ.get("PYTHONPATH", "")]
    return {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, path))}


def start_campar(*args, launcher=(), **kwargs) -> subprocess.Popen:
    """Start ``campar ARGS`` (under ``launcher``, e.g. mpirun -n 2) in its own session."""
    return subprocess.Popen(
        [*map(str, launcher), *CAMPAR, *map(str, args)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=subprocess_env(),
        start_new_session=True,  # killpg reaches mpirun and every rank
        **kwargs,
    )


def wait_for_tiles(store, count: int, proc: subprocess.Popen, timeout=300.0) -> int:
    """Poll a store being written until ``count`` tiles are done; returns how many are."""
    from campar.errors import StoreError
    from campar.sweep.store import read_store

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise AssertionError(f"run ended early ({proc.returncode}): {proc.stderr.read()}")
        try:
            with read_store(store) as reader:
                done = int(reader.done.sum())
        except (StoreError, OSError):
            done = 0  # not created yet, or replaced under us
        if done >= count:
            return done
        time.sleep(0.02)
    raise AssertionError(f"{store}: fewer than {count} tiles done after {timeout} s")


def _children() -> dict[int, list[int]]:
    """Every process's children, read from /proc."""
    children: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            parent = int(stat.read_text().rpartition(")")[2].split()[1])
        except (OSError, IndexError, ValueError):
            continue
        children.setdefault(parent, []).append(int(stat.parent.name))
    return children


def kill_tree(pid: int) -> None:
    """SIGKILL a process and all its descendants, as a node failure would. (hydra starts
    each rank in a session of its own, so killing mpirun's process group misses them.)"""
    children = _children()
    doomed, todo = [], [pid]
    while todo:
        doomed.append(todo.pop())
        todo += children.get(doomed[-1], [])
    for victim in reversed(doomed):  # the ranks first, so none outlives its launcher
        with contextlib.suppress(ProcessLookupError):
            os.kill(victim, signal.SIGKILL)


def guarded(pid: int) -> bool:
    """campar's stop-signal handlers are installed in process ``pid`` (SIGUSR1 caught:
    Python installs no handler of its own for it)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    mask = next(
        (line.split()[1] for line in status.splitlines() if line.startswith("SigCgt:")), "0"
    )
    return bool(int(mask, 16) >> (signal.SIGUSR1 - 1) & 1)


def campar_processes(root: int) -> list[int]:
    """``root`` and its descendants that run campar: a run's ranks (mpirun's proxies start
    them, each in a session of its own), or the serial run itself."""
    children = _children()
    found, todo = [], [root]
    while todo:
        pid = todo.pop()
        todo += children.get(pid, [])
        try:
            argv = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
        except OSError:
            continue
        if b"mpirun" not in argv[0] and any(b"campar.cli" in arg for arg in argv):
            found.append(pid)
    return found


def wait_until_guarded(proc: subprocess.Popen, ranks: int, timeout: float = 120.0) -> float:
    """Wait until ``ranks`` campar processes of ``proc`` (itself, or its ranks) have
    installed campar's signal handlers (or ``proc`` ended); returns the seconds waited.
    What a test that signals a run at start-up waits for, however slow the machine:
    before it, Python's own start-up handles the signal (docs/stores.md)."""
    start = time.monotonic()
    while time.monotonic() - start < timeout and proc.poll() is None:
        pids = campar_processes(proc.pid)
        if len(pids) >= ranks and all(guarded(pid) for pid in pids):
            break
        time.sleep(0.002)
    return time.monotonic() - start


def assert_mpirun_store_equals(job_data: dict, tmp_path: Path, serial: Path) -> None:
    """``mpirun -n 2 campar run`` of ``job_data`` into a store beside ``serial`` (same
    suffix) ran on two ranks and equals ``serial`` bit for bit."""
    from campar.sweep.store import read_store

    parallel = tmp_path / f"mpi{serial.suffix}"
    job_file = tmp_path / f"mpi{serial.suffix}.json"
    job_file.write_text(json.dumps({**job_data, "store": str(parallel)}))
    result = run_campar_mpi(2, "run", job_file)
    assert result.returncode == 0, result.stderr
    with read_store(parallel) as reader:
        assert reader.attrs["runs"][-1]["ranks"] == 2
    assert_same_store(stored(parallel), stored(serial))
