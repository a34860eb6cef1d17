"""A cell's transient: revolutions until its motion is known, under the job's policy.

``transient_converged`` runs revolutions with the variational equations until the
section map has converged to a cycle (Newton-accelerated; campar.core.analysis), a
non-periodic verdict is sure, or the budget ends; ``transient_fixed`` is the paper's
recipe: a fixed number of plain revolutions, then a read window. Both write into the
chain's buffers (campar.core.kernel.ChainWork) and are inlined into the chain.
"""

import math

import numpy as np

from .analysis import (
    REV_LOG_STRETCH,
    SETTLED_DISTANCE,
    assess_revolution,
    cycle_jacobian,
    exponent_bounds,
    exponent_window,
    newton_fixed_point,
    real_dominant_direction,
    repeat_period,
    section_gap,
    spectral_radius,
    stable_cycle_nearby,
    stretch_tangent,
    unstable_cycle_nearby,
)
from .codes import NONFINITE, OK
from .integrator import CTRL_ERR, CTRL_H, SolverOptions, copy_step_control
from .jit import inlined
from .model import N_STATE_VARIATIONAL
from .revolution_call import call_revolution

# Transient policies.
CONVERGED = 0  # stop once the section has converged to a cycle (Newton-accelerated)
FIXED = 1  # a fixed number of revolutions, then a read window (the paper's recipe)

# Newton iterations on Pⁿ at the budget's end at most (settle_at_budget): from a start
# within jump_cap, a few reach conv_tol where they can; more only repeat the noise.
SETTLE_ITERATIONS = 8


@inlined
def step_revolution(cw, k, variational, p, opt, cs, stats, step_budget):
    """Revolution k+1 from xs[k]: fills xs[k+1], jac[k] (if variational), revs[k]."""
    if variational:
        x, f, w = cw.x6, cw.f6, cw.w6
    else:
        x, f, w = cw.x2, cw.f2, cw.w2
    x[0] = cw.xs[k, 0]
    x[1] = cw.xs[k, 1]
    limit = w.counts[0] + w.counts[1] + (step_budget - spend(cw))
    status = call_revolution(
        cw.revolution, x, f, p, opt, w, cw.mode, cw.revs[k], stats, limit, None
    )
    if status != OK:
        return status
    if not (math.isfinite(x[0]) and math.isfinite(x[1])):
        return NONFINITE
    cw.xs[k + 1, 0] = x[0]
    cw.xs[k + 1, 1] = x[1]
    if variational:
        for j in range(4):
            cw.jac[k, j] = x[2 + j]
        cw.revs[k, REV_LOG_STRETCH] = stretch_tangent(cw.jac[k], cw.u)
    return OK


@inlined
def spend(cw):
    return cw.w2.counts[0] + cw.w2.counts[1] + cw.w6.counts[0] + cw.w6.counts[1]


@inlined
def share_step_size(src, dst):
    dst.ctrl[CTRL_H] = src.ctrl[CTRL_H]
    dst.ctrl[CTRL_ERR] = src.ctrl[CTRL_ERR]


@inlined
def transient_converged(cw, p, opt, cs, stats, step_budget):
    """Revolutions until assess_revolution accepts a cycle or the budget ends.

    From revolution cs.chaos_after on (0: never), a motion whose largest Lyapunov
    exponent since the last restart exceeds cs.chaos_lyapunov per revolution at the
    confidence of cs.chaos_z is declared chaotic at once (nonperiodic_verdict): near a
    stable cycle every revolution contracts the tangent, so a sure positive exponent
    rules out that the motion was near one in the window, and a motion that stretches
    that steadily rarely finds one later. From revolution cs.quasiperiodic_after on (0:
    never), a motion whose exponent lies within ±lyap_tol at that confidence over a
    whole read window, as on an invariant circle, is declared quasi-periodic. Both
    verdicts trade a few cells on long transients for revolutions (measured by
    `campar bench revolutions` and by adjudicating the cells they change).

    A motion that lingers at an unstable cycle (analysis.unstable_cycle_nearby: next to
    a period doubling its multiplier is near −1 and the escape takes hundreds of
    revolutions, which the window reads as a torus or as chaos) is moved off it along
    its unstable direction by cs.jump_cap, on the side it was drifting to; Newton jumps
    back to that cycle are refused from then on. A budget that ends without a verdict
    ends with Newton's method on the section map (settle_at_budget). Returns (status, k,
    period, base, jumps, escapes, settled).
    """
    k = 0
    base = np.int64(0)  # not a literal: numba would compile assess_revolution twice
    jumps = 0
    escapes = 0
    sighted = -cs.chaos_clear  # the last revolution with a stable cycle in sight
    avoid0 = math.nan  # the cycle the motion escaped from (jumps to it are refused)
    avoid1 = math.nan
    for a in range(cw.est.shape[0]):  # no estimates of this cell yet
        for b in range(cw.est.shape[1]):
            cw.est[a, b, 0] = -1.0
    while k < cs.max_revolutions:
        status = step_revolution(cw, k, True, p, opt, cs, stats, step_budget)
        if status != OK:
            return status, k, 0, base, jumps, escapes, False
        k += 1
        period, jump_n, z0, z1 = assess_revolution(
            cw.xs,
            cw.jac,
            cw.est,
            k,
            base,
            cs.n_max,
            cs.conv_tol,
            cs.window_tol,
            cs.jump_residual,
            cs.jump_cap,
            cs.jump_agree,
        )
        if period > 0:
            return OK, k, period, base, jumps, escapes, False
        if cs.chaos_sight > 0.0 and stable_cycle_nearby(
            cw.xs, cw.jac, k, base, cs.n_max, cs.chaos_sight
        ):
            sighted = k
        if nonperiodic_verdict(cw, k, base, sighted, cs):
            return OK, k, 0, base, jumps, escapes, False
        if not cs.newton or jumps >= cs.max_jumps:
            continue
        if jump_n > 0 and not max(abs(z0 - avoid0), abs(z1 - avoid1)) <= cs.jump_residual:
            cw.xs[k, 0] = z0
            cw.xs[k, 1] = z1
            base = k
            jumps += 1
            continue
        esc_n, z0, z1, v0, v1 = unstable_cycle_nearby(
            cw.xs, cw.jac, k, base, cs.n_max, cs.jump_residual
        )
        if esc_n > 0:
            side = (cw.xs[k, 0] - z0) * v0 + (cw.xs[k, 1] - z1) * v1
            sign = 1.0 if side >= 0.0 else -1.0
            cw.xs[k, 0] = z0 + sign * cs.jump_cap * v0
            cw.xs[k, 1] = z1 + sign * cs.jump_cap * v1
            avoid0 = z0
            avoid1 = z1
            base = k
            jumps += 1
            escapes += 1
    if not cs.newton:
        return OK, k, 0, base, jumps, escapes, False
    k, period, base, settled, iterations = settle_at_budget(
        cw, k, base, p, opt, cs, stats, step_budget
    )
    return OK, k, period, base, jumps + iterations, escapes, settled


# Newton's outcomes on Pⁿ (newton_on_period)
NO_CYCLE = 0
STABLE_CYCLE = 1  # converged as assess_revolution converges
SETTLED_CYCLE = 2  # within SETTLED_DISTANCE after SETTLE_ITERATIONS
UNSTABLE_CYCLE = 3  # either, to a fixed point of Pⁿ that is not stable

# Starts off an unstable cycle along its flip direction (flip_starts): at the
# motion's distance from it, then twice, four and eight times that.
FLIP_STARTS = 4
# settle_at_budget's second try: the job's tolerances times this (DOP853's steps grow by
# about 1/PRECISE_FACTOR^(1/8), 2.4 times at 1e-3), the variational part's error
# controlled too: at the (ω, μkn) tongue's cell (77, 507) at 600² DP² then has SciPy's
# multiplier 0.9999917 (rtol 1e-12) to 1e-8, where the job's tolerance left it anywhere
# in 0.9992 … 1.00017 (benchmarks/RESULTS.md, Kernel 8).
PRECISE_FACTOR = 1e-3


@inlined
def newton_on_period(cw, k, n, base, from_start, p, opt, cs, stats, step_budget):
    """Newton's method on Pⁿ from section point k. ``from_start``: xs[k] is a start, from
    which n revolutions are integrated with the variational equations first; else the n
    revolutions before k are the transient's path, whose Jacobian is not the cycle's (its
    first estimate is not judged). Each iteration jumps to the estimate from DPⁿ over the
    last n revolutions and integrates n revolutions from it, SETTLE_ITERATIONS at most.
    Returns (outcome, k, base, iterations, z0, z1, m): the last estimate z and DPⁿ; at
    UNSTABLE_CYCLE, z is the fixed point and m its DPⁿ."""
    rows = cw.jac.shape[0]
    iterations = 1 if from_start else 0
    z0 = cw.xs[k, 0]
    z1 = cw.xs[k, 1]
    m = (1.0, 0.0, 0.0, 1.0)
    run = from_start
    while True:
        if not run:
            m = cycle_jacobian(cw.jac, k, n)
            z0, z1, dist_now, dist_then = newton_fixed_point(
                cw.xs[k, 0], cw.xs[k, 1], cw.xs[k - n, 0], cw.xs[k - n, 1], m
            )
            if iterations > 0:
                stable = spectral_radius(m) < 1.0
                found = STABLE_CYCLE if stable else UNSTABLE_CYCLE
                if dist_now <= cs.conv_tol and dist_then <= cs.window_tol:
                    return found, k, base, iterations, z0, z1, m
                if (
                    iterations >= SETTLE_ITERATIONS
                    and dist_now <= SETTLED_DISTANCE
                    and dist_then <= SETTLED_DISTANCE
                ):
                    found = SETTLED_CYCLE if stable else UNSTABLE_CYCLE
                    return found, k, base, iterations, z0, z1, m
            if iterations >= SETTLE_ITERATIONS or not dist_now <= cs.jump_cap:
                return NO_CYCLE, k, base, iterations, z0, z1, m
            cw.xs[k, 0] = z0
            cw.xs[k, 1] = z1
            iterations += 1
        run = False
        if k + n > rows:
            return NO_CYCLE, k, base, iterations, z0, z1, m
        base = k
        for _ in range(n):
            if step_revolution(cw, k, True, p, opt, cs, stats, step_budget) != OK:
                return NO_CYCLE, k, base, iterations, z0, z1, m
            k += 1


@inlined
def settle_at_budget(cw, k, base, p, opt, cs, stats, step_budget):
    """Newton's method on Pⁿ from where the budget left a motion without a verdict:
    (k, period, base, settled, iterations).

    Where the motion returns within jump_residual every n revolutions (the smallest such
    n since the last restart) and the Newton estimate lies within jump_cap, each iteration
    jumps to the estimate and integrates n revolutions with the variational equations,
    so the next estimate comes from DPⁿ at the iterate itself (newton_on_period). In the
    transient the estimate comes from the Jacobian along the path, off by the path's
    distance from the cycle: next to a period doubling (a multiplier of P² near 1) that
    decides whether the cycle looks stable, and the motion creeps for thousands of
    revolutions. period > 0: a cycle stable by its own multipliers, converged as
    assess_revolution converges (settled False), or after SETTLE_ITERATIONS with its
    estimate and last step within SETTLED_DISTANCE (settled True: the integration's
    noise, amplified by 1/(1 − μ), keeps Newton from conv_tol).

    Past a period doubling Newton converges as readily to the cycle that doubled, now
    unstable, as to the stable cycle of twice its period about it: both are fixed points
    of P²ⁿ. Where Newton converged to such a cycle (flip_starts), it starts again off it
    along its flip direction, on the doubled period, at FLIP_STARTS distances; a stable
    cycle SETTLED_DISTANCE or more from it is the one (its revolutions count the start
    that reached it, not the starts before; the steps count all).

    Where neither finds a cycle, all of it is tried once more at the precise tolerance
    (precise_options), from the budget's end: the job's tolerance controls the error of
    (y, y') alone, and DPⁿ from the variational equations is good to ~1e-4 there, too
    coarse where a multiplier lies within that of ±1 to tell which cycle is stable.
    period 0: no cycle either time; the budget's end is restored (k, its section point,
    base and the step control): the cell and the cells after it are as they were without
    the search, but for the revolutions it tried, which stay in the step count. A
    revolution that fails ends that try.
    """
    n = 0
    for d in range(1, min(cs.n_max, k - base) + 1):
        if section_gap(cw.xs, k, k - d) <= cs.jump_residual:
            n = d
            break
    if n == 0:
        return k, 0, base, False, 0
    end = k
    end0 = cw.xs[k, 0]
    end1 = cw.xs[k, 1]
    end_base = base
    copy_step_control(cw.w6.ctrl, cw.w6.h_memory, cw.saved_ctrl, cw.saved_memory)
    iterations = 0
    precise = False  # the try: at the job's tolerance, then at the precise one
    flip = -1  # the start off a doubled cycle (-1: Newton from the motion itself)
    period = n
    first_row = k
    z0 = z1 = v0 = v1 = reach = 0.0
    while True:
        solver = precise_options(opt) if precise else opt
        from_start = flip >= 0 or precise  # else from the transient's path
        if from_start:
            k = first_row if flip >= 0 else end
            cw.xs[k, 0] = end0 if flip < 0 else z0 + reach * v0
            cw.xs[k, 1] = end1 if flip < 0 else z1 + reach * v1
        outcome, k, base, tried, c0, c1, m = newton_on_period(
            cw, k, period, base, from_start, p, solver, cs, stats, step_budget
        )
        iterations += tried
        distinct = flip < 0 or max(abs(c0 - z0), abs(c1 - z1)) > SETTLED_DISTANCE
        if outcome in (STABLE_CYCLE, SETTLED_CYCLE) and distinct:
            return k, period, base, outcome == SETTLED_CYCLE, iterations
        if flip < 0 and outcome == UNSTABLE_CYCLE:
            period, v0, v1, reach = flip_starts(cw, k, n, c0, c1, m, end0, end1, cs)
            if period > 0 and k + period * (SETTLE_ITERATIONS + 1) <= cw.jac.shape[0]:
                z0 = c0
                z1 = c1
                first_row = k
                flip = 0
                continue
        elif flip >= 0 and flip + 1 < FLIP_STARTS and 2.0 * abs(reach) <= cs.jump_cap:
            flip += 1
            reach *= 2.0
            continue
        if precise:
            break
        precise = True
        flip = -1
        period = n
    cw.xs[end, 0] = end0
    cw.xs[end, 1] = end1
    copy_step_control(cw.saved_ctrl, cw.saved_memory, cw.w6.ctrl, cw.w6.h_memory)
    return end, 0, end_base, False, 0


@inlined
def precise_options(opt):
    """The solver options of settle_at_budget's second try: tolerances PRECISE_FACTOR of
    the job's, and the error of the variational equations' Φ controlled besides (y, y')'s."""
    return SolverOptions(
        opt.method,
        opt.rtol * PRECISE_FACTOR,
        opt.atol * PRECISE_FACTOR,
        opt.h_fixed,
        opt.h_min,
        opt.event_tol,
        max(opt.n_err, N_STATE_VARIATIONAL),
    )


@inlined
def flip_starts(cw, k, n, z0, z1, m, end0, end1, cs):
    """Where Newton starts off z, a fixed point of Pⁿ (DPⁿ m) that is not stable, for the
    stable cycle born in its period doubling: (period, v0, v1, reach), the start z + reach
    v, then at twice, four and eight times reach; period 0: z is not such a cycle.

    Where z is unstable through a multiplier below −1 (of Pⁿ; or above 1 of Pⁿ on a cycle
    that repeats every n/2 revolutions: the same flip), the doubled cycle lies on either
    side of it along that multiplier's eigenvector v, at a distance Newton from z's side
    cannot reach: the start lies on the motion's side (end), at its distance from z,
    and Newton runs on P²ⁿ (or Pⁿ)."""
    flip, v0, v1 = real_dominant_direction(m)
    period = 0
    if flip < -1.0 and 2 * n <= cs.n_max:
        period = 2 * n
    elif flip > 1.0 and n % 2 == 0 and section_gap(cw.xs, k, k - n // 2) <= SETTLED_DISTANCE:
        period = n
    side = (end0 - z0) * v0 + (end1 - z1) * v1
    reach = max(abs(side), cs.conv_tol)
    if side < 0.0:
        reach = -reach
    return period, v0, v1, reach


@inlined
def nonperiodic_verdict(cw, k, base, sighted, cs):
    """True when the largest Lyapunov exponent since the last restart (at most a read
    window, analysis.exponent_window) settles a non-periodic verdict.

    Chaos: its estimate exceeds cs.chaos_lyapunov, its lower confidence bound
    (analysis.exponent_bounds at the normal quantile cs.chaos_z) exceeds lyap_tol — it
    is positive, beyond the band of an invariant circle —, and no stable cycle of period
    ≤ n_max has been in sight (analysis.stable_cycle_nearby within cs.chaos_sight, 0:
    not looked for; revolution ``sighted`` the last time) nor a Newton jump taken for
    cs.chaos_clear revolutions: a chaotic transient often shadows the long cycle it
    settles on, and there the jumps of assess_revolution reach it. Quasi-periodic: the exponent's
    interval lies within ±lyap_tol, over a whole read window.
    """
    chaos_due = 0 < cs.chaos_after <= k
    qp_due = 0 < cs.quasiperiodic_after <= k and k - base >= cs.window_revolutions
    if not (chaos_due or qp_due):
        return False
    first, count = exponent_window(k, base, cs.window_revolutions)
    mean, half = exponent_bounds(cw.revs, first, count, cs.chaos_z)
    if (
        chaos_due
        and mean > cs.chaos_lyapunov
        and mean - half > cs.lyap_tol
        and min(k - sighted, k - base) >= cs.chaos_clear
    ):
        return True
    return qp_due and abs(mean) + half <= cs.lyap_tol


@inlined
def transient_fixed(cw, p, opt, cs, stats, step_budget):
    """cs.max_revolutions plain revolutions, then a window with variational equations.

    Returns (status, k, period) with the period from the plain repeat test.
    """
    k = 0
    total = cs.max_revolutions + cs.window_revolutions
    while k < total:
        variational = k >= cs.max_revolutions
        if k == cs.max_revolutions:
            share_step_size(cw.w2, cw.w6)
        status = step_revolution(cw, k, variational, p, opt, cs, stats, step_budget)
        if status != OK:
            return status, k, 0
        k += 1
    period = repeat_period(cw.xs, cs.max_revolutions, k, cs.n_max, cs.period_tol)
    return OK, k, period
