"""A map edge typed by shooting: the cycles on both sides solved, continued across, and
the change between them located.

A map's edge between two periodic cells of different labels says that the attractor
changed between two parameter points, not how. ``type_edge`` solves each side's cycle by
Newton's method on Pⁿ from the cell's stored state (``orbit.find_cycle``: unstable cycles
too), then continues it along the straight path to the other cell in natural-parameter
steps, each corrected by Newton, and watches what the cycle meets on the way:

- **G**, grazing: the cycle's detachments per period change, or the signed ε at its
  extremum nearest 0 (``touch``) changes sign — located where ``touch`` = 0;
- **PD**: a real multiplier crosses −1, or the cycle's minimal period halves (a doubled
  cycle folding back onto the one it doubled from);
- **SN**: Newton loses the cycle while its largest multiplier is real and above
  ``FOLD_MULTIPLIER`` (the cycle ends in a fold), or a real multiplier crosses +1 with the
  cycle going on (a branch point: natural-parameter steps cannot pass a fold, and a
  pitchfork or transcritical point is typed SN too);
- **NS**: a complex pair crosses the unit circle.

The first change met on the path from the cell computed first ("before") types the edge;
if that cycle meets none, the first met from the other side; if neither meets one, both
cycles exist and are stable across the whole edge: the map jumped between coexisting
cycles (**jump**). A change is located by bisection on the path to ``LOCATE_TOL`` of the
edge. What cannot be decided stays ``unknown``, with the reason: no cycle by Newton from
either cell's state, or a cycle lost by Newton with no fold or grazing in sight.
"""

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ContinuationError
from .orbit import PeriodicOrbit, find_cycle, newton, orbit_at
from .section_map import PARAMETER_ORDER, SectionMap, parameter_vector

WALK_STEPS = 4  # natural-continuation steps from a cell to its neighbour
MAX_HALVINGS = 4  # a step Newton refuses is halved so often before the cycle is lost
WALK_NEWTON = 10  # Newton iterations per continuation step
LOCATE_TOL = 1e-3  # of the edge: a change is located to this fraction of it
FOLD_MULTIPLIER = 0.5  # a cycle lost with its largest multiplier real and above this: SN
SAME_STATE = 1e-6  # section points this close are one cycle's (y units)


@dataclass(frozen=True)
class EdgeChange:
    """What a cycle meets on the path between two cells, and where.

    type: PD, SN, NS, G, jump or unknown; side: whose cycle meets it ("before",
    "after"; "both" for a jump and where neither cycle was found); at: where, as the
    fraction of the way from the before cell to the after cell; value: the signed ε
    extremum nearest 0 (G) or the critical multiplier (PD, SN, NS) there; reason: in words.
    """

    type: str
    side: str
    at: float
    value: complex | float | None
    reason: str


@dataclass(frozen=True)
class Cell:
    """One side of an edge: its parameters (PARAMETER_ORDER names), stored state, n."""

    parameters: dict
    state: tuple[float, float]
    n: int


def type_edge(before: Cell, after: Cell, smap: SectionMap) -> EdgeChange:
    """The change between two periodic cells (see the module docstring)."""
    pa, pb = parameter_vector(before.parameters), parameter_vector(after.parameters)
    found = {}
    for name, cell, par in (("before", before, pa), ("after", after, pb)):
        try:
            found[name] = find_cycle(
                cell.n, cell.state, section_map=smap, **dict(zip(PARAMETER_ORDER, par, strict=True))
            )
        except ContinuationError:
            found[name] = None
    if found["before"] is None and found["after"] is None:
        return EdgeChange("unknown", "both", math.nan, None, "no cycle by Newton on either side")
    walks = {}
    for name, start, end, forward in (("before", pa, pb, True), ("after", pb, pa, False)):
        if found[name] is not None:
            change, last = walk(smap, found[name], start, end)
            if change is not None:
                at = change.at if forward else 1.0 - change.at
                return EdgeChange(change.type, name, at, change.value, change.reason)
            walks[name] = last
    if len(walks) < 2:
        missing = "before" if "before" not in walks else "after"
        return EdgeChange(
            "unknown",
            missing,
            math.nan,
            None,
            f"no cycle by Newton from the {missing} cell's state; the other side's cycle "
            "crosses the edge unchanged",
        )
    if same_cycle(walks["before"], found["after"]):
        return EdgeChange(
            "unknown",
            "both",
            math.nan,
            None,
            "one cycle on both sides, unchanged across the edge: the labels differ by the "
            "map's classification, not by the cycle",
        )
    return EdgeChange(
        "jump",
        "both",
        math.nan,
        None,
        f"both cycles ({found['before'].label}, {found['after'].label}) exist and are stable "
        "across the edge: the map jumped between coexisting cycles",
    )


def same_cycle(a: PeriodicOrbit, b: PeriodicOrbit) -> bool:
    """Whether two orbits at one parameter point are one cycle (any phase of it)."""
    if a.n != b.n:
        return False
    return bool(np.min(np.max(np.abs(b.sections - np.asarray(a.state)), axis=1)) <= SAME_STATE)


def walk(smap: SectionMap, orbit: PeriodicOrbit, start: np.ndarray, end: np.ndarray):
    """Continue ``orbit`` (at ``start``) to ``end``: (the first change met, located, with
    ``at`` the fraction of the way; None) or (None, the orbit at ``end``)."""
    s, step, halvings = 0.0, 1.0 / WALK_STEPS, 0
    while s < 1.0:
        t = min(1.0, s + step)
        nxt = solve(smap, orbit, start + t * (end - start))
        if nxt is None:
            if halvings == MAX_HALVINGS:
                return lost(orbit, s), None
            step, halvings = step / 2, halvings + 1
            continue
        kind = change_between(orbit, nxt)
        if kind is not None:
            return locate(smap, orbit, nxt, s, t, start, end, kind), None
        orbit, s = nxt, t
    return None, orbit


def solve(smap: SectionMap, orbit: PeriodicOrbit, par: np.ndarray) -> PeriodicOrbit | None:
    """The cycle through ``orbit``'s state at ``par`` (orbit's period), or None."""
    try:
        shot, iterations = newton(smap, np.asarray(orbit.state), par, orbit.n, WALK_NEWTON)
    except ContinuationError:
        return None
    return orbit_at(smap, shot, par, orbit.n, iterations)


def change_between(a: PeriodicOrbit, b: PeriodicOrbit) -> str | None:
    """The type of the change between two orbits of one branch, or None."""
    if b.n < a.n:
        return "PD"
    if a.p != b.p or (a.touch > 0) != (b.touch > 0):
        return "G"
    if (critical(a) < 1.0) != (critical(b) < 1.0):
        mu = max(a.multipliers + b.multipliers, key=abs)
        if abs(mu.imag) > 1e-9 * abs(mu):
            return "NS"
        return "PD" if mu.real < 0 else "SN"
    return None


def critical(orbit: PeriodicOrbit) -> float:
    return abs(orbit.multipliers[0])


def locate(smap, a, b, s0, s1, start, end, kind) -> EdgeChange:
    """Bisect [s0, s1] for the change ``kind`` between orbits a (at s0) and b (at s1)."""
    while s1 - s0 > LOCATE_TOL:
        mid = 0.5 * (s0 + s1)
        orbit = solve(smap, a, start + mid * (end - start))
        if orbit is None:
            break
        if change_between(a, orbit) == kind:
            b, s1 = orbit, mid
        else:
            a, s0 = orbit, mid
    at = 0.5 * (s0 + s1)
    if kind == "G":
        value = a.touch if abs(a.touch) < abs(b.touch) else b.touch
        reason = (
            f"the {a.label} cycle grazes: its ε extremum nearest 0 reaches {value:.3g}, its "
            f"detachments per period {a.p} → {b.p}"
        )
    else:
        value = min(a.multipliers[0], b.multipliers[0], key=lambda m: abs(abs(m) - 1.0))
        if kind == "PD" and b.n < a.n:
            value = complex(-1.0, 0.0)
            reason = f"the {a.label} cycle's period halves to {b.n}: it meets the cycle it doubled"
        else:
            reason = (
                f"the {a.label} cycle's multiplier crosses the unit circle "
                f"({a.multipliers[0]:.4f} → {b.multipliers[0]:.4f})"
            )
    return EdgeChange(kind, "", at, value, reason)


def lost(orbit: PeriodicOrbit, s: float) -> EdgeChange:
    """Newton lost ``orbit``'s branch past ``s``: a fold if its largest multiplier is real
    and positive, a grazing if ε's extremum is about 0, else unknown."""
    mu = orbit.multipliers[0]
    if abs(mu.imag) <= 1e-9 * abs(mu) and mu.real > FOLD_MULTIPLIER:
        return EdgeChange(
            "SN", "", s, mu, f"the {orbit.label} cycle ends in a fold (multiplier {mu.real:.4f})"
        )
    if abs(orbit.touch) < 1e-3:
        return EdgeChange(
            "G", "", s, orbit.touch, f"the {orbit.label} cycle is lost where it grazes"
        )
    return EdgeChange(
        "unknown",
        "",
        s,
        None,
        f"Newton lost the {orbit.label} cycle (multiplier {mu:.4f}, no fold or grazing)",
    )
