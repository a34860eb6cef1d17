"""Shared fixtures: small job files, serial reference maps, the campar and mpirun commands,
the shared reference cells."""

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

TESTS = Path(__file__).resolve().parent
# Tests compile campar's integrator with fields of their own (test_integrator), and numba
# indexes those signatures by the test module's name: a process that later reads such an
# index must be able to import the module (else ModuleNotFoundError, measured), and the
# package's own cache, which every campar run reads, must not hold them. So the session
# caches into a directory of its own (before numba is imported), and its children find
# the test modules.
os.environ.setdefault("NUMBA_CACHE_DIR", str(TESTS.parent / ".numba-test-cache"))
os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [str(TESTS), os.environ.get("PYTHONPATH")]))

from campar.sweep.job import Job  # noqa: E402 (after the cache is chosen)
from campar.sweep.plan import plan_tiles  # noqa: E402
from campar.sweep.tile import run_tile  # noqa: E402

CAMPAR = [sys.executable, "-m", "campar.cli"]
MPIRUN = Path(sys.executable).parent / "mpirun"

# Cells computed with SciPy DOP853 at rtol 1e-10 outside campar (../shared in the
# workplace; the copy in tests/data in a checkout outside it).
REFERENCE_CASES = Path(__file__).resolve().parents[2] / "shared" / "reference_cases.json"
if not REFERENCE_CASES.exists():
    REFERENCE_CASES = Path(__file__).resolve().parent / "data" / "reference_cases.json"


def reference_case(case_id: int) -> dict:
    """The shared reference cell with this id (its parameters, start and expected result)."""
    (case,) = [c for c in json.loads(REFERENCE_CASES.read_text())["cases"] if c["id"] == case_id]
    return case


def case_arguments(case: dict) -> list[str]:
    """`campar point` options that set every parameter and the start of a reference cell."""
    return [
        "--omega",
        str(case["omega"]),
        "--f0",
        str(case["f0"]),
        "--mu-kn",
        str(case["mu_kn"]),
        "--mu-cn",
        str(case["mu_cn"]),
        "--zeta",
        str(case["zeta"]),
        "--tensile",
        "clamp" if case["clamp"] else "allow",
        "--y0",
        str(case["initial_state"]["y"]),
        "--v0",
        str(case["initial_state"]["yd"]),
    ]


# 6 × 12 cells, one chain a tile; "slow" fixes a long transient so a tile takes
# a noticeable fraction of a second (time to signal or kill a run mid-way).
SMALL_JOB = {
    "name": "small",
    "sweep": {
        "omega": {"from": 6.0, "to": 1.0, "points": 12},
        "mu_cn": {"from": 0.9, "to": 0.6, "points": 6},
    },
    "classify": {"window_revolutions": 16},
    "tiles": {"rows": 1},
}
SLOW = {"transient": {"mode": "fixed", "max_revolutions": 1500}}


def merge(base: dict, extra: dict) -> dict:
    out = dict(base)
    for key, value in extra.items():
        out[key] = merge(out[key], value) if isinstance(value, dict) and key in out else value
    return out


@pytest.fixture
def write_job(tmp_path):
    """write_job(name="x", store=..., **sections) -> (path of a YAML job file, Job)."""

    def write(name="small", slow=False, **extra):
        data = merge(SMALL_JOB, SLOW) if slow else dict(SMALL_JOB)
        data = merge(data, {"name": name, **extra})
        data.setdefault("store", str(tmp_path / f"{name}.zarr"))
        path = tmp_path / f"{name}.yaml"
        path.write_text(yaml.safe_dump(data, sort_keys=False))
        return path, Job.from_dict(data)

    return write


_REFERENCES = {}


def short_curves(patch: pytest.MonkeyPatch, points: int = 40) -> None:
    """Continued curves of at most ``points`` points: a tiny gallery or report runs
    ``campar curves`` beside every map it draws, and the curves' points, not the map's
    cells, set its cost."""
    from functools import partial

    from campar.views import map_curves

    patch.setattr(map_curves, "curves_job", partial(map_curves.curves_job, points=points))


def reference_arrays(job: Job) -> dict[str, np.ndarray]:
    """The whole map computed tile by tile in this process, without runner or store."""
    key = job.digest()
    if key not in _REFERENCES:
        tiles = [run_tile(job, tile) for tile in plan_tiles(job)]
        _REFERENCES[key] = {name: np.concatenate([t[name] for t in tiles]) for name in tiles[0]}
    return _REFERENCES[key]


def assert_same_map(reader, job: Job) -> None:
    """Every array of a finished store equals the serial reference, bit for bit."""
    reference = reference_arrays(job)
    assert reader.done.all()
    assert sorted(reader.names) == sorted(reference)
    for name, expected in reference.items():
        got = reader.read(name)
        assert got.dtype == expected.dtype, name
        assert np.array_equal(got, expected, equal_nan=True), name


def run_campar(*args, timeout=300, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run(
        [*CAMPAR, *map(str, args)], capture_output=True, text=True, timeout=timeout, **kwargs
    )


def subprocess_env() -> dict:
    # Unbuffered, so a test can read a child's progress while it runs.
    return {**os.environ, "PYTHONUNBUFFERED": "1"}


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


def kill_tree(pid: int) -> None:
    """SIGKILL a process and all its descendants, as a node failure would. (hydra starts
    each rank in a session of its own, so killing mpirun's process group misses them.)"""
    children = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rpartition(")")[2].split()
        except OSError:
            continue
        children.setdefault(int(fields[1]), []).append(int(stat.parent.name))
    doomed, todo = [], [pid]
    while todo:
        doomed.append(todo.pop())
        todo += children.get(doomed[-1], [])
    for victim in reversed(doomed):  # the ranks first, so none outlives its launcher
        with contextlib.suppress(ProcessLookupError):
            os.kill(victim, signal.SIGKILL)


def stored(path) -> dict[str, np.ndarray]:
    """Every per-cell array of a store, its checksums and done flags."""
    from campar.sweep.store import read_store

    with read_store(path) as reader:
        out = {name: reader.read(name) for name in reader.names}
        out["checksum"], _ = reader.tile_checksums()
        out["done"] = reader.done
    return out


def assert_same_store(a: dict, b: dict) -> None:
    """Two ``stored`` stores hold the same arrays, bit for bit."""
    assert sorted(a) == sorted(b)
    for name in a:
        assert a[name].dtype == b[name].dtype, name
        assert np.array_equal(a[name], b[name], equal_nan=True), name


def assert_mpirun_store_equals(job_data: dict, tmp_path: Path, serial: Path) -> None:
    """``mpirun -n 2 campar run`` of ``job_data`` into a store beside ``serial`` (same
    suffix) ran on two ranks and equals ``serial`` bit for bit."""
    from campar.sweep.store import read_store

    parallel = tmp_path / f"mpi{serial.suffix}"
    job_file = tmp_path / f"mpi{serial.suffix}.json"
    job_file.write_text(json.dumps({**job_data, "store": str(parallel)}))
    result = subprocess.run(
        [str(MPIRUN), "-n", "2", *CAMPAR, "run", str(job_file)],
        capture_output=True,
        text=True,
        timeout=300,
        env=subprocess_env(),
    )
    assert result.returncode == 0, result.stderr
    with read_store(parallel) as reader:
        assert reader.attrs["runs"][-1]["ranks"] == 2
    assert_same_store(stored(parallel), stored(serial))


def resume_after_interrupt(monkeypatch, job, path, index: int) -> None:
    """Run ``job`` into ``path`` with SIGTERM sent while tile ``index`` computes (the run
    ends Interrupted, the tile pending), then run it again to completion. The signal
    reaches the computing thread; the main thread sees it within its wait (0.05 s), or
    later on a loaded machine: ``index`` should leave two tiles after it."""
    import signal as signals

    import campar.sweep.runner as runner
    from campar.errors import Interrupted
    from campar.sweep.tile import run_tile

    def tile_with_signal(job, tile):
        if tile.index == index:
            os.kill(os.getpid(), signals.SIGTERM)
        return run_tile(job, tile)

    monkeypatch.setattr(runner, "run_tile", tile_with_signal)
    with pytest.raises(Interrupted):
        runner.run_job(job, path)
    from campar.sweep.store import read_store

    with read_store(path) as reader:
        assert not reader.done.all()
    monkeypatch.setattr(runner, "run_tile", run_tile)
    assert runner.run_job(job, path).outcome == "complete"


def computed_store(tmp_path_factory, data: dict) -> tuple[Path, Job]:
    """A Zarr store of the job ``data`` computed in this process, and the job (for
    module-scoped fixtures: one computation shared by a module's tests)."""
    import campar.sweep.runner as runner

    job = Job.from_dict(data)
    path = tmp_path_factory.mktemp(job.name) / f"{job.name}.zarr"
    runner.run_job(job, path)
    return path, job


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
    children: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            parent = int(stat.read_text().rpartition(")")[2].split()[1])
        except (OSError, IndexError, ValueError):
            continue
        children.setdefault(parent, []).append(int(stat.parent.name))
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
