"""What the ranks of a run wait for at its start and end: rank 0 decides the tile rows
without importing the store's backend (a new store's run imports it only to create it),
and a job of no more tiles than workers is written by the master (no worker imports the
backend after its tile)."""

import subprocess
import sys
import textwrap

import numpy as np
import pytest
from support.jobs import assert_same_map
from support.processes import CAMPAR, MPIRUN, subprocess_env, tree_env

import campar.sweep.runner as runner
from campar.sweep.store import read_store


@pytest.mark.parametrize("name", ["map.zarr", "map", "map.h5", "map.HDF5"])
def test_whether_workers_write_is_known_before_the_backend_is_imported(tmp_path, name):
    """What rank 0 decides the tile rows with (before the workers load the kernel) is what
    the backend's store says once opened."""
    from campar.sweep import store

    path = tmp_path / name
    assert store.takes_direct_writes(path) is store._STORES[store._backend(path)].direct_writes


@pytest.mark.process
def test_asking_for_a_missing_store_imports_no_backend(tmp_path):
    """A run asks for its store before it opens it (to resume a layout): a new store's
    run imports its backend only to create it."""
    code = textwrap.dedent(
        f"""
        import sys
        from campar.errors import StoreError
        from campar.sweep.store import read_store
        for name in ("new.zarr", "new.h5"):
            try:
                read_store({str(tmp_path)!r} + "/" + name)
            except StoreError:
                pass
        print(sorted(m for m in ("zarr", "h5py") if m in sys.modules))
        """
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=tree_env()
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split()[-1] == "[]"


@pytest.mark.parametrize(
    ("pending", "ranks", "workers_write"),
    [(1, 2, False), (2, 3, False), (2, 2, True), (6, 3, True), (0, 2, False)],
)
def test_workers_write_their_tiles_only_where_there_are_more_than_workers(
    write_job, pending, ranks, workers_write
):
    """A job of no more pending tiles than workers: each computes about one, and the master
    writes them for less than each worker's import of the store's backend."""
    from types import SimpleNamespace

    _, job = write_job()  # six tiles
    done = np.arange(6) >= pending
    store = SimpleNamespace(done=done)
    comm = SimpleNamespace(Get_size=lambda: ranks)
    assert runner.workers_write_tiles(job, store, comm) is workers_write
    assert runner.workers_write_tiles(job, store, None) is True  # serial: no workers


@pytest.mark.process
@pytest.mark.mpi
@pytest.mark.skipif(not MPIRUN.exists(), reason=f"no mpirun at {MPIRUN}")
def test_a_job_of_one_tile_on_two_ranks_is_written_by_the_master(write_job):
    path, job = write_job(tiles={"rows": 6})  # one tile
    done = subprocess.run(
        [str(MPIRUN), "-n", "2", *CAMPAR, "run", str(path)],
        capture_output=True,
        text=True,
        timeout=300,
        env=subprocess_env(),
    )
    assert done.returncode == 0, done.stderr
    with read_store(job.store) as reader:
        assert_same_map(reader, job)
        entry = reader.attrs["runs"][-1]
    assert entry["writer"] == "master" and entry["tiles_per_rank"] == [0, 1]
