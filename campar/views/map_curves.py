"""Bifurcation curves of a map: seeds from its typed edges, and how well curves and map agree.

``store_seeds`` reads a map store's typed edges (``store_boundaries``) and turns every PD,
SN and G edge into seeds (``campar.continuation.mapscale.Seed``): the periodic cell on the
side whose cycle bifurcates, with its stored state — for PD the side of the shorter
period (the cycle whose multiplier goes to −1), for SN the side whose multiplier goes to
+1 (the cycle that disappears), for G each periodic side. Seeds of one type and period
on neighbouring edges are grouped into one task (``group_seeds``). With ``shoot`` (the
default of ``campar curves`` and the report) the edges the map cannot type between two
periodic cells are typed by shooting first (``views.shot_edges``), so a curve whose only
trace in the map is such an edge gets its seed too; without, the seeds come from the
edges the stored data types, at no cost beyond reading the store.

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


def seed_sides(segment: Segment) -> list:
    """The sides (key "before"/"after", ``transitions.Side``) whose cycle bifurcates at a
    typed edge, the likeliest first: for PD the side of the shorter period, for PD and SN
    the side whose multiplier approaches the critical value; for G both periodic sides
    (either cycle's branch can meet the grazing); [] where neither side is periodic."""
    t = segment.transition
    sides = {"before": t.before, "after": t.after}
    periodic = {k: s for k, s in sides.items() if s.kind == "periodic" and s.multipliers}
    if not periodic:
        return []
    if t.type == "PD" and len(periodic) == 2 and t.before.n != t.after.n:
        key = min(periodic, key=lambda k: periodic[k].n)
        return [(key, periodic[key])]
    if t.type in ("PD", "SN") and t.evidence is not None and t.evidence.side in periodic:
        return [(t.evidence.side, periodic[t.evidence.side])]
    return list(periodic.items())


def store_seeds(
    path, types=SEED_TYPES, *, group: bool = True, shoot: bool = True
) -> list[list[Seed]]:
    """The tasks of a map store's curves of ``types`` (PD, SN, G): seeds grouped by curve
    (``group_seeds``), or each seed a task of its own. ``shoot``: seed from the unknown
    edges between periodic cells too, typed by shooting (two Newton solves and a
    continuation an edge: most of the cost on a coarse map, whose edges are mostly
    unknown); False seeds only from the edges the stored data types."""
    from ..sweep.store import read_store
    from .dataset import open as open_store

    found = store_boundaries(path, shoot=shoot)
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
    model = job.model.model_dump(mode="json")
    window = ((float(omega.min()), float(omega.max())), (float(second.min()), float(second.max())))
    spacing = (
        float(np.abs(np.diff(omega)).mean()) if len(omega) > 1 else 1.0,
        float(np.abs(np.diff(second)).mean()) if len(second) > 1 else 1.0,
    )
    seeds = []
    for segment in found.segments:
        if segment.type not in types:
            continue
        for key, side in seed_sides(segment):
            cell = segment.before if key == "before" else segment.after
            other = segment.after if key == "before" else segment.before
            row, col = cell
            if not np.all(np.isfinite(state[row, col])):
                continue
            axis = "omega" if segment.axis == "omega" else second_name
            neighbour = omega[other[1]] if axis == "omega" else second[other[0]]
            seeds.append(
                Seed(
                    type=segment.type,
                    n=side.n,
                    p=side.p,
                    cell=(int(row), int(col)),
                    parameters={
                        **fixed,
                        "omega": float(omega[col]),
                        second_name: float(second[row]),
                    },
                    state=(float(state[row, col, 0]), float(state[row, col, 1])),
                    axis=axis,
                    neighbour=float(neighbour),
                    plane=("omega", second_name),
                    window=window,
                    spacing=spacing,
                    model=model,
                )
            )
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
        return {
            "type": self.type,
            "edges_near": self.edges_near,
            "length_near": self.length_near,
            "edges": self.counts[0],
            "curve_points": self.counts[1],
        }


def agreement(found, curves, grid, kind_type: str) -> Agreement:
    """``Agreement`` of the typed edges ``found`` (MapBoundaries) with ``curves`` of type
    ``kind_type``. ``grid``: the map's omega and second axes and its kind and n arrays
    (second, omega). A curve's point is judged where the map shows the curve's cycles on
    both sides of it — in the 3 × 3 cells around it every cell periodic, and of the
    curve's period (for PD, of the doubled period too) — and is beside an edge where a
    typed edge of the map lies within one cell."""
    omega, second = np.asarray(grid["omega"], float), np.asarray(grid["second"], float)
    kinds, periods = np.asarray(grid["kind"]), np.asarray(grid["n"])
    spacing = np.array([np.abs(np.diff(omega)).mean(), np.abs(np.diff(second)).mean()])
    plane = ("omega", found.second_name)
    mine = [c for c in curves if c.type == kind_type]
    edges = [s for s in found.segments if s.type == kind_type]
    centres = np.array(
        [[0.5 * (s.edge[0] + s.edge[2]), 0.5 * (s.edge[1] + s.edge[3])] for s in edges]
    ).reshape(-1, 2)
    points = np.vstack([in_plane(c, plane) for c in mine]) if mine else np.zeros((0, 2))
    near = distances_to(centres / spacing, points / spacing) <= NEAR_CELLS + 0.5
    edges_near = float(near.mean()) if len(edges) else float("nan")
    xe, ye = np.sort(cell_edges(omega)), np.sort(cell_edges(second))
    judged, beside = 0, 0
    for curve in mine:
        for point in in_plane(curve, plane):
            j, i = np.searchsorted(xe, point[0]) - 1, np.searchsorted(ye, point[1]) - 1
            if not (0 <= j < len(omega) and 0 <= i < len(second)):
                continue
            jj = j if omega[0] < omega[-1] else len(omega) - 1 - j
            ii = i if second[0] < second[-1] else len(second) - 1 - i
            block = (slice(max(ii - 1, 0), ii + 2), slice(max(jj - 1, 0), jj + 2))
            shown = set(periods[block][kinds[block] == 0].tolist())
            wanted = {curve.n, 2 * curve.n} if kind_type == "PD" else {curve.n}
            if not ((kinds[block] == 0).all() and wanted <= shown):
                continue
            judged += 1
            distance = np.linalg.norm((centres - point) / spacing, axis=1)
            beside += bool(len(centres)) and distance.min() <= NEAR_CELLS + 0.5
    length_near = beside / judged if judged else float("nan")
    return Agreement(kind_type, edges_near, length_near, (len(edges), judged))


def curves_store_path(map_path) -> str:
    """Where ``campar curves`` keeps a map's curves: beside it, ``-curves`` before the
    suffix (results/mu_kn.zarr → results/mu_kn-curves.zarr)."""
    from pathlib import Path

    path = Path(map_path)
    return str(path.with_name(f"{path.stem}-curves{path.suffix}"))


def curves_job(map_path, types=SEED_TYPES, *, points: int = 400, store=None, shoot: bool = True):
    """The curves job of a map store: its seeds grouped into tasks (``store_seeds``, with
    ``shoot`` as there), as a validated Job (campar.sweep.curves_job) that ``campar.run``
    runs."""
    from ..errors import JobError
    from ..sweep.curves_job import curves_job_data
    from ..sweep.job import Job
    from ..sweep.store import read_store

    with read_store(map_path) as reader:
        map_job = reader.job
    if map_job.kind != "map":
        raise JobError(f"{map_path} is a {map_job.kind} store: curves are seeded from a map")
    tasks = store_seeds(map_path, types, shoot=shoot)
    if not tasks:
        raise JobError(
            f"{map_path}: no typed edge of {', '.join(types)} to seed a curve from "
            "(the map needs the multipliers output for PD and SN)"
        )
    data = curves_job_data(
        map_job,
        str(map_path),
        [[s.model_dump(mode="json") for s in t] for t in tasks],
        types=types,
        points=points,
        store=str(curves_store_path(map_path) if store is None else store),  # "" refused
    )
    return Job.from_dict(data, source=f"curves of {map_path}")


def read_curves(path, *, merge: bool = True) -> list:
    """The curves of a curves store (``campar curves``), or of the map store beside which
    ``campar curves`` put them: the curves (``BifurcationCurve``) in the map's plane, of the
    committed tasks whose checksums hold, each curve once (``merge_curves``) unless
    ``merge`` is False."""
    from pathlib import Path

    from ..continuation.curves import BifurcationCurve
    from ..continuation.mapscale import merge_curves
    from ..continuation.tasks import curves_of_rows
    from ..sweep.store import read_store, verify_store

    target = Path(path)
    with read_store(target) as reader:
        if reader.job.kind == "map":
            target = Path(curves_store_path(path))
    rows: dict[int, dict] = {}
    with read_store(target) as reader:
        job = reader.job
        if job.kind != "curves":
            raise ValueError(f"{target} holds no curves")

        def take(check):  # a committed task whose checksum holds
            rows[check.tile.row_start] = {
                k: v for k, v in check.arrays.items() if k.startswith("curve_")
            }

        verify_store(reader, take)
    if not rows:
        return []
    arrays = {
        name: np.concatenate([rows[r][name] for r in sorted(rows)]) for name in rows[min(rows)]
    }
    plane = tuple(job.curves.plane)
    found = [
        BifurcationCurve(
            type=c["type"],
            n=c["n"],
            first=plane[0],
            second=plane[1],
            parameters=dict(job.fixed),
            model=job.model.model_dump(mode="json"),
            values=c["values"],
            states=c["states"],
            multipliers=c["multipliers"],
            p=c["p"],
            end="stored",
            extra={"task": sorted(rows)[c["task"]]},
        )
        for c in curves_of_rows(arrays, plane)
    ]
    if not merge:
        return found
    spacing = job.curves.tasks[0][0].spacing
    return [found[i] for i in merge_curves(found, plane, spacing)]


def curves_beside(map_path, types=SEED_TYPES, *, shoot: bool = True) -> list:
    """The map's curves of ``types``: computed into the store beside it where not there
    yet (``campar curves``, serial or under mpirun as the caller runs; ``shoot`` as in
    ``store_seeds``), then read back (``read_curves``); [] where the map has no typed edge
    to seed from."""
    from ..continuation.tasks import CURVES_WORK
    from ..errors import JobError
    from ..sweep.runner import run_job

    try:
        job = curves_job(map_path, types, shoot=shoot)
    except JobError:
        return []
    run_job(job, tile_work=CURVES_WORK)
    return read_curves(map_path)


def describe_curves(curves) -> str:
    """ "2 PD of 1-cycles, 1 SN of 3-cycles": how many curves of each type and period."""
    counts: dict[str, int] = {}
    for c in curves:
        key = f"{c.type} of {c.n}-cycles"
        counts[key] = counts.get(key, 0) + 1
    return ", ".join(f"{v} {k}" for k, v in sorted(counts.items())) or "none"
