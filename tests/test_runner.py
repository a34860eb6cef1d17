"""The serial runner: results equal run_tile's, signals, kills, resume, refusals, status."""

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from support.cli import call_campar
from support.jobs import assert_same_map, reference_arrays
from support.processes import kill_tree, start_campar, wait_for_tiles

import campar.sweep.runner as runner
import campar.sweep.wire as wire
from campar.errors import CamparError, Interrupted
from campar.sweep.arrays import array_names
from campar.sweep.plan import plan_tiles
from campar.sweep.progress import Progress, format_duration
from campar.sweep.store import cell_arrays, read_store
from campar.sweep.tile import run_tile


def tiles_done(path) -> list[bool]:
    with read_store(path) as reader:
        return reader.done.tolist()


def outcomes(path) -> list[str]:
    with read_store(path) as reader:
        return [run["outcome"] for run in reader.attrs["runs"]]


# -- in-process ---------------------------------------------------------------------


def test_pack_and_unpack_round_trip_a_tile(write_job):
    _, job = write_job(outputs=["label", "dc", "sections"])
    tile = plan_tiles(job)[3]
    rng = np.random.default_rng(0)
    arrays = {}
    schemas = cell_arrays(job)
    for name, dtype, shape in wire.tile_layout(schemas, tile):
        arrays[name] = (rng.normal(size=shape) * 100).astype(dtype)
    buf = wire.pack([3, 42], [arrays[n] for n in array_names(job)])
    assert buf.dtype == np.uint8 and buf[:16].view(np.int64).tolist() == [3, 42]
    back = wire.unpack(schemas, tile, buf[16:])
    for name, values in arrays.items():
        assert back[name].dtype == values.dtype
        np.testing.assert_array_equal(back[name], values)
    with pytest.raises(CamparError, match="bytes received"):
        wire.unpack(schemas, tile, buf[17:])


def test_serial_run_equals_tiles_computed_directly(write_job):
    _, job = write_job()
    summary = runner.run_job(job)
    assert summary.outcome == "complete"
    with read_store(job.store) as reader:
        assert_same_map(reader, job)
        (entry,) = reader.attrs["runs"]
    assert entry["tiles"] == 6 and entry["cells"] == 72 and entry["ranks"] == 1
    assert entry["host"] == socket.gethostname() and entry["outcome"] == "complete"
    assert entry["cells_per_s"] > 0 and 0 < entry["compute_seconds"] <= entry["seconds"] * 1.05
    # A second run finds nothing to do and logs nothing.
    assert runner.run_job(job).outcome == "nothing to do"
    assert outcomes(job.store) == ["complete"]


@pytest.mark.parametrize("load_fails", [False, True])
def test_a_preloading_lane_computes_tiles_as_run_tile_does(write_job, monkeypatch, load_fails):
    """A worker's lane loads the kernel first (runner.run_job); if that fails, its tiles
    still run (and would report the error themselves)."""
    _, job = write_job()
    loaded = []

    def load(j, share):
        loaded.append((j.name, share))
        if load_fails:
            raise RuntimeError("no kernel")

    monkeypatch.setattr(runner, "load_kernel", load)
    lane = runner.ThreadLane(job, "rank 1 on here", preload=True, share=(1, 2))
    tile = plan_tiles(job)[2]
    lane.start(tile)
    out = lane.poll(timeout=60.0)
    lane.close()
    # the share of a cold compile is handed on (split_compile.share_with_ranks)
    assert loaded == [(job.name, (1, 2))] and out is not None and out.error is None
    want = run_tile(job, tile)
    for name in array_names(job):
        np.testing.assert_array_equal(out.arrays[name], want[name])


def test_a_job_without_store_is_a_job_error_and_creates_nothing(write_job, tmp_path):
    _, job = write_job(store=None)
    before = sorted(tmp_path.iterdir())
    with pytest.raises(CamparError, match="--store") as err:
        runner.run_job(job)
    assert err.value.exit_code == 2
    assert sorted(tmp_path.iterdir()) == before


def signal_during(
    monkeypatch,
    index,
    *,
    sleep=0.0,
    again_after=None,
    signum=signal.SIGTERM,
    after=0.0,
    hold: threading.Event | None = None,
):
    """Make run_tile signal this process while computing tile ``index``, ``after`` s in,
    then sleep ``sleep`` s, or with ``hold``, wait until the test sets it (a tile that
    never ends by itself)."""

    def tile_with_signal(job, tile):
        if tile.index == index:
            time.sleep(after)
            os.kill(os.getpid(), signum)
            if again_after is not None:
                time.sleep(again_after)
                os.kill(os.getpid(), signum)
            if hold is not None:
                hold.wait()
            time.sleep(sleep)
        return run_tile(job, tile)

    monkeypatch.setattr(runner, "run_tile", tile_with_signal)


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT, signal.SIGUSR1])
def test_a_signal_collects_the_tile_in_flight_then_interrupts(write_job, monkeypatch, signum):
    _, job = write_job()
    signal_during(monkeypatch, 1, signum=signum, sleep=0.2)  # its handler runs meanwhile
    handler = signal.getsignal(signum)
    with pytest.raises(Interrupted, match=f"stopped by {signum.name} .* resume") as err:
        runner.run_job(job)
    assert err.value.exit_code == 75
    assert signal.getsignal(signum) is handler  # restored
    assert tiles_done(job.store) == [True, True, False, False, False, False]
    assert outcomes(job.store) == ["interrupted"]
    monkeypatch.setattr(runner, "run_tile", run_tile)
    assert runner.run_job(job).outcome == "complete"
    with read_store(job.store) as reader:
        assert_same_map(reader, job)
    assert outcomes(job.store) == ["interrupted", "complete"]


def test_a_signal_takes_back_the_tile_queued_on_the_lane(write_job, monkeypatch):
    """The lane holds tile 2 behind tile 1 (TILES_HELD) when the signal comes: only the
    started tile is collected."""
    _, job = write_job()
    signal_during(monkeypatch, 1, after=0.5, sleep=0.5)
    with pytest.raises(Interrupted):
        runner.run_job(job)
    assert tiles_done(job.store) == [True, True, False, False, False, False]


# The tile in flight below never ends until the test lets it: the run returns only by
# abandoning it, whatever the machine's speed (a run that waits for it hangs, and the
# test's timeout fails it).


def test_a_second_signal_abandons_the_tile_in_flight(write_job, monkeypatch):
    _, job = write_job()
    release = threading.Event()
    signal_during(monkeypatch, 2, again_after=1.3, hold=release)
    try:
        with pytest.raises(Interrupted):
            runner.run_job(job, grace=3600)  # only the second signal ends the wait
    finally:
        release.set()
    assert tiles_done(job.store) == [True, True, False, False, False, False]


def test_the_grace_period_bounds_the_wait_for_tiles_in_flight(write_job, monkeypatch):
    _, job = write_job()
    release = threading.Event()
    signal_during(monkeypatch, 0, hold=release)
    try:
        with pytest.raises(Interrupted):
            runner.run_job(job, grace=0.5)
    finally:
        release.set()
    assert not any(tiles_done(job.store))


def failing(monkeypatch, index, times):
    calls = {"n": 0}

    def tile_that_fails(job, tile):
        if tile.index == index and calls["n"] < times:
            calls["n"] += 1
            raise ZeroDivisionError("injected")
        return run_tile(job, tile)

    monkeypatch.setattr(runner, "run_tile", tile_that_fails)


def test_a_tile_that_fails_once_is_retried(write_job, monkeypatch, caplog):
    _, job = write_job()
    failing(monkeypatch, 3, times=1)
    assert runner.run_job(job).outcome == "complete"
    assert "tile 3 failed" in caplog.text and "ZeroDivisionError" in caplog.text
    with read_store(job.store) as reader:
        assert_same_map(reader, job)


def test_a_tile_that_keeps_failing_ends_the_run_with_where_and_why(write_job, monkeypatch):
    _, job = write_job()
    failing(monkeypatch, 2, times=99)
    with pytest.raises(CamparError) as err:
        runner.run_job(job)
    message = str(err.value)
    assert "tile 2 failed 2×" in message
    assert f"rank 0 on {socket.gethostname()}" in message and "ZeroDivisionError" in message
    # The lane held tile 3 behind tile 2 (TILES_HELD): it ran while 2 waited for its retry.
    # Tile 4, queued behind the retry, runs if the lane started it before the master saw
    # the second failure, else it is taken back; tile 5 is never handed out.
    done = tiles_done(job.store)
    assert done[:4] == [True, True, False, True] and not done[5], done
    assert outcomes(job.store) == ["failed"]


def test_progress_line_counts_rate_and_eta():
    class Tty:
        text = ""

        def isatty(self):
            return True

        def write(self, s):
            self.text += s

        def flush(self):
            pass

    out = Tty()
    progress = Progress(10, 1000, 2, 200, stream=out)
    progress.start -= 10.0  # started ten seconds ago, last drawn then too
    progress.last -= 10.0
    progress.tile_done(100)
    assert out.text.startswith("\rtiles 3/10  cells 300/1000  10.0 cells/s  ETA 1m10s")
    assert progress.rate == pytest.approx(10.0, rel=0.01)
    progress.tile_done(100)  # within REDRAW_SECONDS: not drawn again
    assert out.text.count("tiles") == 1
    assert format_duration(70) == "1m10s" and format_duration(7300) == "2h01m"


# -- the command line, in subprocesses --------------------------------------------------


def test_run_then_status_reports_tiles_cells_and_runs(capsys, write_job):
    path, job = write_job()
    done = call_campar(capsys, "run", path)
    assert done.returncode == 0, done.stderr
    status = call_campar(capsys, "status", job.store)
    assert status.returncode == 0, status.stderr
    assert "tiles   6/6 done" in status.stdout
    assert "cells   72/72 done, 0 failed" in status.stdout
    assert "runs    1 (complete last)" in status.stdout
    reference = reference_arrays(job)
    periodic = int((reference["kind"] == 0).sum())
    assert f"periodic {periodic}" in status.stdout


def test_status_of_a_missing_store_exits_3(capsys, tmp_path):
    result = call_campar(capsys, "status", tmp_path / "none.zarr")
    assert result.returncode == 3 and "no store" in result.stderr


@pytest.mark.slow  # ~4 s each; the store suite kills writers quickly, per backend
@pytest.mark.parametrize("suffix", [".zarr", ".h5"])
@pytest.mark.process
def test_sigkill_mid_run_then_resume_gives_the_same_map(
    write_job, tmp_path, suffix, capsys, caplog
):
    path, job = write_job(slow=True, store=str(tmp_path / f"slow{suffix}"))
    proc = start_campar("run", path)
    wait_for_tiles(job.store, 2, proc)
    kill_tree(proc.pid)
    proc.communicate(timeout=60)
    done = tiles_done(job.store)
    assert 2 <= sum(done) < 6, done
    resumed = call_campar(capsys, "run", path)  # the resume: no process boundary under test
    assert resumed.returncode == 0, resumed.stderr
    assert "stale lock" in caplog.text
    with read_store(job.store) as reader:
        assert_same_map(reader, job)
        assert reader.attrs["runs"][-1]["tiles"] == 6 - sum(done)


@pytest.mark.process
def test_sigterm_exits_75_and_the_same_command_resumes(write_job, capsys):
    path, job = write_job(slow=True)
    proc = start_campar("run", path)
    wait_for_tiles(job.store, 1, proc)
    proc.send_signal(signal.SIGTERM)
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 75, stderr
    assert "SIGTERM" in stderr and "run the same command again" in stderr
    assert 1 <= sum(tiles_done(job.store)) < 6
    resumed = call_campar(capsys, "run", path)  # the resume: no process boundary under test
    assert resumed.returncode == 0, resumed.stderr
    with read_store(job.store) as reader:
        assert_same_map(reader, job)
    assert outcomes(job.store) == ["interrupted", "complete"]


@pytest.mark.slow  # ~4 s; the store suite checks the lock of another process in 0.5 s
@pytest.mark.process
def test_a_concurrent_run_is_refused_with_host_and_pid(write_job, capsys):
    # 24 tiles: the first run is still busy when the second has started (with 6 it once
    # finished them all first, on a loaded machine); SIGTERM ends it either way. The
    # second run is this process's: the refusal is the lock's, no process boundary.
    path, job = write_job(slow=True, sweep={"mu_cn": {"points": 24}})
    first = start_campar("run", path)
    try:
        wait_for_tiles(job.store, 1, first)
        second = call_campar(capsys, "run", path)
        assert second.returncode == 3
        assert f"pid {first.pid} on host {socket.gethostname()}" in second.stderr
    finally:
        first.send_signal(signal.SIGTERM)
        first.communicate(timeout=60)


def test_a_store_of_another_job_is_refused_untouched_unless_overwrite(capsys, write_job):
    path, job = write_job()
    assert call_campar(capsys, "run", path).returncode == 0
    with read_store(job.store) as reader:
        before = reader.read("n").copy()
    changed, _ = write_job(integrator={"rtol": 1e-9}, store=job.store)
    refused = call_campar(capsys, "run", changed)
    assert refused.returncode == 3
    assert "integrator.rtol: 1e-07 in the store, 1e-09 in the job" in refused.stderr
    with read_store(job.store) as reader:
        np.testing.assert_array_equal(reader.read("n"), before)
        assert reader.attrs["job"]["integrator"]["rtol"] == 1e-7
    replaced = call_campar(capsys, "run", changed, "--overwrite")
    assert replaced.returncode == 0, replaced.stderr
    with read_store(job.store) as reader:
        assert reader.attrs["job"]["integrator"]["rtol"] == 1e-9


@pytest.mark.slow  # six runs killed at random moments, ~5 s per backend
@pytest.mark.parametrize("suffix", [".zarr", ".h5"])
@pytest.mark.process
def test_repeated_sigkills_at_random_moments_then_resume_give_the_same_map(
    write_job, tmp_path, suffix
):
    """Kill -9 at seeded random moments (HDF5 checkpointing after every tile, so kills
    also land inside checkpoints) until a run completes; the map is still exact."""
    path, job = write_job(slow=True, store=str(tmp_path / f"killed{suffix}"))
    script = (
        "import sys, campar.sweep.store._hdf5 as h5; h5.CHECKPOINT_TILES = 1\n"
        f"from campar.cli import main; sys.exit(main(['run', {str(path)!r}]))"
    )
    rng = np.random.default_rng(3)
    for _ in range(6):
        done = sum(tiles_done(job.store)) if Path(job.store).exists() else 0
        proc = subprocess.Popen([sys.executable, "-c", script], stderr=subprocess.PIPE, text=True)
        if done + 2 < 6:  # else let it finish
            wait_for_tiles(job.store, done + 2, proc)
            time.sleep(rng.uniform(0.0, 0.5))  # somewhere in the next tile or checkpoint
            proc.kill()
        _, stderr = proc.communicate(timeout=300)
        if proc.returncode == 0:
            break
        assert proc.returncode == -signal.SIGKILL, stderr
    else:
        pytest.fail("six runs did not complete the map")
    with read_store(job.store) as reader:
        assert_same_map(reader, job)
        runs = reader.attrs["runs"]
    assert runs[-1]["outcome"] == "complete"  # killed runs log nothing


def test_an_idle_master_does_not_spin(write_job, monkeypatch):
    """While its only lane sleeps in a tile, the master polls with a 1 ms backoff."""
    _, job = write_job()
    first = run_tile(job, plan_tiles(job)[0])  # kernel loaded before the clock starts

    def sleepy(job, tile):  # every tile is one chain: the same shapes
        time.sleep(0.4)
        return {name: a.copy() for name, a in first.items()}

    monkeypatch.setattr(runner, "run_tile", sleepy)
    wall, cpu = time.perf_counter(), time.process_time()
    runner.run_job(job)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    assert wall > 2.4
    assert cpu < 0.25 * wall, (cpu, wall)


class StubWorkers:
    """The master's view of two worker ranks (``wire.Workers``), set by hand."""

    def __init__(self, held: dict[int, int], writing: dict[int, int], shortest: float):
        from collections import Counter
        from types import SimpleNamespace

        self.comm = SimpleNamespace(Get_size=lambda: 3)
        self.held, self.writing, self.shortest_tile = held, Counter(writing), shortest

    def open_ranks(self):
        return list(self.held)

    def holding(self, rank):
        return self.held[rank]


@pytest.mark.parametrize(
    "local, held, writing, stopped, patient",
    [
        (2, {1: 2, 2: 2}, {}, False, True),  # every lane holds its next tile
        (1, {1: 2, 2: 2}, {}, False, False),  # the master's own lane wants one
        (2, {1: 2, 2: 1}, {}, False, False),  # rank 2 wants one
        (2, {1: 2, 2: 2}, {2: 1}, False, False),  # rank 2's WRITTEN is due, a tile with it
        (2, {1: 2}, {}, False, False),  # rank 2 has not asked yet (or was stopped)
        (2, {1: 2, 2: 2}, {}, True, False),  # a stop: answers to WITHDRAW are due
    ],
)
def test_the_master_waits_long_only_while_every_lane_is_provided_for(
    write_job, local, held, writing, stopped, patient
):
    """Between probes the master waits up to a quarter of the shortest tile (≤ 20 ms) only
    while no lane can need it soon; else it probes within ``BACKOFF_SECONDS``."""
    from types import SimpleNamespace

    _, job = write_job()
    lane = SimpleNamespace(held=list(range(local)), withdraw=lambda: [], shortest_tile=0.2)
    master = runner.Master(job, None, [], None, 1.0, lane)
    master.workers = StubWorkers(held, writing, shortest=0.04)
    if stopped:
        master.stop_reason = "SIGTERM"
    assert master.provided_for is patient
    # the local lane's 0.2 s: the workers' 0.04 s is shorter
    assert master.patient_wait() == pytest.approx(0.01)
    master.workers.shortest_tile = 1.0
    assert master.patient_wait() == runner.PATIENT_WAIT_SECONDS == 0.02
    lane.shortest_tile = master.workers.shortest_tile = float("inf")  # none back yet
    assert master.patient_wait() == wire.BACKOFF_SECONDS


def test_a_worker_writes_into_the_store_only_where_it_sees_the_masters_lock(tmp_path):
    """``seen_store``: the lock file at the store's path must hold the master's text (the
    same file system); else the worker sends its tiles to the master to write."""
    from campar.sweep.store import lock_path
    from campar.sweep.wire import seen_store

    store = tmp_path / "s.zarr"
    store.mkdir()
    lock_path(store).write_text('{"host": "h", "pid": 1}')
    assert seen_store(f'{store}\n{{"host": "h", "pid": 1}}') == str(store)
    assert seen_store(f'{store}\n{{"host": "other", "pid": 2}}') == ""  # another run's lock
    assert seen_store(f'{tmp_path / "absent.zarr"}\n{{"host": "h", "pid": 1}}') == ""
    assert seen_store("") == ""


def test_closing_a_lane_waits_for_its_kernel_load_and_abandons_its_tile(monkeypatch):
    """A lane closed while it loads the kernel returns once the load is over (a process that
    ends with a thread inside llvmlite can crash: a segmentation fault under mpirun when a
    Ctrl-C stopped a run during a rank's load); one closed during a tile returns at once,
    the tile abandoned."""
    from support.jobs import SMALL_JOB

    from campar.sweep.job import Job

    job = Job.from_dict({**SMALL_JOB, "store": None})
    loaded, started, release = threading.Event(), threading.Event(), threading.Event()

    def slow_load(job, share):
        time.sleep(0.3)
        loaded.set()

    def slow_tile(job, tile):
        started.set()
        release.wait(10)
        return {}

    monkeypatch.setattr(runner, "load_kernel", slow_load)
    monkeypatch.setattr(runner, "run_tile", slow_tile)
    lane = runner.ThreadLane(job, "test", preload=True)
    lane.close()
    assert loaded.is_set()
    lane = runner.ThreadLane(job, "test")
    lane.start(plan_tiles(job)[0])
    assert started.wait(10)
    begun = time.monotonic()
    lane.close()
    assert time.monotonic() - begun < 0.2
    release.set()
