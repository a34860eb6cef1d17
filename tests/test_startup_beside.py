"""A serial run loads a cached kernel on a thread of its own while its store opens, and
compiles a cold one before any other thread starts; either way the map is the same."""

import json
import os
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest
from support.jobs import assert_same_map
from support.processes import CAMPAR, MPIRUN, subprocess_env

import campar.sweep.runner as runner
from campar.errors import StoreMismatch
from campar.sweep.store import read_store


def recording(monkeypatch, seconds: float = 0.0, fails: bool = False) -> list:
    """Record (event, thread name, time) of the runner's kernel loads and store openings;
    the load takes at least ``seconds``, then raises if ``fails``."""
    events = []
    compile_kernel, open_store = runner.compile_kernel, runner.open_store

    def load(job, share=None):
        events.append(("load", threading.current_thread().name, time.monotonic()))
        time.sleep(seconds)
        if fails:
            raise RuntimeError("no kernel here")
        compile_kernel(job, share)
        events.append(("loaded", threading.current_thread().name, time.monotonic()))

    def opening(*args, **kwargs):
        events.append(("open", threading.current_thread().name, time.monotonic()))
        return open_store(*args, **kwargs)

    monkeypatch.setattr(runner, "compile_kernel", load)
    monkeypatch.setattr(runner, "open_store", opening)
    return events


def threads_of(events, name: str) -> list[str]:
    return [thread for event, thread, _ in events if event == name]


def test_a_cached_kernel_loads_beside_the_store_and_the_map_is_the_same(write_job, monkeypatch):
    _, job = write_job()
    monkeypatch.setattr(runner, "kernel_cached", lambda job: True)
    events = recording(monkeypatch, seconds=0.3)
    assert runner.run_job(job).outcome == "complete"
    main = threading.current_thread().name
    # the store opened while the load went on, on another thread, which has ended
    assert threads_of(events, "load") == ["campar-load"] and threads_of(events, "open") == [main]
    times = {event: t for event, _, t in events}
    assert times["open"] < times["loaded"]
    assert not any(t.name == "campar-load" for t in threading.enumerate())
    with read_store(job.store) as reader:
        assert_same_map(reader, job)


def test_a_cold_kernel_is_compiled_before_the_store_opens_on_the_only_thread(
    write_job, monkeypatch
):
    """So a cold compile may still fork its helper (campar.core.split_compile)."""
    _, job = write_job()
    monkeypatch.setattr(runner, "kernel_cached", lambda job: False)
    events = recording(monkeypatch)
    assert runner.run_job(job).outcome == "complete"
    main = threading.current_thread().name
    assert [(event, thread) for event, thread, _ in events] == [
        ("load", main),
        ("loaded", main),
        ("open", main),
    ]
    with read_store(job.store) as reader:
        assert_same_map(reader, job)


def test_a_failed_load_beside_the_store_leaves_the_tiles_to_load_it(write_job, monkeypatch, capsys):
    _, job = write_job()
    monkeypatch.setattr(runner, "kernel_cached", lambda job: True)
    recording(monkeypatch, fails=True)
    assert runner.run_job(job).outcome == "complete"
    assert "Traceback" not in capsys.readouterr().err  # the thread's error is no traceback
    with read_store(job.store) as reader:
        assert_same_map(reader, job)


def test_a_refused_store_returns_once_the_load_beside_it_is_over(write_job, monkeypatch):
    _, other = write_job(name="other")
    assert runner.run_job(other).outcome == "complete"
    _, job = write_job(name="small", store=other.store, fixed={"zeta": 0.3})
    monkeypatch.setattr(runner, "kernel_cached", lambda job: True)
    events = recording(monkeypatch, seconds=0.3)
    with pytest.raises(StoreMismatch):
        runner.run_job(job)
    refused = time.monotonic()
    assert sorted(event for event, _, _ in events) == ["load", "loaded", "open"]
    times = {event: t for event, _, t in events}
    assert times["open"] < times["loaded"] <= refused
    assert not any(t.name == "campar-load" for t in threading.enumerate())
    with read_store(other.store) as reader:  # the other job's store is untouched
        assert_same_map(reader, other)


# In a fresh process: whether the cache holds the kernel, and what telling it loaded.
CACHED = textwrap.dedent(
    """
    import json
    from campar.core.kernel import chain_compiled
    from campar.core.revolution import run_revolution
    from campar.sweep.job import Job
    from campar.sweep.tile import kernel_cached
    job = Job.from_dict({
        "name": "one",
        "sweep": {"omega": {"from": 3.0, "to": 3.0, "points": 1},
                  "mu_cn": {"from": 0.8, "to": 0.8, "points": 1}},
    })
    cached = kernel_cached(job)
    loaded = len(chain_compiled.signatures) + len(run_revolution.signatures)
    print(json.dumps({"cached": cached, "loaded": loaded}))
    """
)


@pytest.mark.process
def test_kernel_cached_asks_the_index_and_loads_neither_half(tmp_path):
    """The session's cache holds the kernel (its children load it); an empty one does not.
    Telling loads neither the chain nor the revolution: the load is what runs beside."""
    found = {}
    for name, cache in (("warm", None), ("empty", tmp_path / "numba-cache")):
        env = dict(os.environ)
        if cache is not None:
            env["NUMBA_CACHE_DIR"] = str(cache)
        done = subprocess.run(
            [sys.executable, "-c", CACHED], capture_output=True, text=True, env=env
        )
        assert done.returncode == 0, done.stderr
        found[name] = json.loads(done.stdout.splitlines()[-1])
    assert found["warm"] == {"cached": True, "loaded": 0}
    assert found["empty"] == {"cached": False, "loaded": 0}


def test_kernel_cached_in_a_process_that_holds_the_kernel(write_job):
    from campar.sweep.tile import compile_kernel, kernel_cached

    _, job = write_job()
    compile_kernel(job)
    assert kernel_cached(job) is True


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
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
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
