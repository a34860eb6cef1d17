"""Bifurcations along a line: the type of every boundary between cells of different labels.

A line (``campar.views.line``) follows one attractor by continuation; where two
neighbouring cells carry different n-p labels, something happened between them.
``find_transitions`` names it from the data on both sides — the Floquet
multipliers and the extrema of ε at the last cells before the boundary — in the
field's types (as continuation packages type the bifurcations of periodic
orbits by the multiplier that crosses the unit circle):

- **PD**, period doubling: a real multiplier → −1;
- **NS**, Neimark–Sacker: a complex pair → the unit circle;
- **SN**, saddle-node (fold): a real multiplier → +1;
- **G**, grazing: the number of detachments per revolution changes while an extremum
  of ε approaches 0 (``graze_distance``: a contact about to detach, a flight about to
  touch the cam);
- **chaos**: one side chaotic, the other not (onset or end of chaos); the evidence,
  if any, names the route (PD, NS or SN of the periodic side);
- **jump**: both sides periodic and stable with nothing approaching its critical
  value: a discontinuous transition (hysteresis, which a reverse sweep confirms);
- **unknown**, with the reason (a side unconverged or failed, or evidence that
  does not single out a type).

"Approaching" is read from the last cell before the boundary (the one nearest to
it on its side) and the cell after it, farther away on the same side with the same
label. A quantity at distance d from its critical value (|λ + 1|, |λ − 1|, 1 − |λ|
of a complex pair, or the |ε| of an extremum of ε) approaches it when d ≤ NEAR, or
when d ≤ REACH, d decreases towards the boundary and, at its rate over the last cell
spacing, would reach 0 within STEPS spacings. A smooth crossing inside the boundary
interval (at most one spacing from the last cell) gives at most 1 spacing for a
linear approach (PD, NS, grazing) and at most 1/(√2 − 1) ≈ 2.41 for the square-root
approach of a fold, hence STEPS. Only stable cycles are observed (a line follows
attractors), so the evidence is always on the side the attractor comes from.

``campar.views.boundaries`` applies ``classify_boundary`` to every edge of a map, along ω
and along the second parameter (a ``Side`` then also carries its second parameter, its
stored Lyapunov exponent, and whether its graze distance is only the bound that the
stored extrema of ε give).

A multiplier → +1 on a cycle of period 2m whose σn points pair up towards the
boundary (or beside a period-m cycle) is also what the period-doubled daughter of
a period-m cycle shows; without a multiplier → −1 on the other side that boundary is
typed unknown, not SN.
"""

import math
from dataclasses import dataclass

import numpy as np

from ..core.codes import KIND_NAMES, Kind
from ..core.kernel import GRAZE_TOL, SLOW_MARGIN

# A multiplier this close to its critical value is there (the kernel's SLOW flag margin).
NEAR = SLOW_MARGIN
# Farther than this, an approach at any rate is not evidence (measured on the paper's μkn
# lines of 2000 cells: 0.12–0.15 at the folds' last cells, < 0.01 at the doublings').
REACH = 0.2
STEPS = 1.0 / (math.sqrt(2.0) - 1.0)  # cell spacings, see the module docstring
GRAZE_NEAR = GRAZE_TOL  # an extremum of ε this close to 0 grazes (the kernel's GRAZING flag)
# In units of the stroke h; extrema farther from 0 are not evidence (measured at the
# grazings of those lines: 5e-5 … 6e-3, so lines ten times coarser still pass).
GRAZE_REACH = 0.05
TRACE_PERIODS = 2  # periods traced for the extrema of ε (the wrap-around point is interior)

PERIODIC_NAME = KIND_NAMES[Kind.PERIODIC]
CHAOTIC_NAME = KIND_NAMES[Kind.CHAOTIC]
UNSETTLED_NAMES = (KIND_NAMES[Kind.UNCONVERGED], KIND_NAMES[Kind.FAILED])

# What each approach is, by the critical value it reaches: (text, type).
CRITICAL = {
    "-1": ("real multiplier → −1", "PD"),
    "circle": ("complex pair → |λ| = 1", "NS"),
    "+1": ("real multiplier → +1", "SN"),
    "graze": ("extremum of ε → 0", "G"),
}


@dataclass(frozen=True)
class Side:
    """One side of a boundary: its last cell (nearest to the boundary) and the next."""

    index: int  # the last cell's index in the line
    omega: float
    label: str
    kind: str  # KIND_NAMES
    n: int
    p: int
    multipliers: tuple[complex, ...] | None  # at the last cell (None: not periodic)
    farther: tuple[complex, ...] | None  # at the next cell away, if it has the same label
    graze: float | None = None  # graze_distance at the last cell (None: not traced)
    graze_farther: float | None = None
    # even n: largest distance between σn points half a period apart (→ 0 where the
    # cycle merges into one of half its period), at the last cell and the next one away
    half_gap: float | None = None
    half_gap_farther: float | None = None
    # on a map (campar.views.boundaries): the cell's second parameter (name, value)
    second: tuple[str, float] | None = None
    lyapunov: float | None = None  # largest Lyapunov exponent, if stored
    # True when graze is only an upper bound of the graze distance (a map's stored
    # global extrema of ε, not every extremum of a traced orbit): no grazing is excluded
    graze_bound: bool = False

    @property
    def where(self) -> str:
        """The cell's position in text: "ω 2.38" or "ω 2.38, mu_cn 0.8"."""
        if self.second is None:
            return f"ω {self.omega:.6g}"
        return f"ω {self.omega:.6g}, {self.second[0]} {self.second[1]:.6g}"

    @property
    def halving(self) -> bool:
        """True when the cycle's points pair up towards the boundary (half_gap shrinking):
        the cycle may be the period-doubled daughter of one of half its period."""
        return (
            self.half_gap is not None
            and self.half_gap_farther is not None
            and self.half_gap < self.half_gap_farther
        )

    def to_dict(self) -> dict:
        def pairs(values):
            return None if values is None else [[m.real, m.imag] for m in values]

        return {
            "omega": self.omega,
            "label": self.label,
            "kind": self.kind,
            "n": self.n,
            "p": self.p,
            "multipliers": pairs(self.multipliers),
            "multipliers_farther": pairs(self.farther),
            "graze": finite(self.graze),
            "graze_farther": finite(self.graze_farther),
            "half_gap": finite(self.half_gap),
            "half_gap_farther": finite(self.half_gap_farther),
            **({} if self.second is None else {self.second[0]: self.second[1]}),
            **({} if self.lyapunov is None else {"lyapunov": finite(self.lyapunov)}),
        }


@dataclass(frozen=True)
class Approach:
    """A quantity reaching its critical value towards the boundary on one side."""

    critical: str  # a key of CRITICAL
    side: str  # "before" (larger ω, computed first) or "after"
    value: complex | float  # the multiplier or graze distance at the last cell
    distance: float  # from the critical value, at the last cell
    farther_distance: float | None  # … at the next cell away
    steps: float | None  # cell spacings to reach it at the current rate

    @property
    def type(self) -> str:
        return CRITICAL[self.critical][1]

    def describe(self, side: Side) -> str:
        value = self.value
        shown = (
            f"{value.real:+.4f}{value.imag:+.4f}j" if isinstance(value, complex) else f"{value:.3g}"
        )
        rate = "" if self.steps is None else f", {self.steps:.2f} spacings away at its rate"
        return (
            f"{side.label} at {side.where}: {CRITICAL[self.critical][0]} "
            f"({shown}, distance {self.distance:.3g}{rate})"
        )

    def to_dict(self) -> dict:
        value = self.value
        return {
            "critical": self.critical,
            "what": CRITICAL[self.critical][0],
            "side": self.side,
            "value": [value.real, value.imag] if isinstance(value, complex) else value,
            "distance": self.distance,
            "farther_distance": finite(self.farther_distance),
            "steps": finite(self.steps),
        }


@dataclass(frozen=True)
class Transition:
    """The boundary between cells ``before.index`` and ``after.index`` = before.index + 1.

    Parameters
    ----------
    before : Side
        The cell computed first (larger ω on a line running down): its label,
        multipliers and ε extremes, and those of its neighbour away from the boundary.
    after : Side
        The cell computed next.
    type : str
        ``PD``, ``SN``, ``NS``, ``G``, ``chaos``, ``jump`` or ``unknown``.
    reason : str
        Why this type, in words.
    evidence : Approach or None
        The quantity that approaches its critical value, where one does.

    Examples
    --------
    >>> from campar.views.line import bifurcation_line
    >>> flip = bifurcation_line((2.0, 4.0), 50, mu_kn=0.91).transitions[-1]
    >>> flip.type, round(flip.omega, 3)
    ('PD', 2.347)
    """

    before: Side  # the cell computed first (larger ω on a line running down)
    after: Side
    type: str  # PD, SN, NS, G, chaos, jump, unknown
    reason: str
    evidence: Approach | None

    @property
    def omega(self) -> float:
        """Midpoint of the two cells' ω."""
        return 0.5 * (self.before.omega + self.after.omega)

    def to_dict(self) -> dict:
        return {
            "omega": self.omega,
            "omega_before": self.before.omega,
            "omega_after": self.after.omega,
            "from": self.before.label,
            "to": self.after.label,
            "type": self.type,
            "reason": self.reason,
            "evidence": None if self.evidence is None else self.evidence.to_dict(),
            "before": self.before.to_dict(),
            "after": self.after.to_dict(),
        }


def finite(value: float | None) -> float | None:
    """JSON-ready: None for None, NaN and ±inf."""
    return None if value is None or not math.isfinite(value) else float(value)


def critical_distance(multipliers, critical: str) -> float:
    """Distance of the nearest multiplier from ``critical`` ("-1", "+1": real ones only;
    "circle": complex ones, 1 − |λ|); inf when none qualifies."""
    if multipliers is None:
        return math.inf
    found = [math.inf]
    for m in multipliers:
        if not (math.isfinite(m.real) and math.isfinite(m.imag)):
            continue
        if critical == "circle" and m.imag != 0.0:
            found.append(abs(1.0 - abs(m)))
        elif critical == "-1" and m.imag == 0.0:
            found.append(abs(m.real + 1.0))
        elif critical == "+1" and m.imag == 0.0:
            found.append(abs(m.real - 1.0))
    return min(found)


def approaching(
    distance: float, farther: float | None, near: float, reach: float
) -> tuple[bool, float | None]:
    """(approaches, spacings to reach 0 at the last spacing's rate), see the module doc."""
    steps = None
    if farther is not None and math.isfinite(farther) and farther > distance:
        steps = distance / (farther - distance)
    if distance <= near:
        return True, steps
    return (distance <= reach and steps is not None and steps <= STEPS), steps


def side_approach(side: Side, name: str, critical: str) -> Approach | None:
    """The approach of ``critical`` on ``side`` (named "before" or "after"), if any."""
    if critical == "graze":
        if side.graze is None:
            return None
        d, farther, value = side.graze, side.graze_farther, side.graze
        near, reach = GRAZE_NEAR, GRAZE_REACH
    else:
        d = critical_distance(side.multipliers, critical)
        farther = critical_distance(side.farther, critical) if side.farther else None
        if not math.isfinite(d):
            return None
        value = nearest_multiplier(side.multipliers, critical)
        near, reach = NEAR, REACH
    ok, steps = approaching(d, farther, near, reach)
    return Approach(critical, name, value, d, farther, steps) if ok else None


def nearest_multiplier(multipliers, critical: str) -> complex:
    return min(multipliers, key=lambda m: critical_distance((m,), critical))


def first_approach(sides: dict[str, Side], criticals) -> Approach | None:
    """The first approach found, criticals in the order given, "before" side first."""
    for critical in criticals:
        for name, side in sides.items():
            found = side_approach(side, name, critical)
            if found is not None:
                return found
    return None


def classify_boundary(
    before: Side, after: Side, direction: str = "ω decreasing"
) -> tuple[str, str, Approach | None]:
    """(type, reason, evidence) of the boundary between two sides (module docstring);
    ``direction`` says which way "before" → "after" goes, for the text.

    Precedence: a side without attractor (unknown), chaos on one side (unknown if its
    stored Lyapunov exponent is not > 0), the multiplier approaches PD, NS, SN in this
    order, grazing, jump; anything else is unknown.
    """
    sides = {"before": before, "after": after}
    for side in (before, after):
        if side.kind in UNSETTLED_NAMES:
            return "unknown", f"{side.label} at {side.where}: no attractor there", None
    local = first_approach(sides, ("-1", "circle", "+1"))
    if (before.kind == CHAOTIC_NAME) != (after.kind == CHAOTIC_NAME):
        chaotic = before if before.kind == CHAOTIC_NAME else after
        if chaotic.lyapunov is not None and not chaotic.lyapunov > 0.0:
            return (
                "unknown",
                (
                    f"chaos at {chaotic.where} with a largest Lyapunov exponent "
                    f"{chaotic.lyapunov:.3g} ≤ 0 stored"
                ),
                None,
            )
        begins = "ends" if before.kind == CHAOTIC_NAME else "begins"
        exponent = "" if chaotic.lyapunov is None else f", λ1 {chaotic.lyapunov:.3g}"
        route = f"; route {local.type}: {local.describe(sides[local.side])}" if local else ""
        return "chaos", f"chaos {begins} ({direction}{exponent}){route}", local
    if local is not None:
        side = sides[local.side]
        other = after if side is before else before
        doubled = other.kind == PERIODIC_NAME and side.n == 2 * other.n
        # an even cycle whose σn points were not kept (a map without sections) may be
        # pairing up unseen
        unseen = side.n % 2 == 0 and side.half_gap is None
        if local.critical == "+1" and (doubled or side.halving or unseen):
            parent = other.label if doubled else f"a period-{side.n // 2} cycle"
            pairing = (
                "its points pairing up"
                if doubled or side.halving
                else "its σn points not stored (pairing unseen)"
            )
            return (
                "unknown",
                (
                    f"{local.describe(side)}, {pairing}: the period-doubled "
                    f"daughter of {parent}, or a fold; no multiplier → −1 on the "
                    "other side"
                ),
                local,
            )
        return local.type, local.describe(side), local
    if before.kind != PERIODIC_NAME or after.kind != PERIODIC_NAME:
        return (
            "unknown",
            (f"{before.label} → {after.label}: no multiplier approaches its critical value"),
            None,
        )
    if before.p * after.n != after.p * before.n:  # detachments per revolution change
        graze = first_approach(sides, ("graze",))
        if graze is not None:
            return "G", graze.describe(sides[graze.side]), graze
        if before.graze_bound or after.graze_bound:  # only the global extrema were seen
            reason = (
                f"{before.label} → {after.label}: detachments per revolution change, "
                "no stored extremum of ε approaches 0; a grazing at another extremum "
                "is not excluded (trace the orbits)"
            )
            return "unknown", reason, None
    if before.multipliers is None or after.multipliers is None:
        return "unknown", "multipliers not computed on both sides", None
    radius = max(abs(m) for s in (before, after) for m in s.multipliers)
    return (
        "jump",
        (f"both sides stable (largest |λ| {radius:.3f}), nothing approaches its critical value"),
        None,
    )


def find_transitions(line, *, trace=None) -> tuple[Transition, ...]:
    """Every boundary of a line with its type, in the line's order.

    Parameters
    ----------
    line : BifurcationLine
        The line; it must hold multipliers for PD, SN and NS to be told.
    trace : callable, optional
        ``trace(index, revolutions)`` returns the (t, ε) samples of cell ``index``'s
        steady orbit over that many revolutions, or (None, None); by default the line's
        own model traces it (``campar.views.point.trace_steady``); without a model, no
        grazing evidence.

    Returns
    -------
    tuple of Transition
        One per pair of neighbouring cells with different labels.

    Examples
    --------
    >>> from campar.views.line import compute_line, line_spec
    >>> from campar.views.transitions import find_transitions
    >>> line = compute_line(line_spec((2.0, 4.0), 50, mu_kn=0.91), transitions=False)
    >>> [t.type for t in find_transitions(line)]
    ['G', 'PD']
    """
    labels = line.labels
    trace = trace or line_tracer(line)
    out = []
    for i in range(len(labels) - 1):
        if labels[i] == labels[i + 1]:
            continue
        before = side_of(line, labels, i, i - 1)
        after = side_of(line, labels, i + 1, i + 2)
        if (
            before.kind == after.kind == PERIODIC_NAME
            and trace is not None
            and before.p * after.n != after.p * before.n
        ):
            before = with_grazes(before, line, labels, i - 1, trace)
            after = with_grazes(after, line, labels, i + 2, trace)
        out.append(Transition(before, after, *classify_boundary(before, after)))
    return tuple(out)


def side_of(line, labels, i: int, j: int) -> Side:
    """Side whose last cell is i and next cell away j (used if in range, same label)."""
    kind = Kind(int(line.kind[i]))
    farther = j if 0 <= j < len(labels) and labels[j] == labels[i] else None
    n = int(line.n[i])
    return Side(
        index=i,
        omega=float(line.omega[i]),
        label=labels[i],
        kind=KIND_NAMES[kind],
        n=n,
        p=int(line.p[i]),
        multipliers=cell_multipliers(line, i),
        farther=None if farther is None else cell_multipliers(line, farther),
        half_gap=half_gap(line.sections[i], n),
        half_gap_farther=None if farther is None else half_gap(line.sections[farther], n),
    )


def half_gap(sections, n: int) -> float | None:
    """∞-norm distance between the σn points half a period apart (even n ≥ 2), or None
    (also when the line keeps fewer than n σn points a cell)."""
    points = np.asarray(sections, dtype=float)[:n]
    if n < 2 or n % 2 or len(points) < n:
        return None
    gap = np.abs(points[: n // 2] - points[n // 2 :]).max()
    return float(gap) if np.isfinite(gap) else None


def cell_multipliers(line, i: int) -> tuple[complex, ...] | None:
    values = getattr(line, "multipliers", None)
    if values is None or int(line.kind[i]) != Kind.PERIODIC:
        return None
    pairs = np.asarray(values[i], dtype=float)
    if not np.all(np.isfinite(pairs)):
        return None
    return tuple(complex(re, im) for re, im in pairs)


def with_grazes(side: Side, line, labels, j: int, trace) -> Side:
    """The side with the graze distances of its last cell and (same label) the next one away."""
    graze = graze_distance(*trace(side.index, TRACE_PERIODS * side.n))
    farther = None
    if 0 <= j < len(labels) and labels[j] == side.label:
        farther = graze_distance(*trace(j, TRACE_PERIODS * side.n))
    return Side(**{**side.__dict__, "graze": graze, "graze_farther": farther})


def graze_distance(t, eps) -> float | None:
    """Smallest |ε| at an interior local extremum of ε sampled at times t, each refined
    by the parabola through its sample and both neighbours (None: no extremum).

    A minimum near 0 is a contact about to detach or a shallow flight, a maximum near 0
    a flight about to touch the cam or a short contact: where a detachment appears or
    vanishes. (The kernel's grazing flag looks at minima only.)
    """
    if t is None or len(t) < 3:
        return None
    t = np.asarray(t, dtype=float)
    e = np.asarray(eps, dtype=float)
    a, b, c = e[:-2], e[1:-1], e[2:]
    extremum = ((b <= a) & (b < c)) | ((b >= a) & (b > c))
    if not extremum.any():
        return None
    a, b, c = a[extremum], b[extremum], c[extremum]
    inner = np.flatnonzero(extremum) + 1
    h0, h2 = t[inner - 1] - t[inner], t[inner + 1] - t[inner]  # h0 < 0 < h2
    with np.errstate(divide="ignore", invalid="ignore"):
        # ε ≈ b + slope·u + curve·u², u = time from the extremal sample
        curve = ((c - b) / h2 - (a - b) / h0) / (h2 - h0)
        slope = (c - b) / h2 - curve * h2
        at = -slope / (2.0 * curve)
        vertex = b - slope**2 / (4.0 * curve)
    inside = np.isfinite(vertex) & (at >= h0) & (at <= h2)
    return float(np.min(np.abs(np.where(inside, vertex, b))))


def line_tracer(line):
    """trace(index, revolutions) -> (t, ε) samples of a cell's steady orbit (None, None
    when the integration fails), from the line's model; None for a line without one."""
    model = getattr(line, "model", None)
    if model is None:
        return None
    from .point import trace_steady

    def trace(index: int, revolutions: int):
        cell = model.model_copy(update={"omega": float(line.omega[index])})
        orbit = trace_steady(cell, line.state[index], max(revolutions, 1))
        return (None, None) if orbit is None else (orbit.t, orbit.eps)

    return trace


def describe_transitions(transitions) -> str:
    """One text line per boundary: ω, labels, type and its evidence or reason."""
    return "\n".join(
        f"  ω {t.omega:.5g}  {t.before.label:>6} → {t.after.label:<6} {t.type:>7}  {t.reason}"
        for t in transitions
    )
