"""The attractor structure of the paper's planes: jobs for hysteresis, multistability and zooms.

Three kinds of job, each built from a plane's job (``setups.plane_job``: the job file
``jobs/<plane>.yaml`` at a size, under a force law) and run into the gallery's and the
report's store directory (``setups.run_plane``: reused when complete):

- ``hysteresis_job``: the plane swept both ways along the paper's path, ``chains:
  {start: continue, direction: both}``: down is the paper's 2-D continuation from its
  starting corner, up its mirror (the first column at the lowest ω, each row from
  there up). ``campar.open`` derives ``hysteresis`` (the two directions on different
  cycles); the multipliers stored type the boundaries of each direction's map;
- ``census_job``: the plane on the census grid (``setups.Size.census``: at size full
  134 × 134, every third cell of the 400 × 400 grid, so every census cell is a cell of
  the plane), with an attractor census of CENSUS_STARTS starts per cell (``attractors``);
- ``zoom_job``: a detail window of a plane (ZOOMS: where the paper's Figs. 2c–e and
  4c–e look, moved to where this model shows the analogous structure), RECOMPUTED at
  ``Size.zoom`` points across the window along the paper's path at that finer spacing:
  its first column is the chain along the second axis at ω = 6.0 from the state the
  plane's path reaches at the window's starting edge (``setups.plane_path_job``), its
  rows run ω down from 6.0 through the window on a grid whose spacing is the window's.
  A zoom never crops a coarser map.
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import JobError
from ..sweep.job import Job
from . import setups

CENSUS_STARTS = 8  # starts per cell of the census maps (K of `attractors`)
CENSUS_CAP = 4  # attractors stored per cell


@dataclass(frozen=True)
class Zoom:
    """A detail window of a plane: its panel key, the paper's figure it stands for, what
    it shows in this model, and its ranges (ω low, high), (second low, high)."""

    key: str  # "c", "d", "e"
    paper: str  # the paper's panel, e.g. "Fig. 2c"
    shows: str
    omega: tuple[float, float]
    second: tuple[float, float]


# The paper's detail panels and this model's windows for them, chosen on the clamp's
# 400 × 400 maps (docs/figures/fig2_*, fig4_*): the model's planes are simpler than the
# paper's (fewer labels, no lingual cascades), so each window sits where the analogous
# transition lies in this model, not at the paper's coordinates (which it does not give).
ZOOMS = {
    "omega_f0": (
        Zoom(
            "c",
            "Fig. 2c",
            "the 1-p group at low speed: 1-0, 1-1 and 1-2 and their "
            "transitions (the paper: 1-p → G/SN → 1-(p+1))",
            (0.15, 1.05),
            (0.01, 0.45),
        ),
        Zoom(
            "d",
            "Fig. 2d",
            "1-1 against 2-2: the tip of the 2-2 domain, where its PD "
            "boundary turns (the paper: the transition domain of 1-1 and 2-2)",
            (2.55, 3.35),
            (0.7, 1.3),
        ),
        Zoom(
            "e",
            "Fig. 2e",
            "the tip of the 2-1 tongue inside 2-2 (the paper: tongues between neighbouring n-p)",
            (4.15, 4.75),
            (1.95, 2.75),
        ),
    ),
    "mu_kn": (
        Zoom(
            "c",
            "Fig. 4c",
            "the 1-p group: 1-1, 1-2 and 1-3 at high μkn (the paper: 1-2 against 1-3)",
            (0.55, 1.55),
            (0.91, 0.95),
        ),
        Zoom(
            "d",
            "Fig. 4d",
            "1-1 against 2-2 at the tip of the 2-2 domain, with the few "
            "chaotic and quasi-periodic cells there (the paper: 1-1 → PD → 2-2 → 4-4 → "
            "chaos, NS at μkn = 0.91)",
            (2.25, 2.85),
            (0.838, 0.878),
        ),
        Zoom(
            "e",
            "Fig. 4e",
            "1-1, 3-2 and 3-1 at high speed, with the chaotic and 4-4 "
            "cells at their corner (the paper: 2-1 against 3-1)",
            (5.15, 5.95),
            (0.852, 0.892),
        ),
    ),
}
ZOOM_PLANES = tuple(ZOOMS)


def _named(data: dict, stem: str, tensile: str) -> dict:
    data["name"] = stem if tensile == setups.LAW else f"{stem}-{tensile}"
    data["store"] = None
    return data


def hysteresis_job(plane: str, size: str = "full", tensile: str = setups.LAW) -> Job:
    """The plane's job swept both ways from the paper's start (``continue``), with the
    multipliers and σn points its hysteresis and typed boundaries need (no Lyapunov
    exponent: the gallery's Lyapunov map comes from the plane's own job); named
    "<plane>_both"."""
    base = setups.plane_job(plane, size, tensile)
    data = base.to_dict()
    data["chains"] = {"start": "continue", "direction": "both"}
    data["outputs"] = [o for o in (*data["outputs"], "multipliers", "sections") if o != "lyapunov"]
    data["outputs"] = list(dict.fromkeys(data["outputs"]))
    return Job.from_dict(
        _named(data, f"{plane}_both", tensile), source=f"{base.name} swept both ways"
    )


BASIN_JOB = "basin_bistable"  # jobs/basin_bistable.yaml: ω = 5.8, μkn = 0.86
BASIN_SMALL = 40  # starts per axis of the small gallery's basin (the job file's: 200)


def basin_job(size: str = "full", tensile: str = setups.LAW) -> Job:
    """The basin of the bistable cell (``jobs/basin_bistable.yaml``) under ``tensile``, its
    own 200 × 200 starts at size full, BASIN_SMALL × BASIN_SMALL at small."""
    from ..sweep.job import load_job

    path = setups.jobs_dir() / f"{BASIN_JOB}.yaml"
    data = load_job(path).to_dict()
    if size != "full":
        for axis in data["sweep"].values():
            axis["points"] = BASIN_SMALL
    data["model"]["tensile"] = tensile
    return Job.from_dict(_named(data, BASIN_JOB, tensile), source=f"{path} at size {size}")


def census_points(size: str) -> int | None:
    """Points per axis of the census grid (None: the plane's own grid)."""
    return setups.SIZES[size].census


def census_job(plane: str, size: str = "full", tensile: str = setups.LAW) -> Job:
    """The plane on the census grid, ω down along the paper's path, with an attractor
    census of CENSUS_STARTS starts at every cell; named "<plane>_census"."""
    base = setups.plane_job(plane, size, tensile)
    data = base.to_dict()
    points = census_points(size)
    if points is not None:
        for axis in data["sweep"].values():
            axis["points"] = points
    data["chains"] = {"start": "continue", "direction": "down"}
    data["outputs"] = ["label", "dc"]
    data["attractors"] = {"starts": CENSUS_STARTS, "cap": CENSUS_CAP}
    return Job.from_dict(
        _named(data, f"{plane}_census", tensile), source=f"{base.name} with an attractor census"
    )


def zoom_of(plane: str, key: str) -> Zoom:
    for zoom in ZOOMS.get(plane, ()):
        if zoom.key == key:
            return zoom
    raise JobError(f"the {plane} plane has no zoom {key!r}")


def zoom_grid(start: float, lo: float, hi: float, points: int) -> dict:
    """An ω axis from the plane's ``start`` (6.0) down to ``lo`` whose spacing is that of
    ``points`` values across [lo, hi] (rounded so that ``start`` and ``lo`` are both on it)."""
    step = (hi - lo) / (points - 1)
    count = int(round(abs(start - lo) / step)) + 1
    return {"from": start, "to": lo, "points": max(count, 2)}


def zoom_job(plane: str, key: str, size: str = "full", tensile: str = setups.LAW) -> Job:
    """A zoom window recomputed along the paper's path at ``Size.zoom`` points across it
    (module docstring); named "<plane>_zoom_<key>". Computes the path's state at the
    window's starting edge (a short chain along the second axis at ω = 6.0)."""
    zoom = zoom_of(plane, key)
    base = setups.plane_job(plane, "full", tensile)
    data = base.to_dict()
    points = setups.SIZES[size].zoom
    name = base.second
    parent = data["sweep"][name]
    lo, hi = zoom.second
    first, last = (hi, lo) if parent["from"] > parent["to"] else (lo, hi)  # the path's order
    omega = data["sweep"]["omega"]
    data["sweep"] = {
        "omega": zoom_grid(omega["from"], *zoom.omega, points),
        name: {"from": first, "to": last, "points": points},
    }
    if first != parent["from"]:  # the state the plane's path reaches at (6.0, first)
        path = setups.plane_path_job(omega["from"], first, tensile, plane)
        y, v = setups.plane_path_state(path)
        data["initial"] = {"y": y, "v": v}
    data["chains"] = {"start": "continue", "direction": "down"}
    data["outputs"] = list(dict.fromkeys([*data["outputs"], "multipliers", "sections"]))
    data["outputs"] = [o for o in data["outputs"] if o != "lyapunov"]
    return Job.from_dict(
        _named(data, f"{plane}_zoom_{key}", tensile),
        source=f"{plane} zoom {key} ({zoom.paper}) at size {size}",
    )


def spacing(job: Job) -> tuple[float, float]:
    """Grid spacing (|Δω|, |Δsecond|) of a job."""
    return float(np.abs(np.diff(job.omega)).min()), float(np.abs(np.diff(job.second_values)).min())


def run(job: Job, stores) -> Path:
    """``setups.run_plane``: compute (or reuse) the job's store under ``stores``."""
    return setups.run_plane(job, stores)
