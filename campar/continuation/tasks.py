"""A map's curves as runner tasks: one task a group of seeds, its result fixed-size arrays.

A curves job (``campar curves MAP``, campar.sweep.curves_job) is a grid of tasks ×
points: row t holds the curves task t found, one after the other, each at most ``points``
points long, in ``CURVES_PER_TASK`` slots. A task continues the curve of its first seed
that yields one, then of the first of its seeds that curve does not pass within a cell
of, and so on, so a group of seeds that stands for several curves yields all of them.
The arrays are those of ``CURVE_ARRAYS``; empty points hold the fill values (−1, NaN).
``CURVES_WORK`` is what the runner computes such a job's tiles with (``run_curves_tile``:
plain data in, arrays out, no MPI and no files); the caller hands it to the runner
(``campar.run`` does).
"""

import numpy as np

from ..errors import ContinuationError
from ..sweep.curves_job import CURVE_ARRAYS, CURVES_PER_TASK, FOUND, NONE_FOUND, CurvesWork
from .curves import CURVE_TYPES, BifurcationCurve, CurveSettings
from .mapscale import Seed, curve_from_seed, distances_to, in_plane
from .section_map import SectionMap


def empty_row(points: int) -> dict[str, np.ndarray]:
    """One task's arrays (1, CURVES_PER_TASK × points, …), every point empty."""
    size = CURVES_PER_TASK * points
    row = {}
    for name, (dtype, tail) in CURVE_ARRAYS.items():
        fill = np.nan if np.dtype(dtype).kind == "f" else -1
        row[name] = np.full((1, size, *tail), fill, dtype)
    row["curve_status"][:] = NONE_FOUND
    return row


def task_curves(
    task: list[Seed], *, section_map: SectionMap, settings: CurveSettings
) -> list[BifurcationCurve]:
    """The curves of a task's seeds, at most CURVES_PER_TASK (ContinuationError, naming
    each seed's failure, where none of them yields one)."""
    curves, failures = [], []
    plane, spacing = task[0].plane, np.asarray(task[0].spacing, dtype=float)
    for seed in task:
        if len(curves) == CURVES_PER_TASK:
            break
        if any(near(seed, curve, plane, spacing) for curve in curves):
            continue
        try:
            curves.append(curve_from_seed(seed, section_map=section_map, curve_settings=settings))
        except ContinuationError as exc:
            failures.append(f"cell {seed.cell}: {exc}")
    if not curves:
        raise ContinuationError("; ".join(failures))
    return curves


def near(seed: Seed, curve: BifurcationCurve, plane, spacing) -> bool:
    """True when ``curve`` (of the seed's type and period) passes within a cell and a half
    of the seed's edge."""
    if (curve.type, curve.n) != (seed.type, seed.n):
        return False
    i = plane.index(seed.axis)
    centre = np.array([seed.parameters[plane[0]], seed.parameters[plane[1]]], dtype=float)
    centre[i] = 0.5 * (centre[i] + seed.neighbour)
    return bool(distances_to(centre[None, :] / spacing, in_plane(curve, plane) / spacing)[0] <= 1.5)


def curve_rows(
    tasks: list[list[Seed]], points: int, section_map: SectionMap | None = None
) -> dict[str, np.ndarray]:
    """The arrays (len(tasks), CURVES_PER_TASK × points, …) of these tasks' curves."""
    rows = [empty_row(points) for _ in tasks]
    smap = section_map
    settings = CurveSettings(max_points=points)
    for row, task in zip(rows, tasks, strict=True):
        smap = smap or SectionMap(task[0].model)
        try:
            curves = task_curves(task, section_map=smap, settings=settings)
        except ContinuationError:
            continue
        row["curve_status"][:] = FOUND
        for k, curve in enumerate(curves):
            at = slice(k * points, k * points + len(curve.values))
            row["curve_index"][0, at] = k
            row["curve_type"][0, at] = CURVE_TYPES.index(curve.type)
            row["curve_n"][0, at] = curve.n
            row["curve_p"][0, at] = curve.p
            row["curve_values"][0, at] = in_plane(curve, task[0].plane)
            row["curve_state"][0, at] = curve.states
            row["curve_multipliers"][0, at, :, 0] = curve.multipliers.real
            row["curve_multipliers"][0, at, :, 1] = curve.multipliers.imag
    return {name: np.concatenate([row[name] for row in rows]) for name in CURVE_ARRAYS}


def curves_of_rows(arrays: dict, plane: tuple[str, str]) -> list[dict]:
    """The curves stored in arrays of ``curve_rows``' layout, as plain records (type, n,
    values (N, 2) in the plane, states, multipliers complex (N, 2), p, task)."""
    found = []
    index = np.asarray(arrays["curve_index"])
    for t in range(index.shape[0]):
        for k in sorted(set(index[t][index[t] >= 0].tolist())):
            at = index[t] == k
            mult = np.asarray(arrays["curve_multipliers"])[t, at]
            found.append(
                {
                    "type": CURVE_TYPES[int(np.asarray(arrays["curve_type"])[t, at][0])],
                    "n": int(np.asarray(arrays["curve_n"])[t, at][0]),
                    "p": np.asarray(arrays["curve_p"])[t, at],
                    "values": np.asarray(arrays["curve_values"])[t, at],
                    "states": np.asarray(arrays["curve_state"])[t, at],
                    "multipliers": mult[..., 0] + 1j * mult[..., 1],
                    "plane": plane,
                    "task": t,
                }
            )
    return found


def run_curves_tile(job, tile) -> dict[str, np.ndarray]:
    """The runner's tile of a curves job: its rows' tasks, as ``curve_rows``."""
    tasks = [list(job.curves.tasks[row]) for row in range(tile.row_start, tile.row_stop)]
    return curve_rows(tasks, job.curves.points, SectionMap(curve_model(job)))


def compile_curves(job, share=None) -> None:
    """Compile (or load) the shooting for the job's force law: what a lane does first
    (``share``, the runner's split of a cold compile between ranks, is the kernel's)."""
    SectionMap(curve_model(job))


def curve_model(job) -> dict:
    """The job's model section (force law, cam and contact laws), as a SectionMap takes it."""
    return job.model.model_dump(mode="json")


CURVES_WORK = CurvesWork(tile=run_curves_tile, load=compile_curves)
