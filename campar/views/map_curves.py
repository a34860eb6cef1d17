"""Bifurcation curves of a map: seeds from its typed edges, and how well curves and map agree.

``store_seeds`` reads a map store's typed edges (``store_boundaries``) and turns every PD,
SN and G edge into a ``campar.continuation.mapscale.Seed``: the periodic cell on the side
whose cycle bifurcates, with its stored state — for PD the side of the shorter period
(the cycle whose multiplier goes to −1), for SN the side whose multiplier goes to +1
(the cycle that disappears), for G the side computed first. Seeds of one type and period
on neighbouring edges are grouped into one (``group_seeds``).

``agreement`` measures the map against its curves: the share of the map's edges of a
type that lie within one cell of a continued curve of that type, and the share of each
curve's length that has such edges beside it where the map is periodic on both sides.
"""

from dataclasses import dataclass

import numpy as np

from ..continuation.mapscale import SEED_TYPES, Seed, distances_to, group_seeds, in_plane
from ..sweep.job import cell_edges
from .boundaries import Segment, store_boundaries

NEAR_CELLS = 1.0  # "within one cell"


def seed_side(segment: Segment):
    """The side (``transitions.Side``) whose cycle bifurcates at a typed edge, and which it
    is ("before" or "after"); None where neither side is periodic."""
    t = segment.transition
    sides = {"before": t.before, "after": t.after}
    periodic = {k: s for k, s in sides.items() if s.kind == "periodic" and s.multipliers}
    if not periodic:
        return None
    if t.type == "PD" and len(periodic) == 2 and t.before.n != t.after.n:
        key = min(periodic, key=lambda k: periodic[k].n)
    elif t.type in ("PD", "SN") and t.evidence is not None and t.evidence.side in periodic:
        key = t.evidence.side
    elif "before" in periodic:
        key = "before"
    else:
        key = "after"
    return key, periodic[key]


def store_seeds(path, types=SEED_TYPES, *, group: bool = True) -> list[list[Seed]]:
    """The tasks of a map store's curves of ``types`` (PD, SN, G): seeds grouped by curve
    (``group_seeds``), or each seed a task of its own."""
    from ..sweep.store import read_store
    from .dataset import open as open_store

    found = store_boundaries(path)
    second_name = found.second_name
    with read_store(path) as store:
        job = store.job
    with open_store(path) as ds:
        state = np.asarray(ds["state"].values)
        if "direction" in ds["state"].dims:
            state = state[0]  # the down sweep, as store_boundaries types it
        omega = np.asarray(ds["omega"].values, dtype=float)
        second = np.asarray(ds[second_name].values, dtype=float)
    fixed = dict(job.fixed)
    model = job.model.model_dump()
    window = ((float(omega.min()), float(omega.max())), (float(second.min()), float(second.max())))
    spacing = (float(np.abs(np.diff(omega)).mean()) if len(omega) > 1 else 1.0,
               float(np.abs(np.diff(second)).mean()) if len(second) > 1 else 1.0)  # fmt: skip
    seeds = []
    for segment in found.segments:
        if segment.type not in types:
            continue
        chosen = seed_side(segment)
        if chosen is None:
            continue
        key, side = chosen
        cell = segment.before if key == "before" else segment.after
        other = segment.after if key == "before" else segment.before
        row, col = cell
        if not np.all(np.isfinite(state[row, col])):
            continue
        axis = "omega" if segment.axis == "omega" else second_name
        neighbour = omega[other[1]] if axis == "omega" else second[other[0]]
        seeds.append(Seed(
            type=segment.type, n=side.n, p=side.p, cell=(int(row), int(col)),
            parameters={**fixed, "omega": float(omega[col]), second_name: float(second[row])},
            state=(float(state[row, col, 0]), float(state[row, col, 1])), axis=axis,
            neighbour=float(neighbour), plane=("omega", second_name), window=window,
            spacing=spacing, model=model,
        ))  # fmt: skip
    return group_seeds(seeds) if group else [[seed] for seed in seeds]


@dataclass(frozen=True)
class Agreement:
    """How a map's typed edges and the continued curves agree, per type.

    edges_near: of the map's edges of the type, the share within one cell of a curve of
    the type; length_near: of the curves' length inside the map where the map is
    periodic on both sides of the curve, the share with an edge of the type within one
    cell; counts: (edges, curve points judged).
    """

    type: str
    edges_near: float
    length_near: float
    counts: tuple[int, int]

    def to_dict(self) -> dict:
        return {"type": self.type, "edges_near": self.edges_near,
                "length_near": self.length_near, "edges": self.counts[0],
                "curve_points": self.counts[1]}  # fmt: skip


def agreement(found, curves, omega, second, kinds, kind_type: str) -> Agreement:
    """``Agreement`` of the typed edges ``found`` (MapBoundaries) with ``curves`` of type
    ``kind_type``; ``kinds`` (second, omega): the map's kind codes (0: periodic)."""
    omega, second = np.asarray(omega, float), np.asarray(second, float)
    spacing = np.array([np.abs(np.diff(omega)).mean(), np.abs(np.diff(second)).mean()])
    plane = ("omega", found.second_name)
    mine = [c for c in curves if c.type == kind_type]
    points = np.vstack([in_plane(c, plane) for c in mine]) if mine else np.zeros((0, 2))
    edges = [s for s in found.segments if s.type == kind_type]
    centres = np.array([[0.5 * (s.edge[0] + s.edge[2]), 0.5 * (s.edge[1] + s.edge[3])]
                        for s in edges]).reshape(-1, 2)  # fmt: skip
    near = distances_to(centres / spacing, points / spacing) <= NEAR_CELLS + 0.5
    edges_near = float(near.mean()) if len(edges) else float("nan")
    # the curves' points inside the map whose surrounding cells are periodic
    xe, ye = cell_edges(omega), cell_edges(second)
    judged, beside = 0, 0
    for point in points:
        j = np.searchsorted(np.sort(xe), point[0]) - 1
        i = np.searchsorted(np.sort(ye), point[1]) - 1
        if not (0 <= j < len(omega) and 0 <= i < len(second)):
            continue
        jj = j if omega[0] < omega[-1] else len(omega) - 1 - j
        ii = i if second[0] < second[-1] else len(second) - 1 - i
        block = kinds[max(ii - 1, 0) : ii + 2, max(jj - 1, 0) : jj + 2]
        if not (block == 0).all():
            continue
        judged += 1
        if len(centres) and np.min(np.linalg.norm((centres - point) / spacing, axis=1)) <= \
                NEAR_CELLS + 0.5:  # fmt: skip
            beside += 1
    length_near = beside / judged if judged else float("nan")
    return Agreement(kind_type, edges_near, length_near, (len(edges), judged))
