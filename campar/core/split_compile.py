"""Compile the map kernel with an empty cache on two cores instead of one.

numba compiles a function's callees while it types the function, one after the
other in one process: a cold ``campar point`` spent ~13 s compiling
``chain_compiled`` on one core while the other idled. Here a forked helper
compiles one revolution (``run_revolution`` with the integrator under it, ~45 % of
the work) into numba's on-disk cache, while this process compiles the revolution's
cacheable leaves and the cell's classification (the analysis functions the chain
calls), then the chain itself. Where the chain's typing reaches ``run_revolution``
it waits for the helper (``CompiledCallersOnly.awaiting``) and loads the helper's
result from the cache: 13.3 → 9.9 s (benchmarks/RESULTS.md).

The primers below call those functions with the argument types the chain passes
(``kernel.step_revolution``, ``kernel.run_cell``). If a primer drifts from the
chain, the chain compiles its own variant: slower, never wrong (tests/test_split_compile
checks that the chain loads every primed function instead).

Forking is safe only in a process with one thread and without MPI (``campar point``,
``campar warm-up``, a serial run before its lane starts): MPI ranks compile as before.
With a warm cache nothing is forked.
"""

import os
import signal
import sys
import threading
import time

import numpy as np
from numba import njit, typeof, types

from . import jitcache
from .analysis import (
    add_step_stats,
    assess_revolution,
    cycle_jacobian,
    distinct_period,
    multipliers_of,
    near_unit_circle,
    nonperiodic_kind,
    repeat_period,
    slow_cycle_nearby,
    spectral_radius,
    stable_subperiod,
    stretch_tangent,
    window_stats,
)
from .hermite import hermite_extremum
from .integrator import dense_eval, step_error
from .kernel import OUT_STATS, PERIOD_REACH, SLOW_MARGIN, SLOW_REACH, make_chain_work
from .model import make_params, released
from .revolution import run_revolution, scale_solver_options

HELPER_SECONDS = 300.0  # a helper takes ~6 s here; one still running after this is stuck


@njit(_nrt=False)
def prime_revolution(solver, cs, cw, law):
    """Compiles run_revolution as kernel.step_revolution calls it (never run)."""
    p = make_params(1.0, 1.0, 1.0, 1.0, 1.0, law)
    opt = scale_solver_options(solver, p.omega, cs.rk4_steps)
    want_stats = (cs.output_bits & OUT_STATS) != 0
    limit = cw.w6.counts[0] + cw.w6.counts[1]
    return run_revolution(cw.x6, cw.f6, p, opt, cw.w6, cw.mode, cw.revs[0], want_stats, limit,
                          None)  # fmt: skip


@njit(_nrt=False)
def prime_step_leaves(solver, cs, cw, law):
    """Compiles the cacheable leaves of one revolution as the integrator and
    run_revolution call them: this process has them in the cache before the helper,
    which reaches them late, needs them (the rest take the field as an argument, which
    numba does not cache)."""
    p = make_params(1.0, 1.0, 1.0, 1.0, 1.0, law)
    opt = scale_solver_options(solver, p.omega, cs.rk4_steps)
    w, y, h = cw.w6, cw.x6, p.omega
    err = step_error(opt.method, w.K, h, y, w.y_new, opt.rtol, opt.atol, opt.n_err)
    dense_eval(opt.method, w, y, w.y_new, h, err, opt.n_err, w.y_stage)
    th, _ = hermite_extremum(h, h, h, h, False)
    th, _ = hermite_extremum(th, h, h, h, True)
    contact = cw.mode[1]
    add_step_stats(cw.revs[0], h, released(contact, p), h, h, h, h, h, h, h, h, h, th)


@njit(_nrt=False)
def prime_classification(cs, cw, out):
    """Compiles the analysis functions as kernel.run_cell and its transients call them."""
    k = cw.w6.counts[0]  # an int64, as the chain's revolution counter (not a literal)
    base = np.int64(0)
    period, _, _, _ = assess_revolution(
        cw.xs, cw.jac, cw.est, k, base, cs.n_max, cs.conv_tol, cs.window_tol,
        cs.jump_residual, cs.jump_cap, cs.jump_agree,
    )  # fmt: skip
    stretch = stretch_tangent(cw.jac[k], cw.u)
    stretch += window_stats(cw.revs, k - cs.window_revolutions, cs.window_revolutions)[5]
    period += repeat_period(cw.xs, cs.max_revolutions, k, cs.n_max, cs.period_tol)
    m = distinct_period(cw.xs, k, period, cs.period_tol)
    m = stable_subperiod(cw.xs, cw.jac, k, m, PERIOD_REACH)
    dpn = cycle_jacobian(cw.jac, k, m)
    slow = near_unit_circle(dpn, SLOW_MARGIN)
    multipliers_of(dpn, out.multipliers[0])
    stretch += spectral_radius(dpn)
    slow |= slow_cycle_nearby(cw.xs, cw.jac, k, k - m, cs.n_max, SLOW_REACH, SLOW_MARGIN)
    return nonperiodic_kind(stretch, cs.lyap_tol), slow


def cache_is_cold() -> bool:
    """No compiled chain where numba will look for it (after jitcache dropped stale entries):
    under NUMBA_CACHE_DIR, a chain cached beside the sources does not count."""
    return not any(jitcache.located_cache_dir().glob("kernel.chain_compiled-*.nbi"))


def can_fork() -> bool:
    """One thread, no MPI, two cores: a fork copies nothing that runs."""
    if not hasattr(os, "fork") or threading.active_count() != 1:
        return False
    if len(os.sched_getaffinity(0)) < 2:
        return False
    mpi = sys.modules.get("mpi4py.MPI")
    return mpi is None or not mpi.Is_initialized()


def start_helper(solver, cs, law) -> int | None:
    """Fork the helper that compiles one revolution into the cache; its pid, or None
    (nothing forked) when the cache is warm or forking is unsafe. The caller compiles the
    chain next; where it reaches run_revolution it waits for the helper."""
    jitcache.ensure_fresh_cache()
    if not (can_fork() and cache_is_cold()):
        return None
    cw = make_chain_work(cs)
    signature = (typeof(solver), typeof(cs), typeof(cw), types.int64)
    pid = os.fork()
    if pid == 0:  # the helper: compile, then leave without running the parent's exit code
        status = 1
        try:
            prime_revolution.compile(signature)
            status = 0
        finally:
            os._exit(status)

    run_revolution.awaiting = lambda: wait_for(pid)
    return pid


def wait_for(pid: int) -> None:
    """Until the helper exits, or HELPER_SECONDS: a helper that hangs is killed and this
    process compiles what it did not deliver. Its exit status does not matter either way:
    whatever is missing from the cache is compiled here."""
    deadline = time.monotonic() + HELPER_SECONDS
    while os.waitpid(pid, os.WNOHANG) == (0, 0):
        if time.monotonic() > deadline:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            return
        time.sleep(0.005)


def prime_here(solver, cs, out, law) -> None:
    """This process's share while the helper works: the leaves the helper needs last,
    then the cell's classification."""
    cw = make_chain_work(cs)
    prime_step_leaves.compile((typeof(solver), typeof(cs), typeof(cw), types.int64))
    prime_classification.compile((typeof(cs), typeof(cw), typeof(out)))


def reap(pid: int | None) -> None:
    """Wait for the helper if the chain's compile did not (the chain was cached meanwhile)."""
    if pid is not None and run_revolution.awaiting is not None:
        run_revolution.awaiting = None
        wait_for(pid)
