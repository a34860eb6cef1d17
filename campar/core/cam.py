"""Cam motion laws: the follower's prescribed lift S(θ) and its θ-derivatives.

A cam of the paper's kind has four phases over one revolution, of angles Φ1 … Φ4
(rise, far dwell, fall, near dwell; summing to 2π) and a stroke of 1 (lengths in
units of the stroke h). The rise and the fall each follow a motion law of its own,
as a function s(u) of the phase fraction u ∈ [0, 1] with s(0) = 0, s(1) = 1:

- cosine acceleration (the paper's): s = (1 − cos πu) / 2, acceleration jumps at u = 0, 1;
- cycloidal: s = u − sin(2πu) / 2π, continuous acceleration;
- 3-4-5 polynomial: s = 10u³ − 15u⁴ + 6u⁵, continuous acceleration;
- modified trapezoidal and modified sine: sine ramps and (for the trapezoid) plateaus of
  acceleration, continuous acceleration, jerk jumps inside the phase (u = 1/8, 3/8, …).

S = s(u), S' = s'(u)/Φ, S'' = s''(u)/Φ² on a rise of angle Φ; a fall is 1 − s. A
measured or designed cam is a ``TabulatedCam``: a periodic C² cubic spline through a
table of (θ, S), one formula for the whole revolution (campar.model.cam_table builds it).

Each law is a named tuple class of its own, and ``lift`` picks the law's formula by the
tuple's class when numba types the call (``overload``): the kernel a job compiles holds
only that job's laws, and the per-step path has no branch on the law. The cosine law is
written as the paper's kernel always was (cos kθ with k = π/Φ and the coefficients
folded into constants once), so at Φ1 = Φ3 = π/3 it is bit for bit that kernel.
"""

import math
from typing import NamedTuple

import numpy as np
from numba.extending import overload, register_jitable

TWO_PI = 2.0 * math.pi
# The paper's angles: rise, far dwell, fall, near dwell.
PAPER_ANGLES = (math.pi / 3.0, 2.0 * math.pi / 3.0, math.pi / 3.0, 2.0 * math.pi / 3.0)

# Peak accelerations s''max of the two composite laws on u ∈ [0, 1], in closed form:
# the half-rise s(1/2) = 1/2 fixes them (docs/design.md).
TRAPEZOID_PEAK = 0.5 / (1.0 / (8.0 * math.pi) + 1.0 / 16.0)  # 4.8881…
SINE_PEAK = 0.5 / (1.0 / (8.0 * math.pi) + 1.0 / (2.0 * math.pi**2))  # 5.5279…


class Cosine(NamedTuple):
    """Cosine acceleration on [start, start + width]: k = π/width, c1 = k/2, c2 = k²/2."""

    start: float
    k: float
    c1: float
    c2: float


class Cycloidal(NamedTuple):
    start: float
    inv_width: float


class Polynomial345(NamedTuple):
    start: float
    inv_width: float


class ModifiedTrapezoid(NamedTuple):
    start: float
    inv_width: float


class ModifiedSine(NamedTuple):
    start: float
    inv_width: float


SEGMENT_LAWS = {
    "cosine": Cosine,
    "cycloidal": Cycloidal,
    "polynomial-345": Polynomial345,
    "modified-trapezoid": ModifiedTrapezoid,
    "modified-sine": ModifiedSine,
}
MOTION_LAWS = tuple(SEGMENT_LAWS)
# Each law's largest |s''(u)| on u ∈ [0, 1]: a phase of angle Φ has |S''| ≤ peak / Φ².
SEGMENT_PEAKS = {
    "cosine": math.pi**2 / 2.0,
    "cycloidal": 2.0 * math.pi,
    "polynomial-345": 10.0 / math.sqrt(3.0),  # at u = (3 − √3) / 6
    "modified-trapezoid": TRAPEZOID_PEAK,
    "modified-sine": SINE_PEAK,
}


class PhasedCam(NamedTuple):
    """A rise and a fall of their own laws between dwells; ``bounds``: the five phase
    boundaries 0, Φ1, Φ1+Φ2, Φ1+Φ2+Φ3, 2π; ``peak``: each phase's largest |S''|."""

    rise: tuple
    fall: tuple
    bounds: tuple
    peak: tuple


class TabulatedCam(NamedTuple):
    """A cubic spline: on [knots[i], knots[i+1]], S = ((a d + b) d + c) d + e with
    d = θ − knots[i] and (a, b, c, e) = coef[i]; knots[-1] = 2π. Phase p uses the
    intervals span[p, 0] … span[p, 1] (those meeting it), so that, as a phased cam's
    formula, a phase's spline piece is used as given a rounding error outside the phase.
    ``bounds`` and ``peak`` as PhasedCam's (the revolution's steps end on the bounds);
    ``breaks``: the rough knots (``rough_knots``), which the steps end on too, then inf."""

    knots: np.ndarray
    coef: np.ndarray
    span: np.ndarray  # int64 (4, 2)
    bounds: tuple
    breaks: np.ndarray
    peak: tuple  # each phase's largest |S''| over the intervals it uses


# A knot whose kink (rough_knots) exceeds this is a breakpoint. Measured on tables of the
# cosine, cycloidal and modified-trapezoid laws at 720 … 3600 points along 121-cell chains
# (benchmarks/RESULTS.md, "Tabulated cams"): kinks up to 8e-4 stepped across leave every
# label and the cycles within 1.2e-7 of the built-in law's; a table whose kinks reach 2.1e-3
# (the 3600-point trapezoid) did not.
ROUGHNESS_LIMIT = 1e-3


def rough_knots(knots, coef, bounds) -> np.ndarray:
    """The knots of a spline (``knots`` with 2π last, ``coef`` as TabulatedCam's) the
    revolution ends its steps on.

    The spline's third derivative jumps at every knot, by 6 Δa. A step across a knot is
    not smooth there, and its error depends on where in the step the knot falls: each
    revolution's map is off by a noise the embedded error estimate does not see (a
    720-point table of the modified trapezoid read its 1-cycles as 2-2 … 12-12). The
    noise grows with the kink |ΔS'''| h (h: the knot's shorter interval), the
    jump's trace in the cam's acceleration S''; knots whose kink exceeds ROUGHNESS_LIMIT
    are breakpoints, the others (a dense table's, a dwell's) are stepped across. The phase
    boundaries end the steps already and are left out."""
    knots = np.asarray(knots, dtype=np.float64)
    coef = np.asarray(coef, dtype=np.float64)
    interval = np.diff(knots)
    shorter = np.minimum(interval, np.roll(interval, 1))  # knot 0: its first and last
    kink = 6.0 * np.abs(coef[:, 0] - np.roll(coef[:, 0], 1)) * shorter
    rough = kink > ROUGHNESS_LIMIT
    for b in bounds:
        rough &= np.abs(knots[:-1] - b) > 1e-12 * TWO_PI
    return knots[:-1][rough]


def tabulated_cam(knots, coef, bounds) -> TabulatedCam:
    """The TabulatedCam of a spline (campar.model.cam_table) and the cam's phase bounds."""
    knots = np.ascontiguousarray(knots, dtype=np.float64)
    coef = np.ascontiguousarray(coef, dtype=np.float64)
    breaks = np.append(rough_knots(knots, coef, bounds), math.inf)
    last = len(knots) - 2  # the last interval
    span = np.empty((4, 2), dtype=np.int64)
    for p in range(4):
        first = int(np.searchsorted(knots, bounds[p], side="right")) - 1
        final = int(np.searchsorted(knots, bounds[p + 1], side="left")) - 1
        span[p] = min(max(first, 0), last), min(max(final, first, 0), last)
    # S'' = 6 a d + 2 b is linear on each interval: its largest |S''| is at an end
    ends = np.abs(
        np.stack([2.0 * coef[:, 1], 6.0 * coef[:, 0] * np.diff(knots) + 2.0 * coef[:, 1]])
    )
    peak = tuple(float(ends[:, lo : hi + 1].max()) for lo, hi in span)
    return TabulatedCam(knots, coef, span, tuple(float(b) for b in bounds), breaks, peak)


def segment(name: str, start: float, width: float):
    """The segment law ``name`` on [start, start + width] (ValueError for an unknown name)."""
    if name not in SEGMENT_LAWS:
        raise ValueError(f"unknown motion law {name!r}; allowed: {', '.join(MOTION_LAWS)}")
    if name == "cosine":
        k = math.pi / width
        return Cosine(start, k, 0.5 * k, 0.5 * k * k)
    return SEGMENT_LAWS[name](start, 1.0 / width)


def phase_bounds(angles) -> tuple[float, float, float, float, float]:
    """0, Φ1, Φ1+Φ2, Φ1+Φ2+Φ3, 2π (the last exactly 2π, whatever the rounding of the sum;
    the job checks the angles: campar.model.cam_table.check_angles)."""
    p1, p2, p3, _ = (float(a) for a in angles)
    return (0.0, p1, p1 + p2, p1 + p2 + p3, TWO_PI)


def phased_cam(rise: str = "cosine", fall: str = "cosine", angles=PAPER_ANGLES) -> PhasedCam:
    """The cam of a rise law and a fall law over the four phase angles."""
    bounds = phase_bounds(angles)
    rise_angle, fall_angle = float(angles[0]), float(angles[2])
    peak = (
        SEGMENT_PEAKS[rise] / rise_angle**2,
        0.0,
        SEGMENT_PEAKS[fall] / fall_angle**2,
        0.0,
    )
    # widths from the angles themselves: bounds[3] − bounds[2] is Φ3 only up to rounding
    return PhasedCam(
        segment(rise, 0.0, rise_angle), segment(fall, bounds[2], fall_angle), bounds, peak
    )


PAPER_CAM = phased_cam()


# -- evaluation (numba) ------------------------------------------------------------------


def rise(law, theta):
    """s, ds/dθ, d²s/dθ² of a segment law rising 0 → 1 (compiled code only: ``overload``)."""
    raise TypeError("campar.core.cam.rise is for compiled code")


def fall(law, theta):
    """S, dS/dθ, d²S/dθ² of a segment law falling 1 → 0 (compiled code only)."""
    raise TypeError("campar.core.cam.fall is for compiled code")


def lift(law, theta, phase):
    """yc(θ) and its first two θ-derivatives with the formula of cam phase ``phase``
    (0 rise, 1 far dwell, 2 fall, 3 near dwell) of cam ``law`` (compiled code only)."""
    raise TypeError("campar.core.cam.lift is for compiled code")


def next_join(law, phase, t, omega):
    """The first time after t (θ = ω t) at which the formula of cam phase ``phase`` of cam
    ``law`` joins two pieces (math.inf: none in the phase); compiled code only.

    The composite laws are piecewise: the modified trapezoid's acceleration is a sine
    ramp, a plateau, a sine, a plateau, a ramp, and the modified sine's three sines, each
    join a jump of the cam's fourth derivative (its second derivative and jerk are
    continuous). A step across one is no longer smooth, and the embedded error estimate
    can pass it with an error far above the tolerance: the revolution ends its steps on
    the joins, as on the phase boundaries (run_revolution). A tabulated cam's joins are
    its rough knots (``rough_knots``).
    """
    raise TypeError("campar.core.cam.next_join is for compiled code")


def _normalised(s_of):
    """A segment's rise and fall from its law's s(u), s'(u), s''(u) on u ∈ [0, 1]."""

    def rise_impl(law, theta):
        u = (theta - law.start) * law.inv_width
        s, ds, d2s = s_of(u)
        return s, ds * law.inv_width, d2s * law.inv_width * law.inv_width

    def fall_impl(law, theta):
        u = (theta - law.start) * law.inv_width
        s, ds, d2s = s_of(u)
        return 1.0 - s, -ds * law.inv_width, -d2s * law.inv_width * law.inv_width

    return rise_impl, fall_impl


@register_jitable
def cycloidal(u):
    w = 2.0 * math.pi
    sn = math.sin(w * u)
    return u - sn / w, 1.0 - math.cos(w * u), w * sn


@register_jitable
def polynomial_345(u):
    v = 1.0 - u
    return (
        u * u * u * (10.0 - 15.0 * u + 6.0 * u * u),
        30.0 * u * u * v * v,
        60.0 * u * v * (1.0 - 2.0 * u),
    )


def _mirrored(half):
    """A law antisymmetric about u = 1/2 from its first half: s(u) = 1 − s(1 − u)."""

    @register_jitable
    def s_of(u):
        if u <= 0.5:
            return half(u)
        s, ds, d2s = half(1.0 - u)
        return 1.0 - s, ds, -d2s

    return s_of


@register_jitable
def _sine_ramp(u, a):
    """s, s', s'' on the opening quarter sine (u ∈ [0, 1/8]) of a composite law of peak a."""
    w = 4.0 * math.pi
    return a / w * (u - math.sin(w * u) / w), a / w * (1.0 - math.cos(w * u)), a * math.sin(w * u)


@register_jitable
def _trapezoid_half(u):
    a, w = TRAPEZOID_PEAK, 4.0 * math.pi
    if u < 0.125:
        return _sine_ramp(u, a)
    s1, v1, _ = _sine_ramp(0.125, a)
    if u < 0.375:
        d = u - 0.125
        return s1 + v1 * d + 0.5 * a * d * d, v1 + a * d, a
    v2 = v1 + 0.25 * a
    s2 = s1 + 0.25 * v1 + a / 32.0
    d = u - 0.375
    return (
        s2 + v2 * d + a / (w * w) * (1.0 - math.cos(w * d)),
        v2 + a / w * math.sin(w * d),
        a * math.cos(w * d),
    )


@register_jitable
def _sine_half(u):
    a, w3 = SINE_PEAK, 4.0 * math.pi / 3.0
    if u < 0.125:
        return _sine_ramp(u, a)
    s1, v1, _ = _sine_ramp(0.125, a)
    d = u - 0.125
    return (
        s1 + v1 * d + a / (w3 * w3) * (1.0 - math.cos(w3 * d)),
        v1 + a / w3 * math.sin(w3 * d),
        a * math.cos(w3 * d),
    )


def _cosine_rise(law, theta):
    s3 = math.sin(law.k * (theta - law.start))
    c3 = math.cos(law.k * (theta - law.start))
    return 0.5 * (1.0 - c3), law.c1 * s3, law.c2 * c3


def _cosine_fall(law, theta):
    u = law.k * (theta - law.start)
    s3 = math.sin(u)
    c3 = math.cos(u)
    return 0.5 * (1.0 + c3), -law.c1 * s3, -law.c2 * c3


# Where a composite law's pieces join, as fractions u of its segment (next_join).
SEGMENT_JOINS = {
    ModifiedTrapezoid: (0.125, 0.375, 0.625, 0.875),
    ModifiedSine: (0.125, 0.875),
}

_SEGMENT_IMPLS = {
    Cosine: (_cosine_rise, _cosine_fall),
    Cycloidal: _normalised(cycloidal),
    Polynomial345: _normalised(polynomial_345),
    ModifiedTrapezoid: _normalised(_mirrored(_trapezoid_half)),
    ModifiedSine: _normalised(_mirrored(_sine_half)),
}


def _law_class(typ):
    return getattr(typ, "instance_class", None)


OPTIONS = {"no_cpython_wrapper": True, "_nrt": False}


@overload(rise, jit_options=OPTIONS)
def _rise(law, theta):
    impls = _SEGMENT_IMPLS.get(_law_class(law))
    return None if impls is None else impls[0]


@overload(fall, jit_options=OPTIONS)
def _fall(law, theta):
    impls = _SEGMENT_IMPLS.get(_law_class(law))
    return None if impls is None else impls[1]


def _phased_lift(law, theta, phase):
    if phase == 0:
        return rise(law.rise, theta)
    if phase == 2:
        return fall(law.fall, theta)
    if phase == 1:
        return 1.0, 0.0, 0.0
    return 0.0, 0.0, 0.0


def _spline_lift(law, theta, phase):
    knots = law.knots
    lo = law.span[phase, 0]
    hi = law.span[phase, 1]
    if theta >= knots[hi]:
        lo = hi
    else:
        while hi - lo > 0:  # the interval in lo … hi whose left knot is the last ≤ θ
            mid = (lo + hi + 1) >> 1
            if knots[mid] <= theta:
                lo = mid
            else:
                hi = mid - 1
    a, b, c, e = law.coef[lo, 0], law.coef[lo, 1], law.coef[lo, 2], law.coef[lo, 3]
    d = theta - knots[lo]
    return ((a * d + b) * d + c) * d + e, (3.0 * a * d + 2.0 * b) * d + c, 6.0 * a * d + 2.0 * b


@overload(lift, jit_options=OPTIONS)
def _lift(law, theta, phase):
    cls = _law_class(law)
    if cls is PhasedCam:
        return _phased_lift
    if cls is TabulatedCam:
        return _spline_lift
    return None


def _segment_join(joins):
    """next_join of one segment law whose pieces join at fractions ``joins`` of it."""

    @register_jitable
    def join_after(law, t, omega):
        for u in joins:
            t_join = (law.start + u / law.inv_width) / omega
            if t_join > t:
                return t_join
        return math.inf

    return join_after


_SEGMENT_JOIN_IMPLS = {cls: _segment_join(joins) for cls, joins in SEGMENT_JOINS.items()}


@register_jitable
def _no_join(law, t, omega):
    return math.inf


def segment_join(law, t, omega):
    """next_join within one segment law (compiled code only)."""
    raise TypeError("campar.core.cam.segment_join is for compiled code")


@overload(segment_join, jit_options=OPTIONS)
def _segment_join_overload(law, t, omega):
    cls = _law_class(law)
    if cls in _SEGMENT_JOIN_IMPLS:
        return _SEGMENT_JOIN_IMPLS[cls]
    if cls in _SEGMENT_IMPLS:
        return _no_join
    return None


def _phased_join(law, phase, t, omega):
    if phase == 0:
        return segment_join(law.rise, t, omega)
    if phase == 2:
        return segment_join(law.fall, t, omega)
    return math.inf


def _spline_join(law, phase, t, omega):
    breaks = law.breaks
    lo = 0
    hi = breaks.shape[0] - 1  # inf: none left
    # the first break after t, compared in time: the step that ended on a break ended at
    # breaks[i] / omega, which ω t need not give back exactly
    while lo < hi:
        mid = (lo + hi) >> 1
        if breaks[mid] / omega > t:
            hi = mid
        else:
            lo = mid + 1
    return breaks[lo] / omega


@overload(next_join, jit_options=OPTIONS)
def _next_join(law, phase, t, omega):
    cls = _law_class(law)
    if cls is PhasedCam:
        return _phased_join
    if cls is TabulatedCam:
        return _spline_join
    return None
