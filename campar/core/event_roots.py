"""Where a trial step's event functions reach zero: the first root inside the step.

From g and g' at the step's ends, the cubic Hermite model of g brackets a root, or a dip
of g below zero between two positive ends (a grazing contact); where a bound on |g''| is
known (the field does not see what g follows: free flight, ``model.event_curvature``) it
rules roots out or has the dense output read piece by piece. Roots are located on the
dense output (Illinois regula falsi) to the event tolerance.
"""

import math
from typing import NamedTuple

import numpy as np

from .hermite import MAXIMUM, MINIMUM, hermite_extremum
from .jit import hot
from .stages import dense_eval, prepare_dense

LOCATE_MAX_ITER = 80
HERMITE_BOUND = 4.0 / 27.0
# The cubic model's interior minimum must stay above this fraction of the end
# values, or the dense output is searched for a dip below zero.
DIP_MARGIN = 0.5
GOLDEN = 0.6180339887498949
DIP_ITER = 24
# Pieces a step is read in where the bound on an event function's curvature cannot rule
# out a root (scan_for_root): each piece's share of the bound is 1/64 of the step's.
SCAN_PIECES = 8


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
    w: tuple  # its StepWork (campar.core.integrator)
    n_err: int  # components of the dense output the event functions read
    theta_tol: float  # tolerance of an event time, as a fraction of h
    curvature: float  # a bound on |g0''| (in time) over the step; inf: none known


class Bracket(NamedTuple):
    """A sign change of an event function over a trial step, in fractions θ of it."""

    a: float
    fa: float  # g(a) > 0
    b: float  # a < b
    fb: float  # g(b) ≤ 0


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
    return golden_minimum(rhs, events, step, which, max(0.0, guess - 0.25), min(1.0, guess + 0.25))


@hot
def golden_minimum(rhs, events, step, which, a, b):
    """Minimum of event ``which`` over [a, b] of the step on the dense output (golden
    section, stopping at a value ≤ 0); returns (θ, value)."""
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
def may_cross(g0, d0, g1, d1, bound):
    """Whether a g positive at both ends of [0, 1], with rates d0, d1 there (per unit of
    the interval) and |g''| ≤ bound inside, can reach 0 inside. g lies above the
    parabolas g0 + d0 s − bound s²/2 and g1 − d1 (1 − s) − bound (1 − s)²/2; where each
    stays positive up to its first root and the two reaches cover [0, 1], it cannot."""
    if bound <= 0.0:
        return False  # a linear g between two positive ends
    reach0 = (d0 + math.sqrt(d0 * d0 + 2.0 * bound * g0)) / bound
    reach1 = (-d1 + math.sqrt(d1 * d1 + 2.0 * bound * g1)) / bound
    return reach0 + reach1 < 1.0


@hot
def scan_for_root(rhs, events, step, which, a, ga, da, b, gb, db):
    """The first root of event ``which`` on [a, b] of the step, where g(a) = ga > 0 and
    the rates da, db are per unit of the step: a bracket (lo, g(lo), hi, g(hi)) with
    g(lo) > 0 ≥ g(hi), or g(hi) > 0 where there is none.

    g and g' are read on the dense output at the ends of SCAN_PIECES pieces; a piece whose
    ends are positive and that may_cross, with its share of the bound on g''
    (step.curvature), cannot clear is searched for its minimum (golden section).
    """
    w = step.w
    piece = (b - a) / SCAN_PIECES
    bound = step.curvature * (step.h * piece) ** 2
    lo = a
    glo = ga
    dlo = da * piece
    for j in range(1, SCAN_PIECES + 1):
        hi = a + j * piece
        if j == SCAN_PIECES:
            hi = b
            ghi = gb
            dhi = db * piece
        else:
            ghi = event_value(rhs, events, step, which, hi)
            dhi = w.dg_tmp[which] * step.h * piece
        if ghi <= 0.0:
            return lo, glo, hi, ghi
        if may_cross(glo, dlo, ghi, dhi, bound):
            th, gm = golden_minimum(rhs, events, step, which, lo, hi)
            if gm <= 0.0:
                return lo, glo, th, gm
        lo = hi
        glo = ghi
        dlo = dhi
    return a, ga, b, gb


@hot
def earlier_root(rhs, events, step, which, a, ga, da, lo):
    """A bracket of a root of event ``which`` in (a, lo), where g(a) = ga > 0 with rate da
    (per unit of the step) and g(lo) > 0 is the left end of the bracket a root was found
    in: (lo', g, hi', g(hi') ≤ 0), or g(hi') > 0 where the bound on g'' (step.curvature)
    rules one out or the dense output shows none. A g with several roots in the step (a
    contact inside a long free-flight step that ends in contact) has its first one."""
    if lo <= a:
        return a, ga, lo, ga
    g_lo = event_value(rhs, events, step, which, lo)
    d_lo = step.w.dg_tmp[which] * step.h
    span = lo - a
    if not may_cross(ga, da * span, g_lo, d_lo * span, step.curvature * (step.h * span) ** 2):
        return a, ga, lo, g_lo
    a2, ga2, b2, gb2 = scan_for_root(rhs, events, step, which, a, ga, da, lo, g_lo, d_lo)
    if b2 >= lo - step.theta_tol:
        return a, ga, lo, g_lo  # the root found (a rounding of g just before it)
    return a2, ga2, b2, gb2


@hot
def off_the_surface(rhs, events, step, which, g0, d0, g1, d1):
    """A bracket of the first root of event ``which`` in a step that starts on its surface
    (g0 ≈ 0, rising) and ends positive: a contact that begins and ends inside one step
    just after a detachment. g0 + d0 s − bound s²/2 is positive up to s = 2 d0 / bound and
    peaks at d0 / bound; from that peak on the step is scanned (scan_for_root). g(b) > 0
    where there is none."""
    bound = step.curvature * step.h * step.h
    if d0 <= 0.0 or d0 >= bound:
        return 0.0, g0, 1.0, g1  # falling: g is not rising off its surface; else no room
    peak = d0 / bound
    g_peak = event_value(rhs, events, step, which, peak)
    if g_peak <= 0.0:
        return 0.0, g0, 1.0, g1  # still at the rounding level of its surface
    d_peak = step.w.dg_tmp[which] * step.h
    return scan_for_root(rhs, events, step, which, peak, g_peak, d_peak, 1.0, g1, d1)


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
        curved = i == 0 and step.curvature < math.inf
        da = d0
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
                        da = w.dg_tmp[i] * h
                if fa <= 0.0:  # never inside: the event is at the step start
                    if first_theta > 0.0:
                        first = i
                        first_theta = 0.0
                    continue
        else:
            # both ends positive: a dip below zero needs min(g0, g1) < 4/27 (|d0| + |d1|),
            # the largest excursion of a cubic Hermite basis beyond its end values
            fb = 1.0
            if min(g0, g1) <= HERMITE_BOUND * (abs(d0) + abs(d1)):
                th, val = hermite_extremum(g0, d0, g1, d1, MINIMUM)
                if th > 0.0 and val <= DIP_MARGIN * min(g0, g1):
                    # a shallow dip (a grazing contact or detachment) can reach zero
                    # between the cubic's values: find the minimum on the dense output
                    th, gm = dense_minimum(rhs, events, step, i, th)
                    if gm <= 0.0:
                        b = th
                        fb = gm
            if fb > 0.0 and curved and surface:
                a, fa, b, fb = off_the_surface(rhs, events, step, i, g0, d0, g1, d1)
                if fb > 0.0:
                    continue
            elif fb > 0.0 and curved and may_cross(g0, d0, g1, d1, step.curvature * h * h):
                # the cubic model is blind where g is far from a cubic: in free flight the
                # field does not see the event's cam, and a step can span most of a phase
                a, fa, b, fb = scan_for_root(rhs, events, step, i, 0.0, g0, d0, 1.0, g1, d1)
                if fb > 0.0:
                    continue
            elif fb > 0.0 or surface:
                continue
        if a >= first_theta:
            continue
        lo, hi = locate_event(rhs, events, step, i, Bracket(a, fa, b, fb))
        if curved and fa > 0.0 and (a == 0.0 or g1 <= 0.0):
            # a root bracketed from the step's start (or its peak) need not be the first
            a, fa, b, fb = earlier_root(rhs, events, step, i, a, fa, da, lo)
            if fb <= 0.0:
                _, hi = locate_event(rhs, events, step, i, Bracket(a, fa, b, fb))
        if hi < first_theta:
            first = i
            first_theta = hi
    return first, first_theta
