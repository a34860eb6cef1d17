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
root of an event function, so every step integrates a smooth field: the steps are
campar.core.stages', the roots campar.core.event_roots'.
"""

import math
from typing import NamedTuple

import numpy as np

from . import dop853, entry_steps
from .codes import NONFINITE, OK, STEP_UNDERFLOW
from .event_roots import TrialStep, first_crossing
from .jit import entry, hot
from .stages import DOP853, RK4, end_row, step_error, take_step

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

# Slots of StepWork.ctrl, the step-control state one step hands to the next.
CTRL_H = 0  # proposed size of the next step
CTRL_ERR = 1  # log of the last accepted step's error norm (the PI controller's memory)
CTRL_G1_T = 2  # time of the event values in g1, dg1 the next step may reuse (NaN: none)
CTRL_G1_MODE0 = 3  # the mode (mode[0], mode[1]) they belong to
CTRL_G1_MODE1 = 4
CTRL_G1_M = 5  # how many event functions they hold
# slot 6: CTRL_DENSE (campar.core.stages), 1 when the step's dense output is ready
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


@hot
def all_finite(x):
    for i in range(x.shape[0]):
        if not np.isfinite(x[i]):
            return False
    return True


@hot
def advance(rhs, events, curvature, t, t_end, y, f, p, mode, opt, w):
    """One accepted step from t toward the breakpoint t_end, ending at the first event.

    y and f (= rhs(t, y)) are updated in place. Returns (status, t_new, event):
    event is the index of the event function whose root ends the step, or -1.
    An event at the very start returns t_new = t with y unchanged. ``curvature(y, p,
    mode)`` bounds |g0''| over any step from y in this mode (inf: no bound).

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
    g0_curvature = curvature(y, p, mode)
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
            curvature=g0_curvature,
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
