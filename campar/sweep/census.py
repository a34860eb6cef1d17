"""Which records of one cell are one attractor: the start spread and the grouping rules.

A census of a cell runs many starts through the kernel and groups the converged
results into distinct attractors. The rules live here, in numpy alone, so that one
cell (``campar point --attractors``, ``campar.views.attractors``), every cell of a map
(a job's ``attractors`` key, ``campar.sweep.multistable``) and the hysteresis of a
``both`` map (``campar.views.cycles``) decide "same attractor" alike, and so that
``campar.open`` uses them without loading the kernel.

- the starts (``spread_starts``): rest, any given ones, then Halton points over a box
  of (y, y') at θ = 0;
- periodic records are one attractor when their σn points agree up to a cyclic shift
  within ``match_tolerance`` (``same_cycles``);
- quasi-periodic or chaotic records when of one kind and their section clouds overlap
  (``clouds_overlap``: a weak test, see there);
- ``group_records``: each settled record compared with the first member of every group
  found so far (as Attractors.jl maps initial conditions for ``basins_fractions``),
  groups ranked by the starts that reached them, most first.
"""

import math

import numpy as np

from ..core.codes import Kind
from .job import DEFAULT_CLASSIFY

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
SETTLED_KINDS = frozenset((int(Kind.PERIODIC), int(Kind.QUASIPERIODIC), int(Kind.CHAOTIC)))

# Two records of one cycle agree within this many times the larger of twice the
# convergence window's tolerance, the kernel's period tolerance and the integrator's rtol.
CYCLE_FACTOR = 5.0


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


def match_tolerance(window_tol: float, period_tol: float, rtol: float = 0.0) -> float:
    """∞-norm distance within which the σn points of two converged records of one cycle
    agree (1e-5 with the default settings).

    A converged cell's cycle estimate lies within ``transient.conv_tol`` of its last
    section point and within ``transient.window_tol`` of the point n revolutions before
    (campar.core.analysis), and the kernel counts σn points within
    ``classify.period_tol`` as one; each stored σn point is thus within about
    window_tol of the cycle, two records of one cycle within about 2·window_tol. Two
    records reached from different starts (other initial states, the two sweep
    directions) differ also by the integrator's error of the cycle (rtol-level,
    amplified by 1/(1 − λ) for a multiplier λ near 1): CYCLE_FACTOR times the larger of
    these covers it. Measured: two records of one cycle ≤ 1.4e-7 apart over 2447 starts
    of 80 cells; distinct coexisting cycles ≥ 1.6 apart, five orders of magnitude beyond.
    """
    return CYCLE_FACTOR * max(2.0 * window_tol, period_tol, rtol)


def cycle_tolerance(job) -> float:
    """``match_tolerance`` with a job's settings (1e-5 with the defaults): how the census
    of a map, a basin and the hysteresis of a ``both`` map match cycles."""
    return match_tolerance(job.transient.window_tol, job.classify.period_tol, job.integrator.rtol)


def same_cycles(n_a, sections_a, n_b, sections_b, tol: float) -> np.ndarray:
    """Per cell: the cycles with σn points ``sections_a[..., :n_a, :]`` and
    ``sections_b[..., :n_b, :]`` (time order) are one, i.e. equal within ``tol``
    (∞-norm) after a cyclic shift. Cycles of different n are compared over lcm(n_a,
    n_b) revolutions, so a 2-cycle whose points coincide is the 1-cycle it repeats.
    Cells where either n < 1 are False; call it on converged periodic cells."""
    n_a, n_b = np.asarray(n_a, np.int64), np.asarray(n_b, np.int64)
    sec_a, sec_b = np.asarray(sections_a, float), np.asarray(sections_b, float)
    shape = n_a.shape
    n_a, n_b = n_a.reshape(-1), n_b.reshape(-1)
    sec_a, sec_b = sec_a.reshape(-1, *sec_a.shape[-2:]), sec_b.reshape(-1, *sec_b.shape[-2:])
    same = np.zeros(n_a.size, bool)
    valid = (n_a >= 1) & (n_b >= 1)
    pairs = np.unique(np.stack([n_a[valid], n_b[valid]]), axis=1)
    for na, nb in pairs.T.tolist():  # one vectorised comparison per pair of periods
        cells = np.flatnonzero(valid & (n_a == na) & (n_b == nb))
        length = math.lcm(na, nb)
        a = sec_a[cells][:, np.arange(length) % na]  # (cells, L, 2)
        b = sec_b[cells][:, np.arange(length) % nb]
        for shift in range(nb):  # b is nb-periodic: shifts beyond repeat these
            gap = np.abs(a - np.roll(b, shift, axis=1)).max(axis=(1, 2))
            same[cells] |= gap <= tol
    return same.reshape(shape)


def same_cycle(a: np.ndarray, b: np.ndarray, tol: float) -> bool:
    """True when the cycles with σn points a and b (each (n, 2), in time order) are one
    orbit: equal within tol (∞-norm) after some cyclic shift (``same_cycles``)."""
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


def same_record(kind_a: int, points_a, kind_b: int, points_b, tol: float) -> bool:
    """Two settled records (kind code, σn points: the cycle's n, or the cloud) are one
    attractor: periodic, one cycle (``same_cycle``); else one kind, overlapping clouds."""
    if kind_a != kind_b:
        return False
    if kind_a == Kind.PERIODIC:
        return same_cycle(points_a, points_b, tol)
    return clouds_overlap(points_a, points_b)


def record_points(kind: int, n: int, sections: np.ndarray) -> np.ndarray:
    """A record's σn points as the grouping compares them: a cycle's first n, a cloud's
    recorded (finite) points; ``sections`` (S, 2) NaN-padded, as the kernel fills it."""
    points = np.asarray(sections, float)[: n if n else len(sections)]
    return points[~np.isnan(points[:, 0])]


def group_records(kinds, points, tol: float, counted: int | None = None):
    """Distinct attractors among records; returns (groups, basin).

    ``kinds``: kind code per record; ``points``: its σn points (``record_points``).
    ``group_cells`` of the records, the points NaN-padded into one array; ``groups`` as
    lists of record indices.
    """
    width = max((len(p) for p in points), default=0)
    sections = np.full((len(points), max(width, 1), 2), np.nan)
    ns = np.zeros(len(points), np.int64)
    for i, (kind, pts) in enumerate(zip(kinds, points, strict=True)):
        sections[i, : len(pts)] = pts
        ns[i] = len(pts) if int(kind) == Kind.PERIODIC else 0
    groups, basin = group_cells(kinds, ns, sections, tol, counted)
    return [group.tolist() for group in groups], basin


BLOCK = 4096  # records compared with a group's first member at once (bounds the memory)


def group_cells(kinds, ns, sections, tol: float, counted: int | None = None):
    """Distinct attractors among records given as arrays; returns (groups, basin).

    ``kinds``, ``ns``: kind code and period per record; ``sections`` (records, S, 2):
    their σn points, NaN-padded, as the kernel fills them (``record_points`` reads them).
    Unsettled records (not periodic, quasi-periodic or chaotic) join no group. Each
    settled record joins the first group whose first member is ``same_record``, or
    starts a new one (as Attractors.jl maps initial conditions for ``basins_fractions``).
    Computed group by group: the first record no group has taken starts one, and every
    later record of its kind not taken yet is compared with it at once, which is the
    same rule record by record. ``groups``: arrays of record indices, ranked by how many
    of the first ``counted`` records (the starts whose shares are basin fractions;
    default all) reached each, most first, ties by first member. ``basin``: per record,
    the index of its group in that order, −1 where unsettled.
    """
    kinds = np.asarray(kinds, np.int64).reshape(-1)
    ns = np.asarray(ns, np.int64).reshape(-1)
    sections = np.asarray(sections, float)
    counted = len(kinds) if counted is None else counted
    found = np.full(len(kinds), -1)
    free = np.isin(kinds, list(SETTLED_KINDS))
    members: list[np.ndarray] = []
    for first in np.flatnonzero(free):
        if not free[first]:
            continue
        free[first] = False
        rest = np.flatnonzero(free & (kinds == kinds[first]))
        rest = rest[rest > first]
        same = np.zeros(len(rest), bool)
        if kinds[first] == Kind.PERIODIC:
            for block in range(0, len(rest), BLOCK):
                cells = rest[block : block + BLOCK]
                same[block : block + BLOCK] = same_cycles(
                    np.full(len(cells), ns[first]),
                    np.broadcast_to(sections[first], (len(cells), *sections.shape[1:])),
                    ns[cells],
                    sections[cells],
                    tol,
                )
        else:
            cloud = record_points(int(kinds[first]), int(ns[first]), sections[first])
            for j, cell in enumerate(rest):
                other = record_points(int(kinds[cell]), int(ns[cell]), sections[cell])
                same[j] = clouds_overlap(cloud, other)
        group = np.concatenate([[first], rest[same]])
        free[group] = False
        members.append(group)
    groups = sorted(members, key=lambda g: (-int(np.sum(g < counted)), int(g[0])))
    for g, group in enumerate(groups):
        found[group] = g
    return groups, found
