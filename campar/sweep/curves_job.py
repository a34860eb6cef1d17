"""A curves job: a map's bifurcation curves as tasks the runner hands out and stores.

``campar curves MAP`` seeds curves from a map store's typed edges (campar.views.map_curves)
and runs them as a job of its own: a grid of ``tasks`` × ``points`` (sweep keys ``point``
and ``task``), every task a row, every tile one task, so the runner schedules them
dynamically, checksums and commits each like a tile, resumes and runs under MPI as it does
a map. Row t holds the curves task t found, ``CURVES_PER_TASK`` slots of ``points`` points
each (``CURVE_ARRAYS``). The seeds are part of the job (its ``curves.tasks``), so a store
is resumed only by the job that made it, and a map changed since is a different job.

The task's computation belongs to campar.continuation (a layer above this one): its
caller hands it to the runner as a ``CurvesWork`` (campar.continuation.tasks.CURVES_WORK;
``campar.run`` does), so this layer imports nothing above it and holds no table that an
import must fill first.
"""

from collections.abc import Callable
from typing import Annotated, Literal, NamedTuple

import numpy as np
from pydantic import Field, model_validator

from ..model.settings import MAX_COUNT, MAX_POINTS, Settings

CURVE_AXES = ("point", "task")  # a curves job's sweep keys: columns, rows
CURVES_PER_TASK = 3  # curves a task may find (a group of seeds may stand for several)
CURVE_TYPES = ("PD", "SN", "NS", "G")  # the codes of curve_type, in order
SEED_TYPES = ("PD", "SN", "G")  # the map types a curve is seeded from (the model has no NS)

# dtype and trailing shape of each per-point array of a curves job
CURVE_ARRAYS = {
    "curve_index": (np.int8, ()),
    "curve_type": (np.int8, ()),
    "curve_n": (np.int32, ()),
    "curve_p": (np.int32, ()),
    "curve_values": (np.float64, (2,)),
    "curve_state": (np.float64, (2,)),
    "curve_multipliers": (np.float64, (2, 2)),
    "curve_status": (np.int8, ()),
}
CURVE_TAIL_DIMS = {
    "curve_values": ("plane_axis",),
    "curve_state": ("component",),
    "curve_multipliers": ("multiplier", "part"),
}
FOUND, NONE_FOUND = 0, 1  # curve_status

# What a reader of the store needs to know of each array (as arrays.ARRAY_DOCS).
CURVE_ARRAY_DOCS = {
    "curve_index": (
        "curve of the task",
        None,
        "which of the task's curves the point belongs to; -1: no point here",
    ),
    "curve_type": (
        "bifurcation type of the curve",
        None,
        "0 PD (a multiplier -1), 1 SN (fold, +1), 2 NS (a complex pair on the unit "
        "circle), 3 G (grazing: an extremum of the penetration at 0)",
    ),
    "curve_n": ("period of the cycles on the curve", "1", "cam revolutions"),
    "curve_p": (
        "detachments per period on the curve",
        "1",
        "at the point (for G: the count on one side, p changes across the curve)",
    ),
    "curve_values": (
        "the point in the map's plane",
        "1",
        "(omega, the map's second parameter) of the curve's point",
    ),
    "curve_state": (
        "the cycle's state at θ = 0",
        "1",
        "(y, ydot) of the cycle at the point, units of the stroke h and h·ωn",
    ),
    "curve_multipliers": (
        "Floquet multipliers of the cycle",
        "1",
        "eigenvalues of DP^n at the point, largest modulus first",
    ),
    "curve_status": (
        "whether the task found a curve",
        None,
        "0: its curves are stored; 1: none of its seeds gave one",
    ),
}


class SeedSettings(Settings):
    """One seed of a task: a map's typed edge as plain data (campar.continuation.mapscale).

    type: PD, SN or G; n, p: the seed cell's cycle; cell: its (row, column) in the map;
    parameters: every model parameter there; state: its stored (y, y') at θ = 0; axis:
    the parameter along which the edge lies, whose value at the neighbouring cell is
    ``neighbour``; plane: (omega, second); window: the plane's ranges; spacing: the cell
    spacing along both axes; model: the map's model section; cells: the edges it stands
    for.
    """

    type: Literal["PD", "SN", "G"]
    n: Annotated[int, Field(ge=1, le=MAX_COUNT)]
    p: Annotated[int, Field(ge=0, le=MAX_COUNT)]
    cell: tuple[int, int]
    parameters: dict[str, float]
    state: tuple[float, float]
    axis: str
    neighbour: float
    plane: tuple[str, str]
    window: tuple[tuple[float, float], tuple[float, float]]
    spacing: tuple[float, float]
    model: dict
    cells: Annotated[int, Field(ge=1)] = 1


class CurvesSettings(Settings):
    """The curves of a map: where it was seeded from, its plane, the curve types, the
    points of a curve at most, and the tasks (each a list of seeds tried in turn)."""

    map: str
    plane: tuple[str, str]
    types: tuple[Literal["PD", "SN", "G"], ...]
    points: Annotated[int, Field(ge=2, le=MAX_POINTS)]
    tasks: tuple[tuple[SeedSettings, ...], ...] = Field(min_length=1)

    @model_validator(mode="after")
    def every_task_seeded(self):
        for i, task in enumerate(self.tasks):
            if not task:
                raise ValueError(f"tasks[{i}] has no seed")
        return self


def check_curves_job(job) -> None:
    """ValueError unless a curves job's sweep is (point, task) sized to its tasks and
    ``points``, and the two come together."""
    if (job.curves is not None) == (tuple(job.sweep) == CURVE_AXES):
        return
    if job.curves is None:
        raise ValueError(
            f"a sweep over {', '.join(CURVE_AXES)} is a curves job: it needs "
            "curves: (campar curves MAP writes it)"
        )
    raise ValueError(f"curves: needs the sweep {', '.join(CURVE_AXES)} (campar curves MAP)")


def check_curves_axes(job) -> None:
    if job.curves is None:
        return
    columns = CURVES_PER_TASK * job.curves.points
    if job.shape != (len(job.curves.tasks), columns):
        raise ValueError(
            f"sweep: a curves job of {len(job.curves.tasks)} tasks and "
            f"{job.curves.points} points is {len(job.curves.tasks)} task × "
            f"{columns} point, got {job.shape[0]} × {job.shape[1]}"
        )


def curves_job_data(
    map_job, map_path: str, tasks: list[list[dict]], *, types, points: int, store: str
) -> dict:
    """The job (as a mapping, for Job.from_dict) that runs these tasks of ``map_job``'s
    curves into ``store``."""
    plane = ("omega", map_job.second)
    columns = CURVES_PER_TASK * points
    return {
        "name": f"{map_job.name}_curves",
        "sweep": {
            "point": {"from": 0, "to": columns - 1, "points": columns},
            "task": {"from": 0, "to": max(len(tasks) - 1, 0), "points": len(tasks)},
        },
        "fixed": {k: v for k, v in map_job.fixed.items() if k not in plane},
        "model": map_job.model.model_dump(mode="json"),
        "integrator": map_job.integrator.model_dump(mode="json"),
        "curves": {
            "map": str(map_path),
            "plane": list(plane),
            "types": list(types),
            "points": points,
            "tasks": tasks,
        },
        "tiles": {"rows": 1},
        "store": store,
    }


class CurvesWork(NamedTuple):
    """What computes a curves job's tiles, handed to the runner by its caller (the
    kernel computes every other kind's): ``tile(job, Tile)`` → the arrays of the tile's
    rows; ``load(job, share)`` → None, the compile a lane does ahead of its first tile."""

    tile: Callable
    load: Callable


NOT_THE_KERNELS = (
    "a curves job's tiles are computed by campar.continuation.tasks.CURVES_WORK, "
    "not the kernel: run it with campar.run (or run_job(..., tile_work=CURVES_WORK))"
)
