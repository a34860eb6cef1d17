"""Curves at map scale: from a seed cell beside a typed edge of a map to a continued curve.

A map's typed edges (campar.views.boundaries) say where, to within a cell, a PD, SN or G
transition happens. A ``Seed`` (campar.sweep.curves_job.SeedSettings: as a curves job
stores it) is such an edge reduced to plain data: the periodic cell on the side whose
orbit bifurcates (its type, period and detachments, its cell, parameters and stored
state), the edge's axis and the neighbouring cell's value along it, the plane, its
window and cell spacing, the map's model, and how many edges it stands for.
``curve_from_seed`` is what a runner's task does with it, a plain function of plain data:

1. Newton's method on Pⁿ from the cell's stored state gives its n-cycle (the map's state
   is accurate to its rtol; the fixed point to 1e-10);
2. the cycle's branch is continued along the edge's axis across the two cells, with steps
   of a quarter cell, and the special point of the seed's type between them is located
   (to 1e-10);
3. the curve of that point is continued in the plane across the window, both ways.

Seeds on one curve (neighbouring edges of one type and period) are merged before they run
(``group_seeds``); curves that two seeds still found twice are merged after
(``merge_curves``): what is left is one curve per bifurcation set in the window.
"""

import numpy as np

from ..errors import ContinuationError
from ..sweep.curves_job import SEED_TYPES  # noqa: F401 (its home for the continuation)
from ..sweep.curves_job import SeedSettings as Seed
from .branch import BranchSettings, continue_branch
from .curves import BifurcationCurve, CurveSettings, continue_curve
from .orbit import find_cycle
from .section_map import SectionMap

GROUP_CELLS = 6  # seed cells of one type and period this close (in cells) are one task
CANDIDATES = 8  # seeds of a group tried in turn (those a found curve passes near are skipped)
SAME_CURVE_CELLS = 1.5  # a curve whose points all lie this close to another is that curve


def group_seeds(seeds: list[Seed]) -> list[list[Seed]]:
    """Groups of seeds of one type and period whose cells lie within GROUP_CELLS of each
    other (transitively), each a task: its middle seed first, then up to
    CANDIDATES − 1 others spread over the group, tried in turn where the one before finds
    no point; every one carries the group's size in ``cells``. Deterministic: groups in the
    order of their first seed."""
    parent = list(range(len(seeds)))

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    by_kind: dict[tuple, list[int]] = {}
    for i, seed in enumerate(seeds):
        by_kind.setdefault((seed.type, seed.n), []).append(i)
    for members in by_kind.values():
        cells = np.array([seeds[i].cell for i in members])
        for a in range(len(members)):
            near = np.max(np.abs(cells[a + 1 :] - cells[a]), axis=1) <= GROUP_CELLS
            for b in np.nonzero(near)[0]:
                parent[root(members[a + 1 + b])] = root(members[a])
    groups: dict[int, list[int]] = {}
    for i in range(len(seeds)):
        groups.setdefault(root(i), []).append(i)
    tasks = []
    for members in sorted(groups.values(), key=min):
        order = [members[len(members) // 2]]
        for q in np.linspace(0, len(members) - 1, CANDIDATES + 1).round().astype(int):
            if members[q] not in order and len(order) < CANDIDATES:
                order.append(members[q])
        tasks.append([seeds[i].model_copy(update={"cells": len(members)}) for i in order])
    return tasks


def curve_from_seed(
    seed: Seed,
    *,
    section_map: SectionMap | None = None,
    curve_settings: CurveSettings | None = None,
) -> BifurcationCurve:
    """The curve of ``seed``'s type through the edge it stands for (ContinuationError when
    no such point lies between the seed cell and its neighbour)."""
    smap = section_map or SectionMap(seed.model)
    orbit = find_cycle(seed.n, seed.state, section_map=smap, **seed.parameters)
    start = seed.parameters[seed.axis]
    axis_index = seed.plane.index(seed.axis)
    h = abs(seed.neighbour - start) or seed.spacing[axis_index]
    lo, hi = sorted((start, seed.neighbour))
    window = (lo - 2.0 * h, hi + 2.0 * h)
    branch = continue_branch(
        orbit,
        seed.axis,
        window,
        direction=1.0 if seed.neighbour > start else -1.0,
        section_map=smap,
        settings=BranchSettings(step=h / 4, max_step=h / 4, max_points=60),
    )
    found = [sp for sp in branch.special if sp.type == seed.type]
    if not found:
        seen = ", ".join(f"{sp.type} at {sp.value:.6g}" for sp in branch.special) or "none"
        raise ContinuationError(
            f"no {seed.type} point of the {orbit.label} cycle between {seed.axis}={start:.6g} "
            f"and {seed.neighbour:.6g} (special points met: {seen})"
        )
    sp = min(found, key=lambda s: abs(s.value - 0.5 * (start + seed.neighbour)))
    second = seed.plane[1 - seed.plane.index(sp.parameter)]
    windows = {seed.plane[0]: seed.window[0], seed.plane[1]: seed.window[1]}
    return continue_curve(
        sp,
        second,
        (windows[sp.parameter], windows[second]),
        section_map=smap,
        settings=curve_settings,
    )


def curve_from_task(
    task: list[Seed],
    *,
    section_map: SectionMap | None = None,
    curve_settings: CurveSettings | None = None,
) -> BifurcationCurve:
    """The curve of the first seed of ``task`` that yields one (ContinuationError naming
    each seed's failure when none does)."""
    smap = section_map or SectionMap(task[0].model)
    failures = []
    for seed in task:
        try:
            return curve_from_seed(seed, section_map=smap, curve_settings=curve_settings)
        except ContinuationError as exc:
            failures.append(f"cell {seed.cell}: {exc}")
    raise ContinuationError("; ".join(failures))


def in_plane(curve: BifurcationCurve, plane: tuple[str, str]) -> np.ndarray:
    """The curve's points as (ω, second) of ``plane``, whichever parameter it was seeded on."""
    if (curve.first, curve.second) == plane:
        return curve.values
    return curve.values[:, ::-1]


def merge_curves(curves: list[BifurcationCurve], plane, spacing) -> list[int]:
    """Indices of the curves to keep: a curve whose points all lie within SAME_CURVE_CELLS
    cells of a kept curve of the same type and period is that curve (the longer kept)."""
    order = sorted(range(len(curves)), key=lambda i: (-len(curves[i].values), i))
    scale = np.asarray(spacing, dtype=float)
    kept: list[int] = []
    for i in order:
        mine = in_plane(curves[i], plane) / scale
        duplicate = False
        for k in kept:
            if (curves[k].type, curves[k].n) != (curves[i].type, curves[i].n):
                continue
            theirs = in_plane(curves[k], plane) / scale
            if distances_to(mine, theirs).max() <= SAME_CURVE_CELLS:
                duplicate = True
                break
        if not duplicate:
            kept.append(i)
    return sorted(kept)


def distances_to(points: np.ndarray, polyline: np.ndarray) -> np.ndarray:
    """Distance of each point to the nearest vertex of ``polyline`` (both in cell units;
    vertices lie a fraction of a cell apart, so this is the distance to the curve)."""
    if len(polyline) == 0:
        return np.full(len(points), np.inf)
    out = np.empty(len(points))
    for start in range(0, len(points), 256):
        block = points[start : start + 256]
        d = np.linalg.norm(block[:, None, :] - polyline[None, :, :], axis=2)
        out[start : start + 256] = d.min(axis=1)
    return out
