"""Extremes of ε and Pn inside a step, located on the integrator's dense output.

A revolution folds every step into its statistics (analysis.add_step_stats): ε and Pn
at both ends, and their extremes inside the step. Hermite models from the values and
rates at the step's ends tell whether the step holds an interior extremum and roughly
where (ε: the quintic through ε, ε', ε''; Pn: the cubic through Pn, Pn'). The extremum
itself is then the root of the time derivative on the step's dense output, with the cam
law's exact S, S′, S″ (model.cam): dε/dt = ω S′(ωt) − y′(t) by safeguarded Newton (its
derivative ω² S″ − y″ is exact too), dPn/dt by the Illinois method. A free flight
across a cycloidal fall is one long DOP853 step, over which ε = S(ωt) − y(t) is no
quintic at all while y(t) is as accurate as the integration: the models alone left
min ε up to 7e-3 too shallow there.

Where the ends do not bracket the root (the model sees two extrema in one step), Newton
runs from the model's place and its result is kept only if it converges inside the step
to an extremum of the right kind; else the model's value stands.
"""

import math

import numpy as np

from .hermite import MAXIMUM, MINIMUM, hermite_extremum, quintic_extremum
from .jit import hot
from .model import N_STATE, PUSH, cam, damping, force_and_rate, pushing
from .stages import dense_eval, prepare_dense

EXTREMUM_ITER = 16  # Newton or Illinois iterations at most
# Located to this fraction of the step: the value's error is ~ ε'' (h δθ)², far below
# the integration's own.
THETA_TOL = 1e-9
# Pn's peak to this fraction of the step: Pn's relative error ~ (δθ)² Pn'' h² / Pn, below
# 1e-8 for the short steps of a contact, and Illinois needs far fewer evaluations
PEAK_THETA_TOL = 1e-4
WANTED = np.bool_(True)  # (not a literal True: numba would compile a variant per value)


@hot
def dense_kinematics(rhs, method, w, t0, h, theta, p, mode, want_force):
    """model.kinematics (ε, dε/dt, d²ε/dt², Pn, dPn/dt) at t0 + θh on the dense output of
    the step just accepted from t0 (w.y_old → w.y_new; stages.prepare_dense done); Pn
    and its rate 0 unless ``want_force``.

    One body with one cam evaluation, the arithmetic of model.acceleration and
    model.kinematics term for term (the same numbers): as separate calls (numba inlines
    none) they evaluated the cam twice, the search's main cost."""
    dense_eval(method, w, w.y_old, w.y_new, h, theta, N_STATE, w.y_stage)
    t = t0 + theta * h
    y = w.y_stage[0]
    v = w.y_stage[1]
    yc, dyc, d2yc = cam(p.omega * t, mode[0], p.cam)
    acc = -2.0 * p.zeta * v - y - p.f0
    eps = yc - y
    if mode[1] == PUSH:
        deps = p.vcam * dyc - v
        pen = eps
        if pen < 0.0:  # a point just past an event: extend by zero force
            pen = 0.0
        force, _, _ = pushing(p.contact, p.k, damping(p.contact, p.c), pen, deps)
        acc += force
    rate = p.omega * dyc - v
    accel = p.omega * p.omega * d2yc - acc
    if not want_force or mode[1] != PUSH or eps <= 0.0:
        return eps, rate, accel, 0.0, 0.0
    deps = p.vcam * dyc - v  # the force law's ε'
    d2eps = p.vcam * p.omega * d2yc - acc
    pn, dpn = force_and_rate(p.contact, p.k, damping(p.contact, p.c), eps, deps, rate, d2eps)
    return eps, rate, accel, pn, dpn


@hot
def eps_extremum(rhs, method, w, t0, h, p, mode, guess, de0, de1, want_min):
    """(θ, ε) of ε's interior minimum (want_min) or maximum on the step's dense output,
    from the model's place ``guess``; θ = -1 when Newton leaves the step unbracketed."""
    prepare_dense(rhs, method, t0, w.y_old[:N_STATE], h, p, mode, w)
    sign = 1.0 if want_min else -1.0  # sign · dε/dt rises through 0 at the extremum
    a = 0.0
    b = 1.0
    bracketed = sign * de0 < 0.0 < sign * de1
    theta = guess
    for _ in range(EXTREMUM_ITER):
        eps, rate, accel, _, _ = dense_kinematics(rhs, method, w, t0, h, theta, p, mode, False)
        if bracketed:
            if sign * rate < 0.0:
                a = theta
            else:
                b = theta
        if sign * accel > 0.0:
            step = rate / (accel * h)
            nxt = theta - step
        else:
            step = 1.0
            nxt = -1.0
        if bracketed:
            if not a < nxt < b:
                nxt = 0.5 * (a + b)
                step = theta - nxt
        elif not 0.0 < nxt < 1.0:
            return -1.0, 0.0
        if abs(step) < THETA_TOL or (bracketed and b - a < THETA_TOL):
            return theta, eps  # ε at theta is off by ~ ε'' (h step)² / 2: negligible
        theta = nxt
    eps, _, _, _, _ = dense_kinematics(rhs, method, w, t0, h, theta, p, mode, False)
    return theta, eps


@hot
def force_peak(rhs, method, w, t0, h, p, mode, guess):
    """Largest Pn inside a step whose end rates bracket dPn/dt's fall through 0, on the
    dense output (Illinois to PEAK_THETA_TOL, first probe at the cubic model's place
    ``guess``)."""
    prepare_dense(rhs, method, t0, w.y_old[:N_STATE], h, p, mode, w)
    a = 0.0
    b = 1.0
    fa = 1.0  # signs only: dPn/dt > 0 at a, < 0 at b
    fb = -1.0
    theta = guess
    best = 0.0
    side = 0
    for _ in range(EXTREMUM_ITER):
        _, _, _, pn, dpn = dense_kinematics(rhs, method, w, t0, h, theta, p, mode, True)
        best = max(best, pn)
        if dpn > 0.0:
            a, fa = theta, dpn
            if side == -1:
                fb *= 0.5
            side = -1
        else:
            b, fb = theta, dpn
            if side == 1:
                fa *= 0.5
            side = 1
        if b - a < PEAK_THETA_TOL:
            break
        theta = (a * fb - b * fa) / (fb - fa)
        if not a < theta < b:
            theta = 0.5 * (a + b)
    return best


@hot
def step_models(h, mode, k0, k1, extremes):
    """(reads, pn_hi): whether step_extremes reads the step's dense output (the models see
    an interior extremum of ε, or a peak of Pn the end rates bracket), and where it does
    not, the largest Pn step_extremes returns (its ε has no interior extremum then).
    k0, k1: model.contact_kinematics at the step's ends. Without ``extremes`` only ε's
    minima are looked for (step_extremes's). Cheap, for every step: step_extremes is
    called only where ``reads``."""
    e0, de0, _, pn0, dpn0 = k0
    e1, de1, _, pn1, dpn1 = k1
    # step_extremes finds a minimum exactly where this cubic has one (quintic_extremum
    # starts from the cubic's)
    if hermite_extremum(e0, de0 * h, e1, de1 * h, MINIMUM)[0] > 0.0:
        return True, 0.0
    if not extremes:
        return False, 0.0
    if hermite_extremum(e0, de0 * h, e1, de1 * h, MAXIMUM)[0] > 0.0:
        return True, 0.0
    pn_hi = max(pn0, pn1)
    if mode[1] == PUSH:
        th, val = hermite_extremum(pn0, dpn0 * h, pn1, dpn1 * h, MAXIMUM)
        if th > 0.0:
            if dpn0 > 0.0 > dpn1:
                return True, 0.0
            pn_hi = max(pn_hi, val)
    return False, pn_hi


@hot
def step_extremes(rhs, method, w, t0, h, p, mode, k0, k1, extremes):
    """ε's interior minimum and maximum (NaN: none) and Pn's largest value over the step
    just accepted from t0 (size h), from the values and rates at its ends (k0, k1:
    model.contact_kinematics, ε with two rates and Pn with one) and its dense output.
    Without ``extremes``, ε's minimum alone (the maximum NaN, Pn the ends' larger)."""
    return refine_extremes(rhs, method, w, t0, h, p, mode, k0, k1, WANTED, extremes, extremes)


@hot
def refine_extremes(rhs, method, w, t0, h, p, mode, k0, k1, want_dip, want_peak, want_pn):
    """step_extremes for the quantities wanted alone: ε's interior minimum (``want_dip``),
    maximum (``want_peak``) and Pn's interior peak (``want_pn``); one not wanted is NaN
    (Pn: the ends' larger). Each wanted one is the number step_extremes gives."""
    _, _, _, pn0, dpn0 = k0
    _, _, _, pn1, dpn1 = k1
    dip = math.nan
    peak = math.nan
    if want_dip:
        dip = eps_extreme(rhs, method, w, t0, h, p, mode, k0, k1, MINIMUM)
    pn_hi = max(pn0, pn1)
    if want_peak:
        peak = eps_extreme(rhs, method, w, t0, h, p, mode, k0, k1, MAXIMUM)
    if want_pn and mode[1] == PUSH:
        th, val = hermite_extremum(pn0, dpn0 * h, pn1, dpn1 * h, MAXIMUM)
        if th > 0.0:
            if dpn0 > 0.0 > dpn1:
                val = force_peak(rhs, method, w, t0, h, p, mode, th)
            pn_hi = max(pn_hi, val)
    return dip, peak, pn_hi


@hot
def eps_extreme(rhs, method, w, t0, h, p, mode, k0, k1, want_min):
    """ε's interior minimum (want_min) or maximum over the step: where the quintic model
    has one, located on the dense output (eps_extremum), or the model's value where Newton
    leaves the step; NaN where the model has none."""
    e0, de0, dde0, _, _ = k0
    e1, de1, dde1, _, _ = k1
    h2 = h * h
    th, val = quintic_extremum(e0, de0 * h, dde0 * h2, e1, de1 * h, dde1 * h2, want_min)
    if not th > 0.0:
        return math.nan
    th, refined = eps_extremum(rhs, method, w, t0, h, p, mode, th, de0, de1, want_min)
    return refined if th > 0.0 else val


@hot
def step_model_extremes(h, mode, k0, k1, extremes):
    """What step_extremes would start from, without the dense output: the models' ε
    minimum and maximum (the quintic's), and Pn's largest value with the cubic's interior
    peak; NaN where the models see no interior extremum (the maximum and Pn also without
    ``extremes``). Pn's is step_extremes's own number where its end rates do not bracket
    the peak."""
    e0, de0, dde0, pn0, dpn0 = k0
    e1, de1, dde1, pn1, dpn1 = k1
    h2 = h * h
    dip = math.nan
    peak = math.nan
    pn_hi = math.nan
    th, val = quintic_extremum(e0, de0 * h, dde0 * h2, e1, de1 * h, dde1 * h2, MINIMUM)
    if th > 0.0:
        dip = val
    if not extremes:
        return dip, peak, pn_hi
    th, val = quintic_extremum(e0, de0 * h, dde0 * h2, e1, de1 * h, dde1 * h2, MAXIMUM)
    if th > 0.0:
        peak = val
    if mode[1] == PUSH:
        th, val = hermite_extremum(pn0, dpn0 * h, pn1, dpn1 * h, MAXIMUM)
        if th > 0.0:
            pn_hi = max(max(pn0, pn1), val)
    return dip, peak, pn_hi
