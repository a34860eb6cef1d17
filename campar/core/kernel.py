"""The compiled kernel: one cell, one continuation chain of cells.

``run_chain`` is the entry the runners call: it computes a chain of cells in
order (ω decreasing along the chain in a map), each warm-started from the
previous cell's final state at θ = 0, and fills preallocated output arrays.
No Python objects, no allocation per step; failures are status codes.
``run_chain`` (and campar.core.tracer's ``trace_orbit``) allocate their buffers in
Python and call the compiled entry point ``chain_compiled`` (``trace_compiled``), which
takes only arrays, numbers and named tuples, so numba's on-disk cache serves
every new process. Both call one revolution through its address
(campar.core.revolution_call), so a cold compile splits in two halves
(campar.core.split_compile). The field and event functions are handed to
the integrator as ``model.rhs`` (a module attribute): a dispatcher imported by
name and passed as an argument makes numba refuse to cache the caller
("dynamic globals"), measured with numba 0.68.
"""

import math
from typing import NamedTuple

import numpy as np
from numba import njit, typeof

from . import model
from .analysis import (
    SETTLED_DISTANCE,
    cycle_jacobian,
    distinct_period,
    exponent_window,
    multipliers_of,
    near_unit_circle,
    nonperiodic_kind,
    slow_cycle_period,
    spectral_radius,
    stable_subperiod,
    window_stats,
)
from .codes import (
    FAILED,
    FLAG_ESCAPED,
    FLAG_GRAZING,
    FLAG_NEWTON,
    FLAG_RESTARTED,
    FLAG_SETTLED,
    FLAG_SLOW,
    FLAG_WARM_EXTRAPOLATED,
    OK,
    PERIODIC,
)
from .deferred import DEFER_COLUMNS, refine_window
from .entry_steps import MEMORY_SHAPE
from .integrator import N_CTRL, StepWork, initial_step, make_work, restart_control
from .jit import hot, inlined
from .model import (
    MAX_EVENTS,
    N_STATE,
    N_STATE_VARIATIONAL,
    RISE,
    TWO_PI,
    contact_mode,
    gap,
    kernel_law,
    make_params,
    start_chain,
)
from .revolution import ALL_STATS, DUTY_STATS, NO_STATS, scale_solver_options
from .revolution_call import revolution_link
from .transient import CONVERGED, FIXED, spend, transient_converged, transient_fixed  # noqa: F401 (FIXED: tile)

# Output selection bits: a label-only map computes none of these.
OUT_STATS = 1  # duty cycle (and the grazing flag: ε's dips on the dense output)
OUT_SECTIONS = 2  # σn points of the steady motion
OUT_MULTIPLIERS = 4  # Floquet multipliers of periodic cells
OUT_LYAPUNOV = 8  # largest Lyapunov exponent
OUT_EXTREMA = 16  # ε extremes, Pn max (with OUT_STATS)

SLOW_MARGIN = 0.02  # a multiplier this close to the unit circle marks a slow cell
SLOW_REACH = 0.1  # … and, for a non-periodic cell, a stable cycle estimate this close
PERIOD_REACH = 1e-5  # a converged cycle this close to a stable one of a divisor period is it
GRAZE_TOL = 1e-5  # a dip of ε this close to 0 marks a cell whose p is sensitive
EXTRAPOLATE_MAX = 0.5  # extrapolate the warm start only between fixed points this close (L1)
EXTRAPOLATE_ORDER = 3  # the highest order: a cubic through the last four cells' cycles


class CellSettings(NamedTuple):
    """How one cell is run and classified; built by campar.sweep.tile.cell_settings.

    Each field is the job setting of the same name (campar.sweep.job:
    transient.*, classify.*, integrator.*), but for ``transient`` (the job's
    transient.mode), ``chaos_z`` (from transient.chaos_confidence) and ``output_bits``
    (the job's outputs).
    """

    transient: int  # CONVERGED or FIXED
    max_revolutions: int  # CONVERGED: budget of revolutions; FIXED: transient length
    window_revolutions: int  # read for a non-periodic verdict (FIXED: after the transient)
    n_max: int
    conv_tol: float
    window_tol: float
    period_tol: float
    newton: bool
    jump_residual: float
    jump_cap: float
    max_jumps: int
    jump_agree: float  # trust a far estimate agreeing to this fraction with the one n revs before
    lyap_tol: float
    max_steps: int
    extrapolate: int  # highest polynomial order of the warm start (0: the last state)
    rk4_steps: int  # RK4 steps per revolution
    chaos_after: int  # earliest revolution of a chaotic verdict (0: only at the budget)
    chaos_lyapunov: float  # … for a Lyapunov exponent per revolution above this
    chaos_z: float  # … at this confidence: the normal quantile of transient.chaos_confidence
    chaos_clear: int  # … with no stable cycle in sight nor Newton jump for this many revolutions
    chaos_sight: float  # … in sight: within this distance (0: not looked for)
    quasiperiodic_after: int  # earliest quasi-periodic verdict (0: only at the budget)
    output_bits: int  # OUT_* bits of the optional outputs to compute


class CellOutputs(NamedTuple):
    """Per-cell result arrays of a chain; optional ones may have length 0."""

    n: np.ndarray  # int32: period in revolutions (0: not periodic)
    p: np.ndarray  # int32: detachments in n revolutions (non-periodic: in the window)
    kind: np.ndarray  # int8: campar.core.codes.Kind
    status: np.ndarray  # int8: campar.core.codes.Status
    flags: np.ndarray  # int16: campar.core.codes.Flag
    dc: np.ndarray  # duty cycle: fraction of time separated
    eps_min: np.ndarray
    eps_max: np.ndarray
    pn_max: np.ndarray
    state: np.ndarray  # (cells, 2) final (y, y') at θ = 0
    revolutions: np.ndarray  # int32
    steps: np.ndarray  # int64 accepted steps
    lyapunov: np.ndarray  # per unit dimensionless time
    multipliers: np.ndarray  # (cells, 2, 2): (re, im) of both multipliers
    sections: np.ndarray  # (cells, S, 2) σn points, NaN-padded


class ChainWork(NamedTuple):
    """Buffers reused by every cell of a chain."""

    w2: StepWork  # integrator buffers without variational equations
    w6: StepWork  # … with them
    saved_ctrl: np.ndarray  # w6.ctrl while the budget's end tries revolutions (settle_at_budget)
    saved_memory: np.ndarray  # … and w6.h_memory (integrator.copy_step_control)
    x2: np.ndarray
    f2: np.ndarray
    x6: np.ndarray
    f6: np.ndarray
    mode: np.ndarray  # [cam phase, contact mode]
    xs: np.ndarray  # (R+1, 2) section points
    jac: np.ndarray  # (R, 4) one-revolution Jacobians
    est: np.ndarray  # (n_max, n_max, 3) cycle estimates by period (assess_revolution)
    revs: np.ndarray  # (R, deferred.DEFER_COLUMNS): statistics, then the deferred steps
    u: np.ndarray  # tangent vector for the Lyapunov exponent
    x_start: np.ndarray  # (2,) the start of the current cell
    prev: np.ndarray  # (EXTRAPOLATE_ORDER + 1, 2) the last cells' final states, newest first
    revolution: np.ndarray  # int64 [address, fingerprint] of run_revolution (revolution_call)
    refine: StepWork  # deferred.refine_window's buffers (N_STATE components)
    refine_mode: np.ndarray  # … and its contact mode


def make_chain_work(cs) -> ChainWork:
    """The buffers of a chain, allocated in Python: compiled allocation would cost
    numba compile time in every process with an empty cache."""
    rows = cs.max_revolutions + cs.window_revolutions + 2
    return ChainWork(
        w2=make_work(N_STATE, MAX_EVENTS, 0.0),
        w6=make_work(N_STATE_VARIATIONAL, MAX_EVENTS, 0.0),
        saved_ctrl=np.zeros(N_CTRL),
        saved_memory=np.zeros(MEMORY_SHAPE),
        x2=np.zeros(N_STATE),
        f2=np.zeros(N_STATE),
        x6=np.zeros(N_STATE_VARIATIONAL),
        f6=np.zeros(N_STATE_VARIATIONAL),
        mode=np.zeros(2, dtype=np.int64),
        xs=np.zeros((rows + 1, 2)),
        jac=np.zeros((rows, 4)),
        est=np.full((cs.n_max, cs.n_max, 3), -1.0),
        revs=np.zeros((rows, DEFER_COLUMNS)),
        u=np.array([1.0, 0.0]),
        x_start=np.empty(2),
        prev=np.empty((EXTRAPOLATE_ORDER + 1, 2)),
        revolution=np.zeros(2, dtype=np.int64),  # linked by run_chain
        refine=make_work(N_STATE, MAX_EVENTS, 0.0),
        refine_mode=np.zeros(2, dtype=np.int64),
    )


@inlined
def cell_stats(bits):
    """What the revolutions of a cell computing the outputs ``bits`` fold into their
    statistics (campar.core.revolution's NO_STATS, DUTY_STATS, ALL_STATS): a map that stores
    no extremum refines only the dips its grazing flag reads."""
    if bits & OUT_EXTREMA:
        return ALL_STATS
    if bits & OUT_STATS:
        return DUTY_STATS
    return NO_STATS


@inlined
def fail_cell(out, i, status, k, steps):
    out.n[i] = 0
    out.p[i] = 0
    out.kind[i] = FAILED
    out.status[i] = status
    out.flags[i] = 0
    out.dc[i] = np.nan
    out.eps_min[i] = np.nan
    out.eps_max[i] = np.nan
    out.pn_max[i] = np.nan
    out.state[i, 0] = np.nan
    out.state[i, 1] = np.nan
    out.revolutions[i] = k
    out.steps[i] = steps
    if out.lyapunov.shape[0] > 0:
        out.lyapunov[i] = np.nan
    if out.multipliers.shape[0] > 0:
        fill(out.multipliers[i], np.nan)
    if out.sections.shape[0] > 0:
        fill(out.sections[i], np.nan)


@inlined
def record_window(out, i, cw, first, count, period, p, method, extremes):
    """Statistics of revolutions first … first+count−1 into the outputs of cell i, the
    deferred extrema that can be the window's refined first (campar.core.deferred;
    ``extremes``: all of them, else ε's minima alone)."""
    refine_window(cw.revs, first, count, cw.refine, cw.refine_mode, p, method, extremes, GRAZE_TOL)
    t_free, detach, eps_min, eps_max, pn_max, stretch, graze = window_stats(cw.revs, first, count)
    out.p[i] = int(detach + 0.5)
    out.dc[i] = t_free / (count * period)
    out.eps_min[i] = eps_min
    out.eps_max[i] = eps_max
    out.pn_max[i] = pn_max
    return stretch, graze


@inlined
def record_sections(out, i, cw, last, count):
    s = out.sections.shape[1]
    fill(out.sections[i], np.nan)
    for j in range(min(count, s)):
        out.sections[i, j, 0] = cw.xs[last - count + 1 + j, 0]
        out.sections[i, j, 1] = cw.xs[last - count + 1 + j, 1]


@inlined
def run_cell(x_start, p, opt, cs, cw, out, i):
    """Compute cell i from x_start; returns (status, index of the final state in xs)."""
    period_time = TWO_PI / p.omega
    stats = cell_stats(cs.output_bits)
    c2 = cw.w2.counts
    c6 = cw.w6.counts
    steps0 = c2[0] + c6[0]
    step_budget = spend(cw) + cs.max_steps
    cw.xs[0, 0] = x_start[0]
    cw.xs[0, 1] = x_start[1]
    cw.u[0] = 1.0
    cw.u[1] = 0.0
    flags = 0
    if cs.transient == CONVERGED:
        status, k, n, base, jumps, escapes, settled = transient_converged(
            cw, p, opt, cs, stats, step_budget
        )
        if jumps > escapes:
            flags |= FLAG_NEWTON
        if escapes > 0:
            flags |= FLAG_ESCAPED
        if settled:
            flags |= FLAG_SETTLED
        variational_from = 0
    else:
        status, k, n = transient_fixed(cw, p, opt, cs, stats, step_budget)
        base = cs.max_revolutions
        variational_from = cs.max_revolutions
    steps = c2[0] + c6[0] - steps0
    if status != OK:
        fail_cell(out, i, status, k, steps)
        return status, 0
    out.revolutions[i] = k
    out.steps[i] = steps
    out.status[i] = OK
    final = k
    if n == 0 and cs.transient == CONVERGED:
        # the budget ended on a slow stable cycle (analysis.slow_cycle_period): it is the
        # motion, which the window would read as a torus (its exponent is near 0)
        n = slow_cycle_period(
            cw.xs,
            cw.jac,
            k,
            max(base, k - cs.window_revolutions),
            cs.n_max,
            SETTLED_DISTANCE,
            SLOW_MARGIN,
        )
        if n > 0:
            flags |= FLAG_SETTLED
    if n > 0:
        m = distinct_period(cw.xs, k, n, cs.period_tol)
        if cs.transient == CONVERGED:  # (the paper's recipe keeps its plain repeat test)
            m = stable_subperiod(cw.xs, cw.jac, k, m, PERIOD_REACH)
        _, graze = record_window(
            out, i, cw, k - m, m, period_time, p, opt.method, stats == ALL_STATS
        )
        if graze < GRAZE_TOL:
            flags |= FLAG_GRAZING
        out.n[i] = m
        out.kind[i] = PERIODIC
        have_jacobian = k - m >= variational_from
        if have_jacobian:
            dpn = cycle_jacobian(cw.jac, k, m)
            if near_unit_circle(dpn, SLOW_MARGIN):
                flags |= FLAG_SLOW
            if out.multipliers.shape[0] > 0:
                multipliers_of(dpn, out.multipliers[i])
            if out.lyapunov.shape[0] > 0:
                out.lyapunov[i] = math.log(spectral_radius(dpn)) / (m * period_time)
        elif out.lyapunov.shape[0] > 0:
            out.lyapunov[i] = np.nan
        if out.sections.shape[0] > 0:
            record_sections(out, i, cw, k, m)
        # of the cycle's points, continue from the one nearest the start
        best = math.inf
        for j in range(k - m + 1, k + 1):
            d = abs(cw.xs[j, 0] - x_start[0]) + abs(cw.xs[j, 1] - x_start[1])
            if d < best:
                best = d
                final = j
    else:
        if cs.transient == CONVERGED:  # the revolutions a chaos verdict read
            first, count = exponent_window(k, base, cs.window_revolutions)
        else:
            count = max(min(cs.window_revolutions, k - variational_from), 1)
            first = k - count
        stretch, _ = record_window(
            out, i, cw, first, count, period_time, p, opt.method, stats == ALL_STATS
        )
        out.n[i] = 0
        out.kind[i] = nonperiodic_kind(stretch, cs.lyap_tol)
        if slow_cycle_period(cw.xs, cw.jac, k, k - count, cs.n_max, SLOW_REACH, SLOW_MARGIN):
            flags |= FLAG_SLOW
        if out.lyapunov.shape[0] > 0:
            out.lyapunov[i] = stretch / period_time
        if out.multipliers.shape[0] > 0:
            fill(out.multipliers[i], np.nan)
        if out.sections.shape[0] > 0:
            record_sections(out, i, cw, k, min(k, out.sections.shape[1]))
    if stats == NO_STATS:
        out.dc[i] = np.nan
    if stats != ALL_STATS:  # not asked for: ε's extremes are not all refined
        out.eps_min[i] = np.nan
        out.eps_max[i] = np.nan
        out.pn_max[i] = np.nan
    out.flags[i] = flags
    out.state[i, 0] = cw.xs[final, 0]
    out.state[i, 1] = cw.xs[final, 1]
    return OK, final


def run_chain(omega, zeta, f0, mu_kn, mu_cn, law, x_init, solver, cs, out):
    """Compute a continuation chain of cells in order; outputs are filled in place.

    Cell i has parameters (omega[i], zeta[i], f0[i], mu_kn[i], mu_cn[i]); ``law`` is the
    job's model.Law (the force law's options as LAW_* bits, the cam, the contact law), or
    LAW_* bits alone for the paper's cam and contact (``model.kernel_law``): the options
    are one integer, so every option runs the same compiled code, and each combination of
    laws compiles a kernel of its own. Cell 0
    starts from x_init, every later cell from the final state of the one before
    (extrapolated through the cycles of the cells before: extrapolation_order),
    and the cell after a failure from x_init again, its step control restarted
    as for cell 0. Releases the GIL, so a thread can compute while another one
    talks MPI.
    """
    law = kernel_law(law)
    cw = make_chain_work(cs)
    cw.revolution[:] = revolution_link(solver, cs, cw.w6, law=law)
    start_chain(law)
    chain_compiled(omega, zeta, f0, mu_kn, mu_cn, law, x_init, solver, cs, out, cw)


def compile_chain(signature, solver, cs, law) -> None:
    """Compile (or load) the chain for ``signature`` (chain_signature), then the revolution
    it calls: in this order a cold chain compiles while a forked helper compiles the
    revolution (campar.core.split_compile), and waits for it only at the end."""
    chain_compiled.compile(signature)
    revolution_link(solver, cs, make_chain_work(cs).w6, law=law)


def chain_signature(law, x_init, solver, cs, out) -> tuple:
    """chain_compiled's argument types for a chain with these settings."""
    none = np.empty(0)
    args = (
        none,
        none,
        none,
        none,
        none,
        kernel_law(law),
        x_init,
        solver,
        cs,
        out,
        make_chain_work(cs),
    )
    return tuple(typeof(a) for a in args)


def chain_loaded(solver, law) -> bool:
    """This process holds ``chain_compiled`` for these solver options and this law: compiled
    here or loaded from the cache. Of the chain's arguments only the types of these two
    differ between jobs (the method tag, stages.method_tag; the laws, model.Law);
    every other one is fixed."""
    solver_type, law_type = typeof(solver), typeof(kernel_law(law))
    return any(
        signature[7] == solver_type and signature[5] == law_type
        for signature in chain_compiled.signatures
    )


# Reference counting off, as in campar.core.jit.hot: the inlined cell layer reads arrays
# from cw's fields once a revolution, and each read compiled an incref/decref pair.
# With it off, LLVM spends ~25 % less time on this entry cold and the plane runs ~5 % faster.
@njit(cache=True, nogil=True, _nrt=False)
def chain_compiled(omega, zeta, f0, mu_kn, mu_cn, law, x_init, solver, cs, out, cw):
    """run_chain's compiled body, with the chain's buffers ``cw`` (make_chain_work)."""
    x_start = cw.x_start
    prev = cw.prev
    # how many of them are cycles of one period in a row (0: restart); not a literal 0:
    # numba would compile extrapolation_order for it too (as for every literal argument)
    streak = np.int64(0)
    prev_n = 0
    h_started = False
    for i in range(omega.shape[0]):
        p = make_params(omega[i], zeta[i], f0[i], mu_kn[i], mu_cn[i], law)
        opt = scale_solver_options(solver, omega[i], cs.rk4_steps)
        flags = 0
        order = min(extrapolation_order(prev, streak), cs.extrapolate)
        for c in range(2):  # component-wise: array expressions would allocate
            x_start[c] = x_init[c] if streak == 0 else extrapolated(prev, order, c)
        if streak == 0 and i > 0:
            flags |= FLAG_RESTARTED
        elif streak > 0 and order > 0:
            flags |= FLAG_WARM_EXTRAPOLATED
        if not h_started:
            cw.x2[0] = x_start[0]
            cw.x2[1] = x_start[1]
            cw.mode[0] = RISE
            eps, deps = gap(0.0, cw.x2, p, cw.mode[0])  # not RISE: no literal variant of gap
            cw.mode[1] = contact_mode(eps, deps, p)
            model.rhs(0.0, cw.x2, p, cw.mode, cw.f2)
            h0 = initial_step(
                model.rhs, 0.0, cw.x2, cw.f2, p, cw.mode, solver.rtol, solver.atol, 2, 0.1
            )
            restart_control(cw.w2, h0)
            restart_control(cw.w6, h0)
            h_started = True
        status, final = run_cell(x_start, p, opt, cs, cw, out, i)
        out.flags[i] |= flags
        if status != OK:
            streak = np.int64(0)
            h_started = False  # a failure can leave the step size below its floor
            continue
        periodic = out.kind[i] == PERIODIC
        same_period = periodic and streak > 0 and out.n[i] == prev_n
        streak = min(streak + 1, EXTRAPOLATE_ORDER + 1) if same_period else 1
        prev_n = out.n[i] if periodic else -1
        for j in range(EXTRAPOLATE_ORDER, 0, -1):  # element by element: a row assignment
            for c in range(2):  # compiles numba's shape-checking error message (every cold compile)
                prev[j, c] = prev[j - 1, c]
        for c in range(2):
            prev[0, c] = cw.xs[final, c]


@hot
def fill(a, value):
    """Set every element of a 2-D array (a slice assignment costs numba more to compile)."""
    for i in range(a.shape[0]):
        for j in range(a.shape[1]):
            a[i, j] = value


@hot
def extrapolation_order(prev, streak):
    """Polynomial order of the warm start through the last cells' cycles (0: the last state).

    Up to ``streak`` − 1 (the cells in a row whose cycles have one period, newest in
    prev[0]), and raised only while each finite difference of their fixed points is no
    larger than the one of the order below: on a smooth branch each order of the
    polynomial adds less; where the differences grow (the cells' own convergence error
    dominates them on a flat branch, or the branch bends at a corner) the lower order is
    the safer start. None between fixed points over EXTRAPOLATE_MAX apart (the cycle
    jumped, or the phase of an n-cycle's points is in doubt).
    """
    if streak < 2:
        return 0
    step = difference_size(prev, 1)
    if not step <= EXTRAPOLATE_MAX:
        return 0
    order = 1
    while order < min(streak - 1, EXTRAPOLATE_ORDER):
        higher = difference_size(prev, order + 1)
        if not higher <= step:
            break
        step = higher
        order += 1
    return order


@hot
def difference_size(prev, order):
    """|∇^order prev[0]|, the L1 norm of the backward difference of that order."""
    size = 0.0
    for c in range(2):
        size += abs(backward_difference(prev, order, c))
    return size


@hot
def backward_difference(prev, order, c):
    """Component c of ∇^order prev[0] (∇x_i = x_i − x_{i−1}; binomial coefficients)."""
    total = 0.0
    coefficient = 1.0
    for j in range(order + 1):
        total += coefficient * prev[j, c]
        coefficient *= -(order - j) / (j + 1)
    return total


@hot
def extrapolated(prev, order, c):
    """Component c of the next cell's start: Newton's backward-difference polynomial of
    this order through prev, one cell on (x_{i+1} = Σ_{j ≤ order} ∇^j x_i)."""
    total = 0.0
    for j in range(order + 1):
        total += backward_difference(prev, j, c)
    return total
