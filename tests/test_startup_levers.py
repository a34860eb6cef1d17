"""What a run's start and end skip: the backend a store does not use, the master's lane
computing before it is warm, the interpreter's teardown after a successful run."""

import json
import os
import subprocess
import sys
from collections import Counter
from pathlib import Path
from types import SimpleNamespace

import pytest

from campar.sweep import runner
from campar.sweep.store import read_store

ROOT = Path(__file__).resolve().parents[1]


class HandOutWorkers:
    """The master's view of ``size - 1`` worker ranks (``wire.Workers``): which asked for
    tiles (``ready``), were told to stop, and which tiles each was given."""

    def __init__(self, size: int, ready=()):
        self.comm = SimpleNamespace(Get_size=lambda: size)
        self.ready, self.stopped = list(ready), set()
        self.held: dict[int, list[int]] = {rank: [] for rank in range(1, size)}
        self.writing = Counter()

    def open_ranks(self):
        return [rank for rank in self.ready if rank not in self.stopped]

    def holding(self, rank):
        return len(self.held[rank])

    def room(self, rank, depth):
        return self.holding(rank) < depth

    def assign(self, rank, tile):
        self.held[rank].append(tile.index)

    def stop(self, rank):
        self.stopped.add(rank)


def master_of(job, n_tiles: int, warm: bool, workers: HandOutWorkers) -> runner.Master:
    """A master of ``n_tiles`` pending tiles of ``job`` whose own lane is ``warm`` or not."""
    held: list[int] = []
    lane = SimpleNamespace(held=held, warm=warm, start=lambda tile: held.append(tile.index))
    master = runner.Master(job, None, runner.plan_tiles(job)[:n_tiles], None, 1.0, lane)
    master.workers = workers
    return master


@pytest.fixture
def four_tiles(write_job):
    _, job = write_job()  # one row a tile: six tiles
    assert len(runner.plan_tiles(job)) >= 4
    return job


def test_a_cold_master_lane_leaves_the_only_tile_to_a_worker_even_one_not_yet_ready(
    four_tiles,
):
    master = master_of(four_tiles, 1, warm=False, workers=HandOutWorkers(2))
    master.hand_out()  # rank 1 has not asked yet: the tile waits for it
    assert master.local.held == [] and len(master.queue) == 1
    master.workers.ready.append(1)
    master.hand_out()
    assert master.workers.held[1] == [0] and master.local.held == []


def test_a_warm_master_lane_takes_a_tile_at_once(four_tiles):
    master = master_of(four_tiles, 1, warm=True, workers=HandOutWorkers(2))
    master.hand_out()
    assert master.local.held == [0]


def test_a_cold_master_lane_takes_tiles_once_every_worker_holds_one(four_tiles):
    master = master_of(four_tiles, 3, warm=False, workers=HandOutWorkers(3, ready=[1, 2]))
    master.hand_out()
    assert master.workers.held == {1: [0], 2: [1]} and master.local.held == [2]


def test_a_cold_master_lane_takes_a_tile_that_failed_on_the_only_free_worker(four_tiles):
    master = master_of(four_tiles, 1, warm=False, workers=HandOutWorkers(2, ready=[1]))
    master.failed_on[0] = [1]
    master.hand_out()
    assert master.local.held == [0] and master.workers.held[1] == []


def test_a_serial_lane_takes_its_tiles_as_before(four_tiles):
    held: list[int] = []
    lane = SimpleNamespace(held=held, warm=True, start=lambda tile: held.append(tile.index))
    master = runner.Master(four_tiles, None, runner.plan_tiles(four_tiles), None, 1.0, lane)
    master.hand_out()
    assert held == [0, 1]  # its tile and the next (TILES_HELD)


# A fresh process that creates a store of each backend and writes every tile of its job,
# then says which backend libraries it imported.
CREATE_AND_WRITE = """
import json, sys
import numpy as np
from campar.sweep.arrays import array_names, array_spec
from campar.sweep.job import Job
from campar.sweep.plan import plan_tiles
from campar.sweep.store import open_store
job = Job.from_dict(json.loads(sys.argv[2]))
with open_store(sys.argv[1], job) as store:
    for tile in plan_tiles(job):
        shapes = {name: array_spec(job, name) for name in array_names(job)}
        store.write_tile(tile, {
            name: np.zeros((tile.n_rows, job.shape[1], *tail), dtype)
            for name, (dtype, tail) in shapes.items()
        })
    store.log_run({"tiles": len(plan_tiles(job))})
print(json.dumps({name: name in sys.modules for name in ("zarr", "h5py")}))
"""


@pytest.mark.process
@pytest.mark.parametrize("suffix, imported", [(".zarr", set()), (".h5", {"h5py"})])
def test_a_run_loads_no_backend_library_it_does_not_write_with(
    write_job, tmp_path, suffix, imported
):
    """A run of a Zarr store writes it without zarr (its documents and chunks are campar's
    own, byte for byte zarr's); an HDF5 store loads h5py and never zarr."""
    _, job = write_job()
    store = tmp_path / f"only{suffix}"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run(
        [sys.executable, "-c", CREATE_AND_WRITE, str(store), json.dumps(job.to_dict())],
        capture_output=True,
        text=True,
        env=env,
    )
    assert done.returncode == 0, done.stderr
    found = json.loads(done.stdout.splitlines()[-1])
    assert {name for name, loaded in found.items() if loaded} == imported
    with read_store(store) as reader:
        assert reader.done.all()


def run_command(job_path: Path, store: Path, ranks: int = 1) -> subprocess.CompletedProcess:
    launcher = [] if ranks == 1 else [str(Path(sys.executable).parent / "mpirun"), "-n", "2"]
    command = [*launcher, sys.executable, "-m", "campar.cli", "run", str(job_path)]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [*command, "--store", str(store)], capture_output=True, text=True, env=env
    )


def check_left_whole(done: subprocess.CompletedProcess, store: Path) -> None:
    """The run ended 0 with its last log line written, and its store verifies as complete
    (every tile committed and intact), read by a separate process."""
    from campar.cli import main

    assert done.returncode == 0, done.stderr
    assert f"{store}: complete" in done.stderr.splitlines()[-1]
    assert main(["verify", str(store)]) == 0


@pytest.mark.process
@pytest.mark.parametrize("suffix", [".zarr", ".h5"])
def test_a_run_that_leaves_at_once_leaves_its_store_whole(
    write_job, tmp_path, warm_numba_cache, suffix
):
    job_path, _ = write_job()
    store = tmp_path / f"left{suffix}"
    check_left_whole(run_command(job_path, store), store)


@pytest.mark.process
@pytest.mark.mpi
def test_a_two_rank_run_ends_through_the_interpreter_and_leaves_its_store_whole(
    write_job, tmp_path, warm_numba_cache
):
    job_path, _ = write_job()
    store = tmp_path / "left2.zarr"
    done = run_command(job_path, store, ranks=2)
    check_left_whole(done, store)
    with read_store(store) as reader:
        assert reader.attrs["runs"][-1]["ranks"] == 2


def test_a_command_from_python_returns_rather_than_leaving(write_job, tmp_path, capsys):
    """``main`` with an argument list (a library caller, a test) returns its code: only the
    program (``argv`` None) leaves without the interpreter's teardown."""
    from campar.cli import main

    job_path, _ = write_job()
    store = tmp_path / "inproc.zarr"
    assert main(["run", str(job_path), "--store", str(store)]) == 0
    assert main(["verify", str(store)]) == 0


@pytest.mark.parametrize("dont_write", [True, False])
def test_the_startup_bench_launches_with_bytecode_caches(monkeypatch, tmp_path, dont_write):
    from campar.bench.startup import launch_environment

    monkeypatch.delenv("PYTHONPYCACHEPREFIX", raising=False)
    if dont_write:
        monkeypatch.setenv("PYTHONDONTWRITEBYTECODE", "1")
    else:
        monkeypatch.delenv("PYTHONDONTWRITEBYTECODE", raising=False)
    env = launch_environment(tmp_path)
    assert "PYTHONDONTWRITEBYTECODE" not in env
    assert env.get("PYTHONPYCACHEPREFIX") == (str(tmp_path / "pycache") if dont_write else None)


def test_a_profiled_or_traced_program_keeps_the_interpreters_exit():
    """cProfile and coverage write what they gathered at the interpreter's exit: under
    either the program exits as Python does (``observed``), not with ``os._exit``."""
    from campar.cli import observed

    saved_trace, saved_profile = sys.gettrace(), sys.getprofile()
    try:
        sys.settrace(None)
        sys.setprofile(None)
        assert not observed()
        sys.setprofile(lambda *args: None)
        assert observed()
        sys.setprofile(None)
        sys.settrace(lambda *args: None)
        assert observed()
    finally:
        sys.settrace(saved_trace)
        sys.setprofile(saved_profile)
