"""A cold compile split over two processes loads what the helper compiled and gives the
kernel a serial compile gives; `campar warm-up` (a split cold compile) leaves nothing for a
point or a map to compile. The ranks of a node splitting a cold compile under mpirun:
test_mpi.py."""

import contextlib
import json
import os
import pickle
import signal
import subprocess
import sys
import textwrap
import threading
import time

import pytest
from numba import typeof

from campar.core import split_compile
from campar.core.kernel import chain_compiled, chain_loaded
from campar.sweep.job import cell_job
from campar.sweep.plan import Tile
from campar.sweep.tile import cell_settings, compile_kernel, run_tile, solver_options
from campar.views.point import POINT_OUTPUTS, simulate_point

# Whether the cache numba reads names the revolution a point's chain calls (the signature
# this test's process computes, pickled: typing it in the child would compile and cache
# the helpers whose return types it needs, make_params and scale_solver_options).
REVOLUTION_INDEXED = """
def revolution_indexed(path):
    import pickle
    from pathlib import Path

    from campar.core import numba_internals
    from campar.core.revolution import run_revolution

    signature = pickle.loads(Path(path).read_bytes())
    return numba_internals.cache_indexes(run_revolution, signature)
"""


def point_revolution(tmp_path):
    """The revolution signature of ``simulate_point(3.0)``'s chain, pickled into a file."""
    from campar.core.kernel import make_chain_work
    from campar.core.revolution_call import revolution_args

    job = cell_job(outputs=POINT_OUTPUTS, omega=3.0)
    solver, settings = solver_options(job), cell_settings(job)
    signature = revolution_args(solver, settings, make_chain_work(settings).w6, law=job.law())
    path = tmp_path / "revolution.pickle"
    path.write_bytes(pickle.dumps(signature))
    return path


# `campar warm-up` into an empty cache, in this process, with the helper it forks recorded;
# then the point whose cell and orbit the test compares, computed by the kernel the split
# compile left in this process.
COLD_WARM_UP = REVOLUTION_INDEXED + textwrap.dedent("""
    import contextlib, io, json, sys
    from campar.cli import main
    from campar.core import analysis, integrator, revolution, split_compile, stages
    from campar.views.point import simulate_point

    before = revolution_indexed(sys.argv[1])
    forked = []
    start = split_compile.start_helper
    def start_helper(*args):
        forked.append(start(*args))
        return forked[-1]
    split_compile.start_helper = start_helper
    said = io.StringIO()
    with contextlib.redirect_stdout(said):
        code = main(["warm-up"])
    result = simulate_point(3.0, mu_cn=0.75, multipliers=True, trace=True)
    chain_side = [analysis.assess_revolution, analysis.window_stats, analysis.repeat_period,
                  analysis.distinct_period, analysis.stable_subperiod, analysis.cycle_jacobian,
                  analysis.near_unit_circle, analysis.multipliers_of, analysis.spectral_radius,
                  analysis.slow_cycle_period, analysis.nonperiodic_kind, analysis.stretch_tangent]
    revolution_side = [stages.step_error, integrator.advance]
    # the window's deferred extrema (campar.core.deferred) are refined by the chain
    both_sides = [analysis.add_step_stats, stages.dense_eval]
    stats = revolution.run_revolution.stats
    print(json.dumps({
        "code": code, "said": said.getvalue(), "indexed_before": before,
        "forked": [pid is not None for pid in forked],
        "hits": sum(stats.cache_hits.values()), "misses": sum(stats.cache_misses.values()),
        "revolutions": len(revolution.run_revolution.signatures),
        "chain_side": {d.py_func.__name__: len(d.signatures) for d in chain_side},
        "revolution_side": {d.py_func.__name__: len(d.signatures) for d in revolution_side},
        "both_sides": {d.py_func.__name__: len(d.signatures) for d in both_sides},
        "result": result.to_dict(),
        "trace": [result.trace.y.tolist(), result.trace.events.tolist()],
    }))
""")

# A later process on that cache: a plotted point, then a map (`campar point --plot`,
# `campar run`), each as the CLI runs it.
WARM_POINT_AND_MAP = REVOLUTION_INDEXED + textwrap.dedent("""
    import json, sys
    from campar.cli import main

    indexed = revolution_indexed(sys.argv[1])
    codes = [main(["point", "--omega", "3", "--plot", sys.argv[2]]), main(["run", sys.argv[3]])]
    print(json.dumps({"indexed": indexed, "codes": codes}))
""")


def python_child(script: str, cache, *args, cwd=None) -> dict:
    """``python -c script args`` with numba's cache at ``cache``; its last stdout line."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    run = subprocess.run(
        [sys.executable, "-c", script, *map(str, args)],
        env=env,
        text=True,
        capture_output=True,
        timeout=600,
        cwd=cwd,
    )
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout.splitlines()[-1])


def cached_functions(cache) -> set[str]:
    """Every compiled function's index and every signature's machine code in the cache."""
    return {p.name for p in cache.rglob("*.nb[ic]")}


@pytest.mark.slow  # the suite's one cold compile outside mpirun: ~20 CPU s
@pytest.mark.process
@pytest.mark.timeout(900)  # a cold compile, then a point and a map: minutes on a loaded machine
def test_a_cold_warm_up_splits_its_compile_and_leaves_nothing_for_a_point_or_a_map(tmp_path):
    """`campar warm-up` (the install line's step) into an empty cache: its compile is split
    over two processes (a forked helper compiles the revolutions, this process the chain
    and the tracer, then loads the helper's half from the cache); the kernel it leaves
    gives the cell and the orbit this test's process gives; and a later process's plotted
    point and map compile nothing more."""
    cache = tmp_path / "cache"
    revolution = point_revolution(tmp_path)
    cold = python_child(COLD_WARM_UP, cache, revolution)
    assert cold["code"] == 0 and "compiled and cached" in cold["said"]
    # the empty cache does not name the revolution: cache_indexes reads the cache numba reads
    # (NUMBA_CACHE_DIR), whatever the source tree's __pycache__ holds
    assert cold["indexed_before"] is False
    assert cold["forked"] == [True]  # one helper, forked by the warm-up's compile
    # this process loaded both revolutions (the chain's, the tracer's with a recorder) from
    # the helper's cache entries and compiled nothing under them: the chain and the tracer
    # call them through their addresses and link none of their code
    assert (cold["hits"], cold["misses"], cold["revolutions"]) == (2, 0, 2)
    assert set(cold["revolution_side"].values()) == {0}, cold["revolution_side"]
    # the chain's classification compiled once per function, in this process
    assert set(cold["chain_side"].values()) == {1}, cold["chain_side"]
    assert set(cold["both_sides"].values()) == {1}, cold["both_sides"]
    # the split kernel's cell and orbit are those of this process's kernel (the session's,
    # compiled whole in one process or loaded from its cache)
    here = simulate_point(3.0, mu_cn=0.75, multipliers=True, trace=True)
    assert cold["result"] == json.loads(json.dumps(here.to_dict()))
    assert cold["trace"] == [here.trace.y.tolist(), here.trace.events.tolist()]
    assert here.label == "1-1"

    warm = cached_functions(cache)
    assert any(name.startswith("kernel.") for name in warm), sorted(warm)
    job = tmp_path / "job.yaml"
    job.write_text(
        "name: w\nsweep:\n  omega: {from: 4.0, to: 2.0, points: 3}\n"
        "  mu_cn: {from: 0.9, to: 0.8, points: 2}\n"
        f"store: {tmp_path / 'w.zarr'}\n"
    )
    later = python_child(
        WARM_POINT_AND_MAP, cache, revolution, tmp_path / "point.png", job, cwd=tmp_path
    )
    assert later == {"indexed": True, "codes": [0, 0]}  # the revolution the helper cached
    assert (tmp_path / "point.png").stat().st_size > 10_000
    assert cached_functions(cache) == warm  # nothing more compiled into the cache


def test_no_helper_where_forking_is_unsafe():
    job = cell_job(outputs=POINT_OUTPUTS, omega=3.0)
    solver, settings = solver_options(job), cell_settings(job)
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    try:
        assert not split_compile.can_fork()
        assert split_compile.start_helper(solver, settings) is None
    finally:
        stop.set()
        other.join()


def test_a_stuck_helper_is_killed_and_reaped(monkeypatch):
    monkeypatch.setattr(split_compile, "HELPER_SECONDS", 0.2)
    pid = os.fork()
    if pid == 0:  # a helper that never finishes: wait() returns only by killing it
        while True:
            signal.pause()
    try:
        split_compile.Helper(pid).wait()
        with pytest.raises(ChildProcessError):  # reaped: no zombie left behind
            os.waitpid(pid, 0)
    finally:
        with contextlib.suppress(ProcessLookupError, ChildProcessError):
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)


def test_a_loaded_chain_serves_every_job_of_its_method():
    # compile_kernel returns at once when chain_loaded: only the solver options' type may
    # differ between jobs' chains, so other outputs, transients and laws add no signature
    compile_kernel(cell_job(outputs=POINT_OUTPUTS, omega=3.0))
    signatures = len(chain_compiled.signatures)
    other = cell_job(
        omega=2.0,
        outputs=("label", "dc", "sections", "multipliers", "lyapunov"),
        transient="fixed",
        revolutions=20,
        tensile="allow",
    )
    assert chain_loaded(solver_options(other), other.law())
    run_tile(other, Tile(0, 0, 1))
    assert len(chain_compiled.signatures) == signatures
    # another method is another chain (whether this process holds it depends on the tests
    # before): its options' type differs, so the DOP853 chain never stands in for it
    assert typeof(
        solver_options(cell_job(outputs=POINT_OUTPUTS, omega=3.0, method="rk4"))
    ) != typeof(solver_options(other))


def test_a_rank_waiting_for_a_half_nobody_compiles_gives_up(monkeypatch):
    # a signature no rank compiles (a 3-element state): after HELPER_SECONDS the caller
    # compiles it itself instead of waiting for good
    from numba import types

    from campar.core.revolution import run_revolution

    monkeypatch.setattr(split_compile, "HELPER_SECONDS", 0.3)
    never = (types.Array(types.float64, 3, "C"),) * 2
    started = time.monotonic()
    split_compile.until_cached(run_revolution, never)  # a wait without end: the timeout fails it
    assert time.monotonic() - started >= 0.3
    assert never not in run_revolution.overloads


def test_where_numbas_cache_cannot_be_asked_a_cold_compile_is_not_split(monkeypatch):
    """The fallback of campar.core.numba_internals, on this session's warm cache: a
    revolution the cache does not name is cold while the cache can be asked, and where it
    cannot (another numba's dispatcher) nothing is forked and no rank waits for another's
    half, so each process compiles the whole kernel itself, as numba alone would. (The
    answers of each private call without the internals: test_numba_internals.py.)"""
    from numba import types

    from campar.core import numba_internals
    from campar.core.revolution import run_revolution

    never = (types.Array(types.float64, 3, "C"),) * 2  # a signature no process compiles
    assert split_compile.cold_for(run_revolution, [never])
    assert split_compile.cold_for(chain_compiled, [never])
    monkeypatch.setattr(numba_internals, "CACHE_ATTRIBUTE", "_cache_of_another_numba")
    assert not split_compile.cold_for(run_revolution, [never])
    assert not split_compile.cold_for(chain_compiled, [never])

    def no_fork():
        raise AssertionError("forked")

    monkeypatch.setattr(split_compile, "can_fork", lambda: True)
    monkeypatch.setattr(os, "fork", no_fork)
    job = cell_job(outputs=POINT_OUTPUTS, omega=3.0)
    solver, settings = solver_options(job), cell_settings(job)
    assert split_compile.start_helper(solver, settings, trace=True) is None
    started = time.monotonic()
    for rank in (0, 1):  # with the internals, rank 1 would wait HELPER_SECONDS for the chain
        split_compile.share_with_ranks((rank, 2), solver, settings, never, job.law())
        assert run_revolution.awaiting is None  # rank 0 would await the revolution
    assert time.monotonic() - started < 0.5 * split_compile.HELPER_SECONDS
