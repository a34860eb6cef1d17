"""A cold compile split over two processes loads what the helper compiled and gives the
kernel a serial compile gives."""

import contextlib
import json
import os
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

COLD_POINT = textwrap.dedent("""
    import json, sys
    from campar.core import analysis, integrator, numba_internals, revolution, split_compile
    from campar.sweep import tile
    from campar.views.point import simulate_point

    if sys.argv[1] == "without internals":  # a numba whose cache campar cannot ask
        numba_internals.CACHE_ATTRIBUTE = "_cache_of_another_numba"
    forked = []
    start = split_compile.start_helper
    def start_helper(*args):
        forked.append(start(*args))
        return forked[-1]
    split_compile.start_helper = start_helper
    result = simulate_point(3.0, mu_cn=0.75, multipliers=True, trace=True)
    chain_side = [analysis.assess_revolution, analysis.window_stats, analysis.repeat_period,
                  analysis.distinct_period, analysis.stable_subperiod, analysis.cycle_jacobian,
                  analysis.near_unit_circle, analysis.multipliers_of, analysis.spectral_radius,
                  analysis.slow_cycle_period, analysis.nonperiodic_kind, analysis.stretch_tangent]
    revolution_side = [integrator.step_error, integrator.advance]
    # the window's deferred extrema (campar.core.deferred) are refined by the chain
    both_sides = [analysis.add_step_stats, integrator.dense_eval]
    stats = revolution.run_revolution.stats
    print(json.dumps({
        "forked": [pid is not None for pid in forked],
        "hits": sum(stats.cache_hits.values()), "misses": sum(stats.cache_misses.values()),
        "revolutions": len(revolution.run_revolution.signatures),
        "chain_side": {d.py_func.__name__: len(d.signatures) for d in chain_side},
        "revolution_side": {d.py_func.__name__: len(d.signatures) for d in revolution_side},
        "both_sides": {d.py_func.__name__: len(d.signatures) for d in both_sides},
        # a DOP853 job's kernel has no other stepper (integrator.method_tag)
        "other_steppers": len(integrator.rk4_step.signatures + integrator.error_norm.signatures),
        "result": result.to_dict(),
        "trace": [result.trace.y.tolist(), result.trace.events.tolist()],
    }))
""")


def cold_point(mode: str, cache) -> dict:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    run = subprocess.run(
        [sys.executable, "-c", COLD_POINT, mode],
        env=env,
        text=True,
        capture_output=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout)


@pytest.mark.slow
@pytest.mark.process
@pytest.mark.timeout(600)  # two cold compiles of the kernel: ~20 s each idle, minutes loaded
def test_split_compile_loads_the_helpers_revolution_and_matches_a_serial_compile(tmp_path):
    """The suite's cold compiles, two: split over two processes, and serial where numba's
    cache cannot be asked (campar.core.numba_internals): both give the cell and the orbit
    this process gives, and what the split compile cached is found in the cache."""
    split = cold_point("split", tmp_path / "split")
    serial = cold_point("without internals", tmp_path / "serial")
    # without the internals the helper is asked for and declines: nothing is split
    assert split["forked"] == [True] and serial["forked"] == [False]
    # this process loaded both revolutions (the chain's, the tracer's with a recorder) from
    # the helper's cache entries and compiled nothing under them: the chain and the tracer
    # call them through their addresses and link none of their code
    assert (split["hits"], split["misses"], split["revolutions"]) == (2, 0, 2)
    assert set(split["revolution_side"].values()) == {0}, split["revolution_side"]
    assert (serial["hits"], serial["misses"], serial["revolutions"]) == (0, 2, 2)
    # the chain's classification compiled once per function, in this process
    assert set(split["chain_side"].values()) == {1}, split["chain_side"]
    assert set(split["both_sides"].values()) == {1}, split["both_sides"]
    assert split["result"] == serial["result"] and split["trace"] == serial["trace"]
    here = simulate_point(3.0, mu_cn=0.75, multipliers=True, trace=True)
    assert json.loads(json.dumps(here.to_dict())) == serial["result"]
    assert here.label == "1-1"
    # the serial compile typed the whole kernel in this process: DP5(4)'s error estimate and
    # RK4's step were pruned before typing, never compiled
    assert serial["other_steppers"] == 0
    # in_cache finds the revolution the split compile put in its cache (an empty cache:
    # test_in_cache_reads_the_cache_numba_reads)
    assert in_cache_run(tmp_path / "split") == ["True"]


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


IN_CACHE = textwrap.dedent("""
    import sys
    from campar.core import numba_internals
    from campar.core.kernel import make_chain_work
    from campar.core.revolution import run_revolution
    from campar.core.revolution_call import revolution_args
    from campar.sweep.tile import cell_settings, solver_options
    from campar.sweep.job import cell_job
    from campar.views.point import POINT_OUTPUTS
    job = cell_job(outputs=POINT_OUTPUTS, omega=3.0)
    solver, settings = solver_options(job), cell_settings(job)
    signature = revolution_args(solver, settings, make_chain_work(settings).w6, law=job.law())
    print(numba_internals.cache_indexes(run_revolution, signature))
""")


def in_cache_run(cache) -> list[str]:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    run = subprocess.run(
        [sys.executable, "-c", IN_CACHE], env=env, text=True, capture_output=True, timeout=300
    )
    assert run.returncode == 0, run.stderr
    return run.stdout.split()


@pytest.mark.process
def test_in_cache_reads_the_cache_numba_reads(tmp_path):
    """The helper forks where the job's revolution is missing from the cache numba will
    read (``numba_internals.cache_indexes``, ``split_compile.cold_for``): under
    NUMBA_CACHE_DIR only that directory counts, whatever the source tree's ``__pycache__``
    holds."""
    assert in_cache_run(tmp_path / "cache") == ["False"]


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
