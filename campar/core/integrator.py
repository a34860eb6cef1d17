"""Explicit Runge–Kutta stepping with dense output, step control and event location.

Methods: Dormand–Prince 5(4) (Dormand & Prince 1980) with the 4th-order
continuous extension of Shampine (1986) and Hairer's PI step-size control, and
the classical fixed-step RK4 (the paper's method family) with cubic Hermite
dense output, and Dormand–Prince 8(5,3) (DOP853, core/dop853.py) with its
7th-order dense output and Hairer's step-size control.

The integrator knows nothing of cams. It sees

* ``rhs(t, y, p, mode, dy)`` — a vector field that is smooth while ``mode``
  (an int array, the discrete state of a hybrid system) is fixed;
* ``events(t, y, f, p, mode, g, dg) -> m`` — m event functions, positive while
  the mode holds, into g, and their time rates (given f = rhs(t, y)) into dg;
  they may read only the error-controlled components y[:n_err];
* ``t_end`` — a breakpoint that a step must end on exactly.

``advance`` takes one accepted step and ends it early, exactly on the first
root of an event function, so every step integrates a smooth field. Roots are
found on the dense output; a pair of roots inside one step is caught from the
cubic Hermite model of g built from its values and rates at both ends.
"""

import math
from typing import NamedTuple

import numpy as np

from . import dop853, entry_steps
from .codes import NONFINITE, OK, STEP_UNDERFLOW
from .dopri5 import N_STAGES, A, B, C, E, P, dopri5_dense_eval, error_norm  # noqa: F401 (B, E, P: tests)
from .hermite import MAXIMUM, MINIMUM, hermite_extremum
from .jit import entry, hot

DP54 = 0
RK4 = 1
DOP853 = 2


def method_tag(code: int) -> tuple:
    """A method as the compiled code receives it (``SolverOptions.method``): a tuple whose
    length is the method's code. numba folds ``len()`` of a tuple argument to a constant
    before typing and prunes the branches it decides, so a job's kernel compiles its own
    stepper only (a literal integer is not pruned on); a DOP853 job compiles neither
    DP5(4) nor RK4: a one-cell run with an empty cache compiles less (benchmarks/RESULTS.md)."""
    return (0,) * code


K_ROWS = dop853.N_STAGES_EXTENDED  # rows of StepWork.K: enough for every method

# Step-size control (Hairer, Nørsett & Wanner, DOPRI5): PI controller.
SAFETY = 0.9  # aim below the tolerance so the next step is likely accepted
MIN_FACTOR = 0.2  # never shrink by more than 5× at once
MAX_FACTOR = 10.0  # never grow by more than 10× at once
PI_BETA = 0.04  # weight of the previous error; damps oscillation at the stability limit
ERR_FLOOR = 1e-4  # the previous error the controller remembers: at least this (and at a start)
LOG_ERR_FLOOR = math.log(ERR_FLOOR)
ERROR_EXPONENT = 0.2 - 0.75 * PI_BETA
# DOP853: Hairer's dop853.f, an I controller (β = 0) on err^(1/8)
ERROR_EXPONENT_853 = 1.0 / (dop853.ERROR_ORDER + 1)
MAX_REJECTS = 60  # consecutive rejections before the step is declared underflowed
# A step that would leave less than this fraction of itself before t_end is stretched.
STRETCH = 0.01
LOCATE_MAX_ITER = 80
HERMITE_BOUND = 4.0 / 27.0
# The cubic model's interior minimum must stay above this fraction of the end
# values, or the dense output is searched for a dip below zero.
DIP_MARGIN = 0.5
GOLDEN = 0.6180339887498949
DIP_ITER = 24

# Slots of StepWork.ctrl, the step-control state one step hands to the next.
CTRL_H = 0  # proposed size of the next step
CTRL_ERR = 1  # log of the last accepted step's error norm (the PI controller's memory)
CTRL_G1_T = 2  # time of the event values in g1, dg1 the next step may reuse (NaN: none)
CTRL_G1_MODE0 = 3  # the mode (mode[0], mode[1]) they belong to
CTRL_G1_MODE1 = 4
CTRL_G1_M = 5  # how many event functions they hold
CTRL_DENSE = 6  # 1 when StepWork.F holds the DOP853 dense output of the step in K
N_CTRL = 7


class SolverOptions(NamedTuple):
    """Integrator settings; times in the dimensionless units of the field."""

    method: tuple  # method_tag(DP54, RK4 or DOP853)
    rtol: float
    atol: float
    h_fixed: float  # RK4 step size (DP54: unused)
    h_min: float  # step-size floor; below it the step underflows
    event_tol: float  # absolute tolerance of an event time
    n_err: int  # the first n_err components are error-controlled


class StepWork(NamedTuple):
    """Caller-owned buffers for ``advance``; build with ``make_work``."""

    K: np.ndarray  # (K_ROWS, n) stage derivatives; K[end_row(method)] = f at the step end
    y_new: np.ndarray  # (n,) state at the step end
    y_old: np.ndarray  # (n,) state at the start of the last accepted step (its dense output's)
    y_stage: np.ndarray  # (n,) stage argument, dense value
    g0: np.ndarray  # event values and rates at the step start
    dg0: np.ndarray
    g1: np.ndarray  # … at the step end
    dg1: np.ndarray
    g_tmp: np.ndarray
    dg_tmp: np.ndarray
    ctrl: np.ndarray  # (N_CTRL,) step-control state, slots CTRL_*
    counts: np.ndarray  # [accepted steps, rejected steps, field evaluations]
    F: np.ndarray  # (7, n) DOP853 dense-output coefficients of the step in K
    h_memory: np.ndarray  # (entry_steps.MEMORY_SHAPE) the step to enter (mode[0], mode[1]) with


def make_work(n, max_events, h0) -> StepWork:
    """Buffers for an n-dimensional state with up to max_events event functions
    (allocated in Python, as every buffer of the core: see kernel.make_chain_work)."""
    w = StepWork(
        K=np.zeros((K_ROWS, n)),
        y_new=np.zeros(n),
        y_old=np.zeros(n),
        y_stage=np.zeros(n),
        g0=np.zeros(max_events),
        dg0=np.zeros(max_events),
        g1=np.zeros(max_events),
        dg1=np.zeros(max_events),
        g_tmp=np.zeros(max_events),
        dg_tmp=np.zeros(max_events),
        ctrl=np.empty(N_CTRL),
        counts=np.zeros(3, dtype=np.int64),
        F=np.zeros((dop853.INTERPOLATOR_POWER, n)),
        h_memory=np.zeros(entry_steps.MEMORY_SHAPE),
    )
    restart_control(w, h0)
    return w


@hot
def copy_step_control(ctrl, memory, to_ctrl, to_memory):
    """Copy a StepWork's step control (``ctrl``: the proposed step, the controller's
    memory) and its entry steps (``memory``: ``h_memory``) into ``to_ctrl`` and
    ``to_memory``: what one revolution hands the next. Every other buffer of a StepWork
    is a step's scratch, written before it is read. A chain that tries revolutions and
    takes them back restores these, so the cells after it are computed as if it had not
    tried."""
    for i in range(ctrl.shape[0]):
        to_ctrl[i] = ctrl[i]
    for i in range(memory.shape[0]):
        for j in range(memory.shape[1]):
            to_memory[i, j] = memory[i, j]


@entry
def restart_control(w, h0):
    """Step control as at a start: next step h0, no error history, no reusable events."""
    w.ctrl[CTRL_H] = h0
    w.ctrl[CTRL_ERR] = LOG_ERR_FLOOR
    w.ctrl[CTRL_G1_T] = np.nan
    w.ctrl[CTRL_G1_MODE0] = -1.0
    w.ctrl[CTRL_G1_MODE1] = -1.0
    w.ctrl[CTRL_G1_M] = 0.0
    entry_steps.forget(w.h_memory)


class TrialStep(NamedTuple):
    """The step just tried, whose dense output the event search reads.

    w holds its stages and end state; the event functions see (t, y) and the
    field's parameters p and mode exactly as the step did.
    """

    method: tuple  # method_tag(DP54, RK4 or DOP853)
    t: float  # start time
    y: np.ndarray  # (n,) state at the start
    h: float  # step size
    p: object  # the field's parameters, opaque to the integrator
    mode: np.ndarray  # the discrete state the step was taken in
    w: StepWork
    n_err: int  # components of the dense output the event functions read
    theta_tol: float  # tolerance of an event time, as a fraction of h


class Bracket(NamedTuple):
    """A sign change of an event function over a trial step, in fractions θ of it."""

    a: float
    fa: float  # g(a) > 0
    b: float  # a < b
    fb: float  # g(b) ≤ 0


@hot
def rk_stages(rhs, t, y, h, p, mode, w, a, c, first, last, to_new):
    """Stages first … last of an explicit Runge–Kutta tableau (a, c) into w.K:
    K[s] = rhs(t + c[s] h, y + h Σ_j a[s, j] K[j]). With ``to_new``, stage ``last``
    is f at the new state (row ``last`` of ``a`` holds the weights), left in w.y_new."""
    n = y.shape[0]
    K = w.K
    for s in range(first, last + 1):
        out = w.y_new if to_new and s == last else w.y_stage
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += a[s, j] * K[j, i]
            out[i] = y[i] + h * acc
        rhs(t + c[s] * h, out, p, mode, K[s])
    w.counts[2] += last - first + 1


@hot
def rk_step(rhs, t, y, f, h, p, mode, w, a, c, last):
    """One step of an explicit FSAL-form tableau (DP5(4): last 6; DOP853: 12) from
    (t, y) with f = rhs(t, y): fills K[0 … last] and w.y_new."""
    for i in range(y.shape[0]):
        w.K[0, i] = f[i]
    rk_stages(rhs, t, y, h, p, mode, w, a, c, 1, last, True)


@hot
def rk4_step(rhs, t, y, f, h, p, mode, w):
    """One classical RK4 step; K[0..3] hold the stages, K[6] = rhs at the new point."""
    n = y.shape[0]
    K = w.K
    for i in range(n):
        K[0, i] = f[i]
        w.y_stage[i] = y[i] + 0.5 * h * K[0, i]
    rhs(t + 0.5 * h, w.y_stage, p, mode, K[1])
    for i in range(n):
        w.y_stage[i] = y[i] + 0.5 * h * K[1, i]
    rhs(t + 0.5 * h, w.y_stage, p, mode, K[2])
    for i in range(n):
        w.y_stage[i] = y[i] + h * K[2, i]
    rhs(t + h, w.y_stage, p, mode, K[3])
    for i in range(n):
        w.y_new[i] = y[i] + h / 6.0 * (K[0, i] + 2.0 * K[1, i] + 2.0 * K[2, i] + K[3, i])
    rhs(t + h, w.y_new, p, mode, K[6])
    w.counts[2] += 4


@hot
def step_error(method, K, h, y, y_new, rtol, atol, n_err):
    """Scaled error norm of the step in K by the method's embedded estimate (≤ 1: accept)."""
    if len(method) == DOP853:
        return dop853.dop853_error(K, h, y, y_new, rtol, atol, n_err)
    return error_norm(K, h, y, y_new, rtol, atol, n_err)


@hot
def end_row(method):
    """The row of StepWork.K that holds f at the end of the step."""
    return dop853.N_STAGES if len(method) == DOP853 else N_STAGES - 1


@hot
def prepare_dense(rhs, method, t, y, h, p, mode, w):
    """Make the dense output of the step in w readable: DOP853 needs three more
    stages (once per step, only for steps whose interior is read)."""
    if len(method) == DOP853 and w.ctrl[CTRL_DENSE] != 1.0:
        first, last = dop853.N_STAGES + 1, dop853.N_STAGES_EXTENDED - 1
        rk_stages(rhs, t, y, h, p, mode, w, dop853.A, dop853.C, first, last, False)
        dop853.dop853_dense_coefficients(y, w.y_new, h, w.K, w.F)
        w.ctrl[CTRL_DENSE] = 1.0


@hot
def dense_eval(method, w, y, y_new, h, theta, n, out):
    """First n components of the state at t + θh (0 ≤ θ ≤ 1) from the last step
    (DOP853: after prepare_dense)."""
    K = w.K
    if len(method) == DOP853:
        dop853.dop853_dense_eval(w.F, y, theta, n, out)
    elif len(method) == DP54:
        dopri5_dense_eval(K, y, h, theta, n, out)
    else:
        # cubic Hermite through (y, f) at both ends
        t2 = theta * theta
        t3 = t2 * theta
        h00 = 2.0 * t3 - 3.0 * t2 + 1.0
        h10 = t3 - 2.0 * t2 + theta
        h01 = -2.0 * t3 + 3.0 * t2
        h11 = t3 - t2
        for i in range(n):
            out[i] = h00 * y[i] + h10 * h * K[0, i] + h01 * y_new[i] + h11 * h * K[6, i]


@hot
def event_value(rhs, events, step, which, theta):
    """Event function ``which`` at θ on the dense output of the trial step."""
    w = step.w
    prepare_dense(rhs, step.method, step.t, step.y, step.h, step.p, step.mode, w)
    dense_eval(step.method, w, step.y, w.y_new, step.h, theta, step.n_err, w.y_stage)
    events(step.t + theta * step.h, w.y_stage, w.K[0], step.p, step.mode, w.g_tmp, w.dg_tmp)
    return w.g_tmp[which]


@hot
def locate_event(rhs, events, step, which, bracket):
    """Root of event ``which`` inside the bracket, to step.theta_tol.

    Illinois variant of regula falsi on the dense output. Returns the final
    bracket (lo, hi); a step ended at hi has g ≤ 0, so the next mode's own event
    function starts at ≥ 0.
    """
    a, fa, b, fb = bracket
    side = 0
    for _ in range(LOCATE_MAX_ITER):
        if b - a <= step.theta_tol:
            break
        m = (a * fb - b * fa) / (fb - fa)
        if not (a < m < b):
            m = 0.5 * (a + b)
        fm = event_value(rhs, events, step, which, m)
        if fm > 0.0:
            a, fa = m, fm
            if side == -1:
                fb *= 0.5
            side = -1
        else:
            b, fb = m, fm
            if side == 1:
                fa *= 0.5
            side = 1
    return a, b


@hot
def dense_minimum(rhs, events, step, which, guess):
    """Minimum of event ``which`` over the step on the dense output (golden section).

    Searches the half of the step around the cubic model's minimum ``guess``;
    returns (θ, value).
    """
    a = max(0.0, guess - 0.25)
    b = min(1.0, guess + 0.25)
    c = b - GOLDEN * (b - a)
    d = a + GOLDEN * (b - a)
    fc = event_value(rhs, events, step, which, c)
    fd = event_value(rhs, events, step, which, d)
    for _ in range(DIP_ITER):
        if fc <= 0.0 or fd <= 0.0:
            break
        if fc < fd:
            b, d, fd = d, c, fc
            c = b - GOLDEN * (b - a)
            fc = event_value(rhs, events, step, which, c)
        else:
            a, c, fc = c, d, fd
            d = a + GOLDEN * (b - a)
            fd = event_value(rhs, events, step, which, d)
    if fc <= fd:
        return c, fc
    return d, fd


@hot
def first_crossing(rhs, events, step, m):
    """Earliest event root in the trial step, from g and g' at both step ends.

    Reads the first m event functions' values and rates at the start (w.g0,
    w.dg0) and at the end (w.g1, w.dg1). Returns (event index or -1, θ of the
    root). A g on its surface at the start (≤ 0, or rising from within one event
    tolerance of 0, as just after a mode switch) has its root bracketed from its
    peak inside the step, not from the start.
    """
    w = step.w
    h = step.h
    first = -1
    first_theta = 2.0
    for i in range(m):
        g0 = w.g0[i]
        g1 = w.g1[i]
        d0 = w.dg0[i] * h
        d1 = w.dg1[i] * h
        a = 0.0
        fa = g0
        b = -1.0
        fb = 0.0
        # on the surface: g is ≤ 0, or rises from within one event tolerance of 0 (the
        # mode was just entered across it). There g's rounding (~1e-16 for ε = yc − y)
        # can exceed g itself, and a root found between the start and the first
        # dense-output points is noise: it ends the step at once, the mode switches
        # back, and the two modes swap at one instant for ever (a detachment where
        # 1 + c ε' ≈ 0 did). The step's next crossing lies beyond g's peak.
        surface = g0 <= 0.0 or (d0 > 0.0 and g0 <= d0 * step.theta_tol)
        if g1 <= 0.0:
            b = 1.0
            fb = g1
            if surface:
                # the mode holds only inside the step, if at all: bracket from its peak
                fa = 0.0
                th, _ = hermite_extremum(g0, d0, g1, d1, MAXIMUM)
                if th > 0.0:
                    gm = event_value(rhs, events, step, i, th)
                    if gm > 0.0:
                        a = th
                        fa = gm
                if fa <= 0.0:  # never inside: the event is at the step start
                    if first_theta > 0.0:
                        first = i
                        first_theta = 0.0
                    continue
        else:
            # both ends positive: a dip below zero needs min(g0, g1) < 4/27 (|d0| + |d1|),
            # the largest excursion of a cubic Hermite basis beyond its end values
            if min(g0, g1) > HERMITE_BOUND * (abs(d0) + abs(d1)):
                continue
            th, val = hermite_extremum(g0, d0, g1, d1, MINIMUM)
            if th <= 0.0 or val > DIP_MARGIN * min(g0, g1):
                continue
            # a shallow dip (a grazing contact or detachment) can reach zero between
            # the cubic's values: find the minimum on the dense output itself
            th, gm = dense_minimum(rhs, events, step, i, th)
            if gm > 0.0:
                continue
            b = th
            fb = gm
            if surface:
                continue
        if a >= first_theta:
            continue
        _, hi = locate_event(rhs, events, step, i, Bracket(a, fa, b, fb))
        if hi < first_theta:
            first = i
            first_theta = hi
    return first, first_theta


@hot
def take_step(rhs, method, t, y, f, h, p, mode, w):
    if len(method) == DP54:
        rk_step(rhs, t, y, f, h, p, mode, w, A, C, N_STAGES - 1)
    elif len(method) == DOP853:
        rk_step(rhs, t, y, f, h, p, mode, w, dop853.A, dop853.C, dop853.N_STAGES)
    else:
        rk4_step(rhs, t, y, f, h, p, mode, w)
    w.ctrl[CTRL_DENSE] = 0.0  # K holds a new step


@hot
def all_finite(x):
    for i in range(x.shape[0]):
        if not np.isfinite(x[i]):
            return False
    return True


@hot
def advance(rhs, events, t, t_end, y, f, p, mode, opt, w):
    """One accepted step from t toward the breakpoint t_end, ending at the first event.

    y and f (= rhs(t, y)) are updated in place. Returns (status, t_new, event):
    event is the index of the event function whose root ends the step, or -1.
    An event at the very start returns t_new = t with y unchanged.

    The event values at the start are reused from the previous step's end when
    that step ended at this t in this mode without an event: the caller must
    not change y or f between two such calls.
    """
    n = y.shape[0]
    ctrl = w.ctrl
    adaptive = len(opt.method) != RK4
    fresh = not (
        t == ctrl[CTRL_G1_T] and mode[0] == ctrl[CTRL_G1_MODE0] and mode[1] == ctrl[CTRL_G1_MODE1]
    )  # the first step since the discrete state was entered (or since a step ended early)
    if fresh:
        m = events(t, y, f, p, mode, w.g0, w.dg0)
        remembered = entry_steps.recall(w.h_memory, mode)
        if adaptive and remembered > 0.0:
            ctrl[CTRL_H] = remembered
    else:
        m = int(ctrl[CTRL_G1_M])
        for i in range(m):
            w.g0[i] = w.g1[i]
            w.dg0[i] = w.dg1[i]
    ctrl[CTRL_G1_T] = np.nan
    rejects = 0
    end = end_row(opt.method)
    # DOP853: an I controller on err^(1/8) (β = 0); DP5(4): the PI controller
    exponent, beta = (
        (ERROR_EXPONENT_853, 0.0) if len(opt.method) == DOP853 else (ERROR_EXPONENT, PI_BETA)
    )
    if fresh:
        reject_exponent = -entry_steps.ENTRY_ERROR_EXPONENT
    elif len(opt.method) == DOP853:
        reject_exponent = -ERROR_EXPONENT_853
    else:
        reject_exponent = -0.2
    while True:
        remaining = t_end - t
        h = ctrl[CTRL_H] if adaptive else opt.h_fixed
        if h >= remaining * (1.0 - STRETCH):
            h = remaining
        if h < opt.h_min and h < remaining:
            return STEP_UNDERFLOW, t, -1
        take_step(rhs, opt.method, t, y, f, h, p, mode, w)
        err = 0.0
        if adaptive:
            err = step_error(opt.method, w.K, h, y, w.y_new, opt.rtol, opt.atol, opt.n_err)
            if not err <= 1.0:  # also catches NaN
                rejects += 1
                w.counts[1] += 1
                if rejects > MAX_REJECTS:
                    if not all_finite(w.y_new):
                        return NONFINITE, t, -1
                    return STEP_UNDERFLOW, t, -1
                fac = SAFETY * err**reject_exponent if np.isfinite(err) else MIN_FACTOR
                ctrl[CTRL_H] = h * max(MIN_FACTOR, min(1.0, fac))
                continue
        elif not all_finite(w.y_new):
            return NONFINITE, t, -1
        t_new = t_end if h == remaining else t + h
        events(t_new, w.y_new, w.K[end], p, mode, w.g1, w.dg1)
        step = TrialStep(
            method=opt.method,
            t=t,
            y=y,
            h=h,
            p=p,
            mode=mode,
            w=w,
            n_err=opt.n_err,
            theta_tol=opt.event_tol / h,
        )
        which, theta = first_crossing(rhs, events, step, m)
        if which >= 0 and theta < 1.0:
            if theta * h <= opt.event_tol:
                return OK, t, which
            # redo the step to end on the root: the field stays smooth inside it
            h_event = theta * h
            take_step(rhs, opt.method, t, y, f, h_event, p, mode, w)
            if adaptive:
                err_event = step_error(
                    opt.method, w.K, h_event, y, w.y_new, opt.rtol, opt.atol, opt.n_err
                )
                if not err_event <= 1.0:
                    rejects += 1
                    w.counts[1] += 1
                    ctrl[CTRL_H] = h_event * 0.5
                    continue
            t_new = t + h_event
        else:
            if adaptive and fresh and h < remaining:
                entry_steps.remember(w.h_memory, mode, h, err)
            if adaptive:
                # PI control of the next step from this accepted step's error
                # err^ERROR_EXPONENT / err_prev^PI_BETA as one exp of logs: two powers
                # per step were 7 % of a map's time (perf), exp and log cost half
                log_err = math.log(max(err, 1e-10))
                fac = math.exp(exponent * log_err - beta * ctrl[CTRL_ERR]) / SAFETY
                fac = max(1.0 / MAX_FACTOR, min(1.0 / MIN_FACTOR, fac))
                ctrl[CTRL_H] = h / fac
                ctrl[CTRL_ERR] = max(log_err, LOG_ERR_FLOOR)
            if which < 0:  # g1 holds the event values at t_new: reusable next step
                ctrl[CTRL_G1_T] = t_new
                ctrl[CTRL_G1_MODE0] = mode[0]
                ctrl[CTRL_G1_MODE1] = mode[1]
                ctrl[CTRL_G1_M] = m
        for i in range(n):
            w.y_old[i] = y[i]
            y[i] = w.y_new[i]
            f[i] = w.K[end, i]
        w.counts[0] += 1
        return OK, t_new, which


@hot
def initial_step(rhs, t, y, f, p, mode, rtol, atol, n_err, h_max):
    """Starting step size (Hairer, Nørsett & Wanner, II.4), capped at h_max."""
    d0 = 0.0
    d1 = 0.0
    for i in range(n_err):
        scale = atol + rtol * abs(y[i])
        d0 += (y[i] / scale) ** 2
        d1 += (f[i] / scale) ** 2
    d0 = np.sqrt(d0 / n_err)
    d1 = np.sqrt(d1 / n_err)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    return min(h0, h_max)
