"""The MPI runner under real mpirun (mpich's hydra, beside the venv's python).

Every map is compared with tiles computed directly in the test process, so
a wrong rank-to-tile bookkeeping, a garbled buffer or a lost tile fails.
"""

import json
import logging
import signal
import socket
import subprocess
import sys
import textwrap
import time

import pytest
import yaml
from support.cli import call_campar
from support.jobs import SLOW, SMALL_JOB, assert_same_map, merge, reference_arrays
from support.processes import (
    CAMPAR,
    MPIRUN,
    kill_tree,
    start_campar,
    subprocess_env,
    wait_for_tiles,
)

from campar.sweep.job import Job
from campar.sweep.plan import auto_tile_rows
from campar.sweep.store import read_store

pytestmark = [
    pytest.mark.mpi,
    pytest.mark.skipif(not MPIRUN.exists(), reason=f"no mpirun at {MPIRUN}"),
]
# Each test starts mpirun (2–5 s), so every one is in the `mpi` tier; those that start it
# several times or compile are `slow` too.
slow = pytest.mark.slow


def mpirun(ranks: int) -> list[str]:
    return [str(MPIRUN), "-n", str(ranks)]


def run_mpi(ranks: int, *args, timeout=300, command=CAMPAR) -> subprocess.CompletedProcess:
    """``campar ARGS`` (or ``command ARGS``) under mpirun -n RANKS."""
    return subprocess.run(
        [*mpirun(ranks), *command, *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=subprocess_env(),
    )


def last_run(store) -> dict:
    with read_store(store) as reader:
        return reader.attrs["runs"][-1]


def assert_the_ranks_computed(store, ranks: int, writer: str) -> None:
    """The run's record: every rank on this host, the 6 tiles computed among them. Of two
    ranks each computes; of more, a worker that starts after the others took every tile
    computes none (a loaded machine's third rank may), so the workers together did."""
    entry = last_run(store)
    assert entry["ranks"] == ranks and entry["outcome"] == "complete"
    assert entry["writer"] == writer
    assert entry["hosts"] == [socket.gethostname()]
    per_rank = entry["tiles_per_rank"]
    assert len(per_rank) == ranks and sum(per_rank) == 6, per_rank
    assert all(n >= 1 for n in per_rank) if ranks == 2 else sum(per_rank[1:]) >= 1, per_rank
    assert len(entry["peak_rss_mb"]) == ranks and all(0 < mb < 2000 for mb in entry["peak_rss_mb"])


@pytest.mark.process
@pytest.mark.mpi
def test_mpi_map_equals_the_serial_one_and_every_rank_computes(write_job):
    path, job = write_job(slow=True)
    proc = start_campar("run", path, launcher=mpirun(2))
    reference_arrays(job)  # the serial map, here while the ranks start and run
    _, stderr = proc.communicate(timeout=300)
    assert proc.returncode == 0, stderr
    with read_store(job.store) as reader:
        assert_same_map(reader, job)
    assert_the_ranks_computed(job.store, 2, "workers")  # Zarr: each worker writes its tiles


# The HDF5 case runs on 3 ranks: the same map from two workers and a master
@slow
@pytest.mark.parametrize(
    ("suffix", "env", "ranks"), [(".zarr", {"CAMPAR_WRITER": "master"}, 2), (".h5", {}, 3)]
)
@pytest.mark.process
@pytest.mark.mpi
def test_where_the_master_writes_every_tile_the_map_is_the_same(
    write_job, tmp_path, suffix, env, ranks
):
    path, job = write_job(slow=True, store=str(tmp_path / f"m{suffix}"))
    result = subprocess.run(
        [*mpirun(ranks), *CAMPAR, "run", str(path)],
        capture_output=True,
        text=True,
        timeout=300,
        env={**subprocess_env(), **env},
    )
    assert result.returncode == 0, result.stderr
    with read_store(job.store) as reader:
        assert_same_map(reader, job)
    assert_the_ranks_computed(job.store, ranks, "master")


@slow
@pytest.mark.process
@pytest.mark.mpi
def test_mpi_run_killed_with_sigkill_resumes_to_the_same_map(write_job):
    path, job = write_job(slow=True)
    proc = start_campar("run", path, launcher=mpirun(2))
    wait_for_tiles(job.store, 2, proc)
    kill_tree(proc.pid)  # mpirun and every rank, as a dead node would
    proc.communicate(timeout=60)
    with read_store(job.store) as reader:
        done = int(reader.done.sum())
    assert 2 <= done < 6
    resumed = run_mpi(3, "run", path)
    assert resumed.returncode == 0, resumed.stderr
    assert "stale lock" in resumed.stderr
    with read_store(job.store) as reader:
        assert_same_map(reader, job)
    assert last_run(job.store)["tiles"] == 6 - done


@slow
@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGUSR1])
@pytest.mark.process
@pytest.mark.mpi
def test_a_signal_to_mpirun_exits_75_and_a_serial_run_resumes(write_job, signum, capsys):
    path, job = write_job(slow=True)
    proc = start_campar("run", path, launcher=mpirun(2))
    wait_for_tiles(job.store, 1, proc)
    proc.send_signal(signum)  # hydra forwards it to every rank
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 75, stderr
    assert stderr.count("run the same command again") == 1  # rank 0 only
    with read_store(job.store) as reader:
        assert 1 <= int(reader.done.sum()) < 6
    resumed = call_campar(capsys, "run", path)  # in this process: no boundary to test here
    assert resumed.returncode == 0, resumed.stderr
    with read_store(job.store) as reader:
        assert_same_map(reader, job)
        assert [r["outcome"] for r in reader.attrs["runs"]] == ["interrupted", "complete"]


@slow
@pytest.mark.process
@pytest.mark.mpi
def test_a_stop_takes_back_the_tiles_queued_on_lanes(write_job, tmp_path):
    """Lanes hold their next tile (TILES_HELD): on a signal the master takes the queued
    ones back (WITHDRAW), so no tile starts after it and every started one is collected."""
    path, job = write_job()
    starts = tmp_path / "starts"
    script = textwrap.dedent(f"""
        import sys, time
        import campar.sweep.runner as runner
        from campar.cli import main
        from campar.sweep.job import load_job
        from campar.sweep.plan import plan_tiles
        from campar.sweep.tile import run_tile
        first = run_tile(load_job({str(path)!r}), plan_tiles(load_job({str(path)!r}))[0])
        def slow_tile(job, tile):  # every tile is one chain: the same shapes
            with open({str(starts)!r}, "a") as log:
                log.write(f"{{tile.index}} {{time.monotonic()}}\\n")
            time.sleep(1.5)
            return {{name: a.copy() for name, a in first.items()}}
        runner.run_tile = slow_tile
        sys.exit(main(["run", {str(path)!r}]))
    """)
    proc = subprocess.Popen(
        [*mpirun(2), sys.executable, "-c", script],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=subprocess_env(),
        start_new_session=True,
    )
    wait_for_tiles(job.store, 1, proc)  # ~1.5 s: two tiles run, two are queued
    time.sleep(0.5)
    signalled = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 75, stderr
    started = {
        int(i): float(t) for i, t in (line.split() for line in starts.read_text().splitlines())
    }
    assert max(started.values()) < signalled, (started, signalled)  # queued ones never ran
    with read_store(job.store) as reader:
        done = {int(i) for i in reader.done.nonzero()[0]}
    assert done == set(started) and len(done) == 4, (done, started)


@slow
@pytest.mark.process
@pytest.mark.mpi
def test_one_probe_loop_takes_in_every_waiting_message():
    """mpich's Iprobe can bring a message in and still answer no: the master's loop must
    not stop at the first no, or a backlog of messages drains one per poll."""
    script = textwrap.dedent("""
        import sys
        import time
        import numpy as np
        from mpi4py import MPI
        from campar.sweep.wire import waiting_messages
        comm = MPI.COMM_WORLD
        if comm.Get_rank():
            for i in range(3):
                request = comm.Isend(np.array([i], np.int64), 0, 5)
                while not request.Test():
                    time.sleep(0.0005)
            time.sleep(1.0)  # no MPI call: nothing pushes the messages on from here
        else:
            time.sleep(0.5)
            status, taken = MPI.Status(), 0
            for _ in waiting_messages(comm, MPI.ANY_SOURCE, 5, status):
                comm.Recv(np.empty(1, np.int64), status.Get_source(), 5)
                taken += 1
            sys.stdout.write(f"taken {taken} of {3 * (comm.Get_size() - 1)}\\n")
    """)
    result = run_mpi(4, "-c", script, command=[sys.executable], timeout=120)
    assert "taken 9 of 9" in result.stdout, result.stdout  # a loop that stops early: 1 of 9
    assert result.returncode == 0, result.stderr


# Two runs in one 3-rank world, run_tile raising by a rule of each run's own: "worker", rank 1
# fails every tile of a slow job (rank 0 cannot finish alone before rank 1 asks); "tile",
# tile 4 fails wherever it runs. Each rank's stderr of each run goes to a file of its own;
# the program exits with the last run's code.
FAULT_RUNS = textwrap.dedent("""
    import os, sys
    import campar.sweep.runner as runner
    from campar.cli import main
    from campar.sweep.tile import run_tile
    rank = int(os.environ["PMI_RANK"])
    RULES = {"worker": lambda tile: rank == 1, "tile": lambda tile: tile.index == 4}
    def faulty(job, tile):
        if rule(tile):
            raise RuntimeError(f"injected fault, tile {tile.index}")
        return run_tile(job, tile)
    runner.run_tile = faulty
    for name, path in zip(sys.argv[1::2], sys.argv[2::2]):
        rule = RULES[name]
        sys.stderr.flush()
        with open(f"{path}.{rank}.err", "w") as err:
            os.dup2(err.fileno(), 2)
        code = main(["run", path])
        sys.stdout.write(f"{name} {rank} {code}\\n")
        sys.stdout.flush()
    sys.exit(code)
""")


@pytest.fixture(scope="module")
def fault_runs(tmp_path_factory, warm_numba_cache):
    """{rule: (job, what the ranks said, {rank: exit code})} of the two FAULT_RUNS runs,
    and mpirun's exit code."""
    folder = tmp_path_factory.mktemp("faults")
    jobs = {}
    # write_job's slow job, whose serial reference the session may hold already
    for name, data in (("worker", merge(SMALL_JOB, SLOW)), ("tile", SMALL_JOB)):
        path = folder / f"{name}.yaml"
        data = {**data, "store": str(folder / f"{name}.zarr")}
        path.write_text(yaml.safe_dump(data, sort_keys=False))
        jobs[name] = (path, Job.from_dict(data))
    args = [a for name, (path, _) in jobs.items() for a in (name, path)]
    result = run_mpi(3, "-c", FAULT_RUNS, *args, command=[sys.executable])
    codes = {}
    for line in result.stdout.splitlines():
        name, rank, code = line.split()
        codes.setdefault(name, {})[int(rank)] = int(code)
    runs = {
        name: (job, "".join(p.read_text() for p in sorted(folder.glob(f"{name}.yaml.*.err"))))
        for name, (_, job) in jobs.items()
    }
    return {n: (job, said, codes.get(n, {})) for n, (job, said) in runs.items()}, result


@slow
@pytest.mark.process
@pytest.mark.mpi
def test_a_worker_that_fails_every_tile_does_not_stop_the_run(fault_runs):
    (job, said, codes), result = fault_runs[0]["worker"], fault_runs[1]
    assert codes == {0: 0, 1: 0, 2: 0}, (codes, result.stderr, said)
    assert f"rank 1 on {socket.gethostname()}" in said
    assert "injected fault" in said
    with read_store(job.store) as reader:
        assert_same_map(reader, job)


@slow
@pytest.mark.process
@pytest.mark.mpi
def test_a_tile_that_fails_on_two_ranks_ends_the_run_with_where(fault_runs):
    (job, said, codes), result = fault_runs[0]["tile"], fault_runs[1]
    assert result.returncode == 1 and codes[0] == 1, (codes, result.stderr, said)
    assert "tile 4 failed 2×" in said
    assert "injected fault, tile 4" in said and f"on {socket.gethostname()}" in said
    with read_store(job.store) as reader:
        assert not reader.done[4] and reader.done.sum() >= 1
    assert last_run(job.store)["outcome"] == "failed"


COLD_RUN = textwrap.dedent("""
    import json, sys
    from campar.core import dopri5, integrator, kernel, revolution, stages
    from campar.sweep.job import load_job
    from campar.sweep.runner import run_job
    from campar.sweep.wire import mpi_world

    run_job(load_job(sys.argv[1]))
    def compiled(dispatcher):  # [loaded from the cache, compiled here]
        stats = dispatcher.stats
        return [sum(stats.cache_hits.values()), sum(stats.cache_misses.values())]
    typed = [integrator.advance, stages.step_error, stages.rk4_step, dopri5.error_norm]
    sys.stdout.write(json.dumps({"rank": mpi_world().Get_rank(),
                                 "chain": compiled(kernel.chain_compiled),
                                 "revolution": compiled(revolution.run_revolution),
                                 "typed": {d.py_func.__name__: len(d.signatures) for d in typed}})
                     + "\\n")
""")


@slow
@pytest.mark.process
@pytest.mark.mpi
@pytest.mark.timeout(600)  # a cold compile on two ranks: minutes on a loaded machine
def test_ranks_of_a_node_split_a_cold_compile_and_load_each_others_half(write_job, tmp_path):
    path, job = write_job()
    env = {**subprocess_env(), "NUMBA_CACHE_DIR": str(tmp_path / "empty cache")}
    result = subprocess.run(
        [*mpirun(2), sys.executable, "-c", COLD_RUN, str(path)],
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )
    assert result.returncode == 0, result.stderr
    ranks = sorted(
        (json.loads(line) for line in result.stdout.splitlines()), key=lambda r: r["rank"]
    )
    # rank 0 compiled the chain and loaded rank 1's revolution; rank 1 the other way round
    assert ranks[0]["chain"] == [0, 1] and ranks[0]["revolution"] == [1, 0], ranks
    assert ranks[1]["chain"] == [1, 0] and ranks[1]["revolution"] == [0, 1], ranks
    # rank 1 typed the integrator under the revolution it compiled, DOP853's step alone:
    # DP5(4)'s error norm and RK4's step were pruned before typing (stages.method_tag),
    # never compiled; rank 0 typed none of it (the chain calls the revolution by address)
    typed = {"advance": 1, "step_error": 1, "rk4_step": 0, "error_norm": 0}
    assert ranks[1]["typed"] == typed, ranks
    assert ranks[0]["typed"] == dict.fromkeys(typed, 0), ranks
    with read_store(job.store) as reader:
        assert_same_map(reader, job)


@slow
@pytest.mark.process
@pytest.mark.mpi
def test_a_refusal_under_mpi_ends_every_rank_of_the_cli_and_of_an_spmd_caller(write_job, capsys):
    """One store made by a serial run, then a changed job refused twice: by ``campar run``
    under mpirun (one line, every rank ends), and by library callers, which run the same
    code on every rank: the refusal must reach them all."""
    path, job = write_job()
    assert call_campar(capsys, "run", path).returncode == 0  # the store, made in this process
    changed_path, changed = write_job(integrator={"rtol": 1e-9}, store=job.store)
    refused = run_mpi(3, "run", changed_path, timeout=120)
    assert refused.returncode == 3
    stored = f"integrator.rtol: {job.integrator.rtol:g} in the store"
    assert refused.stderr.count(stored) == 1  # rank 0 says it
    script = textwrap.dedent(f"""
        import os
        import sys
        from campar.errors import StoreMismatch
        from campar.sweep.job import Job
        from campar.sweep.runner import run_job
        job = Job.from_dict({changed.to_dict()!r})
        try:
            run_job(job)
        except StoreMismatch as exc:
            rank = os.environ["PMI_RANK"]
            sys.stdout.write(f"rank {{rank}} refused {{getattr(exc, 'rank', 0)}}\\n")
            run_job(job, overwrite=True)
            sys.stdout.write(f"rank {{rank}} overwrote\\n")
    """)
    result = run_mpi(2, "-c", script, command=[sys.executable])
    assert result.returncode == 0, result.stderr
    assert sorted(result.stdout.splitlines()) == [
        "rank 0 overwrote",
        "rank 0 refused 0",
        "rank 1 overwrote",
        "rank 1 refused 1",
    ]
    with read_store(job.store) as reader:
        assert reader.attrs["job"]["integrator"]["rtol"] == 1e-9
        assert_same_map(reader, changed)


@slow
@pytest.mark.process
@pytest.mark.mpi
def test_no_rank_spins_while_waiting(write_job):
    """Tiles that sleep (no CPU) on both ranks: CPU time stays far below wall time on each."""
    path, job = write_job()
    script = textwrap.dedent(f"""
        import sys, time
        import campar.sweep.runner as runner
        from campar.cli import main
        from campar.sweep.job import load_job
        from campar.sweep.plan import plan_tiles
        from campar.sweep.tile import run_tile
        first = run_tile(load_job({str(path)!r}), plan_tiles(load_job({str(path)!r}))[0])
        def sleepy(job, tile):  # every tile is one chain: the same shapes
            time.sleep(1.0)  # long against the run's own CPU (imports, store): ~0.8 s
            return {{name: a.copy() for name, a in first.items()}}
        runner.run_tile = sleepy
        wall, cpu = time.perf_counter(), time.process_time()
        code = main(["run", {str(path)!r}])
        usage = f"usage {{time.perf_counter() - wall}} {{time.process_time() - cpu}}\\n"
        sys.stdout.write(usage)  # one write: the ranks' lines reach mpirun whole
        sys.exit(code)
    """)
    result = run_mpi(2, "-c", script, command=[sys.executable])
    assert result.returncode == 0, result.stderr
    usage = [line.split()[1:] for line in result.stdout.splitlines() if line.startswith("usage")]
    assert len(usage) == 2
    for wall, cpu in (map(float, u) for u in usage):
        assert wall > 2.8 and cpu < 0.3 * wall, (wall, cpu)  # spinning: ≈ 0.65


@slow
@pytest.mark.process
@pytest.mark.mpi
def test_auto_tile_rows_are_chosen_for_the_ranks_and_kept_by_a_resume(write_job, capsys, caplog):
    grid = {  # 24 chains decide the rows; 6 cells a chain keep a tile ~0.1 s
        "omega": {"from": 6.0, "to": 1.0, "points": 6},
        "mu_cn": {"from": 0.9, "to": 0.6, "points": 24},
    }
    path, job = write_job(
        slow=True,
        sweep=grid,
        tiles={"rows": "auto"},
        transient={"mode": "fixed", "max_revolutions": 400},
    )
    three, serial = auto_tile_rows(job, 3, True)[0], auto_tile_rows(job, 1, False)[0]
    assert (three, serial) == (2, 4)  # 24 chains: 4 tiles a lane for 3 ranks, else the default
    proc = start_campar("run", path, launcher=mpirun(3))
    wait_for_tiles(job.store, 2, proc)
    kill_tree(proc.pid)
    proc.communicate(timeout=60)
    with read_store(job.store) as reader:
        assert reader.job.tiles.rows == three and not reader.done.all()
    caplog.set_level(logging.INFO)  # the run's log lines, in this process
    resumed = call_campar(capsys, "run", path)  # one rank now: the store's layout stays
    assert resumed.returncode == 0, resumed.stderr
    assert f"tiles.rows {three}, as the store" in caplog.text
    with read_store(job.store) as reader:
        assert reader.job.tiles.rows == three
        assert_same_map(reader, job.with_tile_rows(three))
