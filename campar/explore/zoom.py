"""A zoom that computes: a rectangle of a map run again on a grid of its own.

The zoom is a job of the same model as the map — every setting of the map's job kept,
the sweep narrowed to the rectangle at ``points`` × ``points`` cells, the first chain
started from the map's stored final state at the rectangle's starting corner (so it
follows the map's attractor, not a start from rest) — run by ``campar run`` in a child
process (under ``mpirun`` on ``ranks`` ranks where the venv has it): resumable,
verified, stored beside the map in ``<map>.zooms/<job>-<digest>.zarr`` with its job
file and run log. The same rectangle asked again finds the same store and resumes it.
"""

import subprocess
import sys
from pathlib import Path

import numpy as np
import yaml

from ..errors import JobError
from ..sweep.job import Job
from .source import MapSource, stored_cell

MAX_POINTS = 400  # cells along each side of a zoom's grid


def zoom_job(source: MapSource, box, points: int) -> Job:
    """The job of a zoom of ``source`` over ``box`` = (x0, x1, y0, y1), points × points."""
    if not 2 <= points <= MAX_POINTS:
        raise JobError(f"a zoom has 2 to {MAX_POINTS} points a side, got {points}")
    job = source.job
    x0, x1, y0, y1 = box
    lo_x, hi_x = source.x_edges[0], source.x_edges[-1]
    lo_y, hi_y = source.y_edges[0], source.y_edges[-1]
    x0, x1, y0, y1 = max(x0, lo_x), min(x1, hi_x), max(y0, lo_y), min(y1, hi_y)
    if not (x0 < x1 and y0 < y1):
        raise JobError("the zoom's rectangle lies outside the map")
    xs, ys = job.first_values, job.second_values
    # the map's own order along each axis (ω decreasing in the paper's planes)
    fx = (x1, x0) if xs[0] > xs[-1] else (x0, x1)
    fy = (y1, y0) if len(ys) > 1 and ys[0] > ys[-1] else (y0, y1)
    row = int(np.abs(ys - fy[0]).argmin())
    col = int(np.abs(xs - fx[0]).argmin())
    _, corner = stored_cell(source.path, row, col)
    state = [float(a) for a in corner["state"]]
    data = job.to_dict()
    data.update(
        sweep={
            job.first: {"from": float(fx[0]), "to": float(fx[1]), "points": points},
            job.second: {"from": float(fy[0]), "to": float(fy[1]), "points": points},
        },
        initial={"y": state[0], "v": state[1]} if all(map(np.isfinite, state)) else data["initial"],
        store=None,
    )
    data.pop("curves", None)
    data["name"] = f"{job.name}-zoom"
    named = Job.from_dict(data, source="zoom")
    data["name"] = f"{job.name}-zoom-{named.digest()[:10]}"
    return Job.from_dict(data, source="zoom")


def zoom_store(source: MapSource, job: Job) -> Path:
    return source.path.parent / f"{source.path.name}.zooms" / f"{job.name}.zarr"


def start_zoom(source: MapSource, job: Job, ranks: int = 2) -> tuple[Path, subprocess.Popen]:
    """Run the zoom's job into its store beside the map: (store, the run's process)."""
    store = zoom_store(source, job)
    store.parent.mkdir(exist_ok=True)
    data = {**job.to_dict(), "store": str(store)}
    job_file = store.with_suffix(".yaml")
    job_file.write_text(yaml.safe_dump(data, sort_keys=False))
    mpirun = Path(sys.executable).parent / "mpirun"
    command = [sys.executable, "-m", "campar.cli", "run", str(job_file)]
    if ranks > 1 and mpirun.exists():
        command = [str(mpirun), "-n", str(ranks), *command]
    log = store.with_suffix(".log").open("ab")
    process = subprocess.Popen(
        command, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL
    )
    log.close()
    return store, process
