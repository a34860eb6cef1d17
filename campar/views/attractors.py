"""Coexisting attractors of one cell: many starts, each run to its steady motion, grouped.

``find_attractors`` runs K starts at one parameter point — rest, any starts given,
then a deterministic spread over a box of (y, y') at θ = 0 (``spread_starts``) —
each as its own one-cell job through ``simulate_point`` (``run_tile``): every start
takes the kernel path of ``campar point --y0 --v0``, with one setting changed:
chaos is only called at the end of the transient budget (CHAOS_AFTER). The
converged results are grouped into distinct attractors (as Attractors.jl maps
initial conditions for its ``basins_fractions``: each result compared with the
first member of every group found so far), and each attractor's basin fraction is
the fraction of the K starts that reached it (a given start counts as one of K, so
fractions estimate basin sizes in the box only without given starts).

Same attractor, decided by the motion itself, never by its label:

- periodic: the σn points of two cycles equal up to a cyclic shift within
  ``match_tolerance`` (∞-norm), which is the cycle's own accuracy, see there;
- quasi-periodic or chaotic: the same kind and overlapping section clouds
  (``clouds_overlap``: one cloud within the other at the clouds' own point spacing) —
  a weak test: two distinct attractors whose clouds interleave at that scale would be
  merged, and a cloud is 64 section points at the end of a 500-revolution budget, so a
  transient longer than that is taken for an attractor.

Starts whose cell is unconverged (no period ≤ n_max and a negative Lyapunov
exponent: a stable motion not yet reached) or failed are never attractors; they
are kept apart as ``unsettled`` and count in the denominator of the fractions.
"""

import math
from dataclasses import dataclass

import numpy as np

from ..core.codes import KIND_NAMES, Kind
from ..sweep.job import DEFAULT_CLASSIFY, DEFAULT_TRANSIENT
from .cycles import match_tolerance as cycle_match_tolerance
from .cycles import same_cycles
from .point import PointResult, simulate_point

DEFAULT_STARTS = 16
# The start box (y, y') at θ = 0, where the cam is on its base circle (yc = 0, ẏc = 0):
# y from one stroke h below the base circle to two strokes above it (flights above the
# cam's lift), y' within ±(3/2) ω h, the cam's peak speed (docs/model.md: ẏc = ω dyc/dθ,
# max dyc/dθ = 3/2), the speed scale the cam gives the follower.
BOX_Y = (-1.0, 2.0)
CAM_PEAK_SPEED = 1.5  # max dyc/dθ of the cosine-acceleration law, stroke 1
HALTON_BASES = (2, 3)
CLOUD_POINTS = DEFAULT_CLASSIFY.window_revolutions  # σn points kept of a non-periodic start
# Chaos is called only at the end of the budget: the kernel's early verdict (after
# transient.chaos_after revolutions) also takes transient chaos for an attractor, e.g. at
# ω = 4.5, μkn = 0.91, where rest reaches 1-1 after 135 revolutions.
CHAOS_AFTER = 0
CLOUD_FACTOR = 3.0  # cross-cloud distance, in units of the clouds' own point spacing
# Kinds of steady motion that are attractors (not unconverged, not failed).
SETTLED_KINDS = frozenset(KIND_NAMES[k] for k in (Kind.PERIODIC, Kind.QUASIPERIODIC, Kind.CHAOTIC))


@dataclass(frozen=True)
class Attractor:
    """One attractor of a cell and the starts that reached it.

    ``result`` is the first start's cell (label, multipliers, σn points, …); ``state``
    is a point of the attractor at θ = 0 (its final state), a start that lands on it.
    """

    result: PointResult
    starts: tuple[int, ...]  # indices into the census' starts, first = representative
    fraction: float  # len(starts) / K

    @property
    def label(self) -> str:
        return self.result.label

    @property
    def kind(self) -> str:
        return self.result.kind

    @property
    def state(self) -> tuple[float, float]:
        return self.result.state

    def to_dict(self, starts: np.ndarray) -> dict:
        """The cell's summary (PointResult.to_dict, without the parameters) with the
        basin fraction and the starts (y, y') that reached it."""
        data = {**self.result.to_dict(), "fraction": self.fraction}
        del data["parameters"]
        data["starts"] = [[float(y), float(v)] for y, v in starts[list(self.starts)]]
        return data


@dataclass(frozen=True)
class AttractorCensus:
    """What K starts of one cell reached: distinct attractors, most frequent first."""

    parameters: dict  # omega, f0, mu_kn, mu_cn, zeta, tensile
    starts: np.ndarray  # (K, 2) initial (y, y') at θ = 0
    attractors: tuple[Attractor, ...]
    basin: np.ndarray  # (K,) index into attractors of each start; -1: unsettled
    unsettled: tuple[tuple[int, PointResult], ...]  # (start index, its cell)
    match_tol: float  # ∞-norm tolerance used to match cycles

    def to_dict(self) -> dict:
        return {
            "parameters": self.parameters,
            "starts": len(self.starts),
            "match_tolerance": self.match_tol,
            "attractors": [a.to_dict(self.starts) for a in self.attractors],
            "unsettled": [
                {
                    "start": [float(v) for v in self.starts[i]],
                    "label": r.label,
                    "kind": r.kind,
                    "status": r.status,
                    "revolutions": r.revolutions,
                }
                for i, r in self.unsettled
            ],  # fmt: skip
        }


def halton(index: int, base: int) -> float:
    """The index-th element (index ≥ 1) of the van der Corput sequence in ``base``, in (0, 1)."""
    value, scale = 0.0, 1.0
    while index:
        scale /= base
        index, digit = divmod(index, base)
        value += digit * scale
    return value


def spread_starts(count: int, omega: float, given=()) -> np.ndarray:
    """(count, 2) starts (y, y') at θ = 0: rest, then the ``given`` ones, then Halton points.

    The Halton points (bases 2, 3, from index 1) fill the box y ∈ BOX_Y,
    y' ∈ ±CAM_PEAK_SPEED·ω; they are nested, so more starts only add points.
    ``count`` ≥ 1 + len(given) (the given starts are kept even beyond ``count``).
    """
    speed = CAM_PEAK_SPEED * omega
    fixed = [(0.0, 0.0), *((float(y), float(v)) for y, v in given if (y, v) != (0.0, 0.0))]
    points = [*fixed]
    index = 1
    while len(points) < count:
        u, w = (halton(index, base) for base in HALTON_BASES)
        points.append((BOX_Y[0] + u * (BOX_Y[1] - BOX_Y[0]), speed * (2.0 * w - 1.0)))
        index += 1
    return np.array(points, dtype=float)


def match_tolerance(
    window_tol: float = DEFAULT_TRANSIENT.window_tol,
    period_tol: float = DEFAULT_CLASSIFY.period_tol,
) -> float:
    """∞-norm distance within which σn points of two converged cycles are one point
    (``cycles.match_tolerance``, the rule of a map's hysteresis too)."""
    return cycle_match_tolerance(window_tol, period_tol)


def same_cycle(a: np.ndarray, b: np.ndarray, tol: float) -> bool:
    """True when the cycles with σn points a and b (each (n, 2), in time order) are one
    orbit: equal within tol (∞-norm) after some cyclic shift (``cycles.same_cycles``)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.size == 0 or b.size == 0:
        return False
    return bool(same_cycles([len(a)], a[None], [len(b)], b[None], tol)[0])


def clouds_overlap(a: np.ndarray, b: np.ndarray, factor: float = CLOUD_FACTOR) -> bool:
    """True when one section cloud ((m, 2) each) lies within the other at its sampling scale.

    The median distance from the points of one cloud to the nearest point of the other,
    in the direction where it is smaller, must be at most ``factor`` times the clouds'
    own point spacing (the larger median nearest-neighbour distance within a cloud). Two
    samples of one chaotic set or invariant circle pass, also when one sample covers only
    part of the set (a slow transient dwelling near a saddle); clouds apart by more than a
    few spacings do not. Weak: two distinct attractors whose clouds interleave at that
    scale pass too, and a non-periodic verdict at the end of the budget may still be a
    long transient.
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if len(a) < 2 or len(b) < 2:
        return False
    cross = np.abs(a[:, None, :] - b[None, :, :]).max(axis=2)
    spacing = max(own_spacing(a), own_spacing(b))
    reach = min(np.median(cross.min(axis=1)), np.median(cross.min(axis=0)))
    return bool(reach <= factor * spacing)


def own_spacing(cloud: np.ndarray) -> float:
    """Median ∞-norm distance from each point of a cloud to its nearest other point."""
    d = np.abs(cloud[:, None, :] - cloud[None, :, :]).max(axis=2)
    np.fill_diagonal(d, np.inf)
    return float(np.median(d.min(axis=1)))


def same_attractor(a: PointResult, b: PointResult, tol: float) -> bool:
    """Periodic: one cycle (``same_cycle``); otherwise one kind and overlapping clouds."""
    if a.kind != b.kind:
        return False
    if a.kind == KIND_NAMES[Kind.PERIODIC]:
        return same_cycle(a.sections, b.sections, tol)
    return clouds_overlap(a.sections, b.sections)


def find_attractors(
    omega: float,
    *,
    count: int = DEFAULT_STARTS,
    starts=None,
    given=(),
    lyapunov: bool = False,
    **settings,
) -> AttractorCensus:
    """Run ``count`` starts at one cell and group them into distinct attractors.

    ``starts`` ((K, 2) array of (y, y') at θ = 0) replaces the spread of
    ``spread_starts(count, omega, given)``. ``settings``: the keywords of
    ``campar.views.point.point_job`` (parameters, tensile, transient, integrator)
    but y0, v0 and sections; ``chaos_after`` defaults to CHAOS_AFTER. Multipliers are
    always computed (one 2×2 eigenvalue problem per cycle). Raises JobError for a
    parameter out of range.
    """
    settings.setdefault("chaos_after", CHAOS_AFTER)
    if starts is None:
        starts = spread_starts(count, omega, given)
    starts = np.asarray(starts, dtype=float).reshape(-1, 2)
    results = [
        simulate_point(omega, y0=float(y), v0=float(v), multipliers=True, lyapunov=lyapunov,
                       sections=CLOUD_POINTS, **settings)
        for y, v in starts
    ]  # fmt: skip
    tol = match_tolerance()
    members: list[list[int]] = []
    basin = np.full(len(starts), -1)
    unsettled = []
    for i, result in enumerate(results):
        if result.kind not in SETTLED_KINDS:
            unsettled.append((i, result))
            continue
        for g, group in enumerate(members):
            if same_attractor(results[group[0]], result, tol):
                group.append(i)
                basin[i] = g
                break
        else:
            basin[i] = len(members)
            members.append([i])
    order = sorted(range(len(members)), key=lambda g: (-len(members[g]), members[g][0]))
    renumber = {old: new for new, old in enumerate(order)}
    basin = np.array([renumber.get(int(g), -1) for g in basin])
    attractors = tuple(
        Attractor(results[members[g][0]], tuple(members[g]), len(members[g]) / len(starts))
        for g in order
    )
    parameters = results[0].parameters if results else {"omega": omega}
    return AttractorCensus(parameters, starts, attractors, basin, tuple(unsettled), tol)


def describe_attractors(census: AttractorCensus) -> str:
    """A few text lines per attractor: label, kind, basin fraction, state, multipliers."""
    par = ", ".join(f"{k}={v}" for k, v in census.parameters.items())
    k = len(census.starts)
    rows = [f"{len(census.attractors)} attractor(s) from {k} starts at {par}"]
    for j, a in enumerate(census.attractors, 1):
        r = a.result
        share = f"{a.fraction:.3f} ± {fraction_error(a.fraction, k):.3f} ({len(a.starts)}/{k})"
        flags = f"  flags: {', '.join(r.flags)}" if r.flags else ""
        rows.append(f"  [{j}] {a.label:>6}  ({a.kind})  basin fraction {share}{flags}")
        first = census.starts[a.starts[0]]
        rows.append(f"      state ({r.state[0]:+.6f}, {r.state[1]:+.6f}), first reached from "
                    f"({first[0]:+.6f}, {first[1]:+.6f})")  # fmt: skip
        if r.n and r.multipliers is not None:
            mult = ", ".join(f"{m.real:+.6f}{m.imag:+.6f}j (|λ|={abs(m):.6f})"
                             for m in r.multipliers)  # fmt: skip
            rows.append(f"      Floquet multipliers: {mult}")
    if census.unsettled:
        rows.append(f"  {len(census.unsettled)} start(s) settled on no attractor:")
        for i, r in census.unsettled:
            y, v = census.starts[i]
            rows.append(f"      from ({y:+.6f}, {v:+.6f}): {r.label} ({r.status}, "
                        f"{r.revolutions} revolutions)")  # fmt: skip
    rows.append(f"  (cycles matched within {census.match_tol:.0e}, ∞-norm of σn points)")
    return "\n".join(rows)


def fraction_error(fraction: float, count: int) -> float:
    """Binomial standard error of a basin fraction estimated from ``count`` starts."""
    return math.sqrt(max(fraction * (1.0 - fraction), 0.0) / max(count, 1))
