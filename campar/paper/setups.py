"""The paper's set-ups as data, and the small computations behind its figures and claims.

The paper (seed/000: a cam with a flat-bottomed follower, Hunt–Crossley
contact) shows three two-parameter planes (its Figs. 2, 4, 7), bifurcation
lines at four μkn (Fig. 5), phase portraits along one of them (Fig. 6), the
penetration ε(t) (Figs. 3, 8) and the contact force with the cam input
(Fig. 9). This module fixes the parameter values of each, where the paper
leaves them open says what was chosen, and computes them:

- planes: the job files ``jobs/{omega_f0,mu_kn,mu_cn}.yaml``, at their own
  400 × 400 (size "full") or on a coarser grid (size "small"), through the
  sweep runner into a store (which resumes, so a second command reuses it);
- lines: one continuation chain each (``campar.views.line``), ω from 6.0 down;
- orbits of the point claims: reached by continuation along ω from 6.0
  (``continued_state``), then traced with ``simulate_point`` from that state;
- orbits of Fig. 6: reached along the paper's path, the (ω, μkn) plane's 2-D
  continuation from its corner (6.0, 0.95) (``plane_path_job``: the plane's grid
  spacing, ending exactly at the cell), traced from that state, together with every
  attractor an attractor census (``campar.views.attractors``) finds at the cell;
- ε(t) and Pn(t) (Figs. 3, 8, 9): ``simulate_point`` from rest, (y, y') = (0, 0)
  at θ = 0 (the paper's initial state; it does not say more).

Every function takes ``tensile`` ("clamp": no tensile force, the product's
definition; "allow": the paper's literal force law).
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import JobError
from ..sweep.job import DEFAULT_MODEL, Job, ModelSettings, field_choices, load_job
from ..views.line import (
    PAPER_START,
    BifurcationLine,
    LineSpec,
    bifurcation_line,
    compute_line,
    compute_lines,
    continued_state,
    line_spec,
)

PLANES = ("omega_f0", "mu_kn", "mu_cn")
TENSILE = field_choices(ModelSettings, "tensile")  # both force laws: clamp, allow
LAW = DEFAULT_MODEL.tensile  # the default force law; its figures and planes get plain names


@dataclass(frozen=True)
class Size:
    """Resolution of a figure set: plane grid (None: the job file's own), line cells, the
    census maps' grid (None: the plane's), the points across a zoom window
    (``campar.paper.structure``) and whether the curves continued over a map are seeded
    from its unknown edges too, typed by shooting (``views.map_curves.store_seeds``)."""

    plane: int | None
    line: int
    census: int | None = None
    zoom: int = 12
    shoot: bool = True


# full: the census on every third cell of the 400 × 400 planes (134 = 399/3 + 1), zooms
# of 120 × 120 cells.
SIZES = {
    "small": Size(plane=48, line=1000, census=24, zoom=40),
    "full": Size(plane=None, line=4000, census=134, zoom=120),
}

# Fig. 5: bifurcation lines at four contact stiffness ratios (f0 = 0.5, μcn = 0.8).
FIG5_MU_KN = (0.94, 0.90, 0.91, 0.922)
LINE_OMEGA = (PAPER_START, 0.02)  # the planes' ω range; the paper's Fig. 5 does not state its own

# Fig. 6: the paper's labels along μkn = 0.91 (f0 = 0.5, μcn = 0.8, ζ = 0.2).
FIG6_MU_KN = 0.91
FIG6_CLAIMS = (
    (2.71, "3-2"),
    (2.709, "chaos"),
    (2.83, "4-4"),
    (3.0, "2-2"),
    (3.15, "1-1"),
    (3.208583, "QP"),
)
CLOUD_REVOLUTIONS = 1500  # σn points of a non-periodic orbit's Poincaré section
FIG6_PLANE = "mu_kn"  # the plane whose 2-D continuation is the paper's path to Fig. 6
FIG6_STARTS = 16  # starts of the attractor census at each Fig. 6 cell

# Figs. 3, 8, 9: time series at three cam speeds. The paper names neither the three
# preloads of Fig. 3 nor the stiffness and damping ratios of Fig. 8; these are chosen
# so that both ratios take the same three values (a like-for-like comparison).
SPEEDS = (1.0, 3.0, 5.0)
FIG3_F0 = (0.5, 1.5, 2.5)
FIG8_F0 = 2.5
FIG8_RATIOS = (0.7, 0.8, 0.9)
FIG9_F0 = 0.5

# Floquet multipliers the paper quotes (its Fig. 5b1, μkn = 0.90) and what it concludes.
QUOTED_MULTIPLIERS = (
    (1.1620, (complex(-0.354351, 0.263715), complex(-0.354351, -0.263715)), "period doubling"),
    (1.4301, (complex(0.263516, 0.0), complex(0.374650, 0.0)), "onset of chaos"),
)
QUOTED_MU_KN = 0.90


def jobs_dir() -> Path:
    """The repository's ``jobs/`` directory (next to the package in a source checkout)."""
    return Path(__file__).resolve().parents[2] / "jobs"


def plane_job(name: str, size: str = "full", tensile: str = LAW, jobs: Path | None = None) -> Job:
    """The job of a plane at a size: ``jobs/<name>.yaml``, its grid coarsened for "small",
    its force law set to ``tensile``, the ``lyapunov`` output added (the gallery draws it);
    named "<name>" or "<name>-allow", store unset."""
    if name not in PLANES:
        raise JobError(f"unknown plane {name!r}; the paper's planes are {', '.join(PLANES)}")
    path = (jobs or jobs_dir()) / f"{name}.yaml"
    data = load_job(path).to_dict()
    points = SIZES[size].plane
    if points is not None:
        for axis in data["sweep"].values():
            axis["points"] = points
    data["model"]["tensile"] = tensile
    if "lyapunov" not in data["outputs"]:  # the gallery's Lyapunov map (≈ 1.4× the cost)
        data["outputs"] = [*data["outputs"], "lyapunov"]
    data["name"] = name if tensile == LAW else f"{name}-{tensile}"
    data["store"] = None
    return Job.from_dict(data, source=f"{path} at size {size}")


def run_plane(job: Job, stores: Path) -> Path:
    """Compute a plane into ``stores/<job name>.zarr`` with the sweep runner (serial, or
    MPI under mpirun) and return the store's path. A finished store of the same job is
    reused as is; one of another version of the job (older settings or campar) is
    replaced: ``stores`` belongs to the gallery and the report, a cache of their planes."""
    from ..errors import StoreMismatch
    from ..sweep.runner import run_job

    path = Path(stores) / f"{job.name}.zarr"
    try:
        run_job(job, path)
    except StoreMismatch:
        run_job(job, path, overwrite=True)
    return path


def paper_lines(size: str = "full", tensile: str = LAW) -> list[BifurcationLine]:
    """The Fig. 5 lines, one per μkn of FIG5_MU_KN, computed side by side."""
    return compute_lines([paper_line_job(mu, size, tensile) for mu in FIG5_MU_KN])


FINE_LINE = (PAPER_START, 2.0, 4001)  # ω from, to, points: steps of 0.001 through Fig. 6's range


def fine_line(mu_kn: float, tensile: str = LAW) -> BifurcationLine:
    """The line at μkn through the paper's Fig. 6 range in steps of 0.001 (any size)."""
    hi, lo, points = FINE_LINE
    return bifurcation_line((hi, lo), points, tensile=tensile, mu_kn=mu_kn)


def paper_line_job(mu_kn: float, size: str = "full", tensile: str = LAW) -> LineSpec:
    """A Fig. 5 line: ω from 6.0 down to 0.02 at μkn, the other parameters at base values."""
    return line_spec(
        LINE_OMEGA, SIZES[size].line, tensile=tensile, mu_kn=mu_kn, name=f"line_mu_kn_{mu_kn:g}"
    )


@dataclass(frozen=True)
class ContinuedPoint:
    """A point reached by continuation from ω = 6.0, its orbit, and (if not periodic)
    the cloud of its σn points over CLOUD_REVOLUTIONS revolutions."""

    result: object  # PointResult with trace, multipliers and Lyapunov exponent
    line: BifurcationLine  # the continuation chain that reached it
    cloud: object  # (m, 2) σn points: the orbit's n points, or a long run's cloud


def continued_point(omega: float, tensile: str = LAW, **params) -> ContinuedPoint:
    """Reach ``omega`` by continuation from 6.0 and trace the attractor found there."""
    from ..views.point import simulate_point

    line, state = continued_state(omega, tensile=tensile, **params)
    result = simulate_point(
        omega,
        y0=state[0],
        v0=state[1],
        tensile=tensile,
        multipliers=True,
        lyapunov=True,
        trace=True,
        **params,
    )
    cloud = np.asarray(result.sections)
    if result.kind != "periodic":
        cloud = section_cloud(omega, state, tensile=tensile, **params)
    return ContinuedPoint(result, line, cloud)


def section_cloud(omega: float, state, revolutions: int = CLOUD_REVOLUTIONS, **options):
    """σn points (m, 2) of ``revolutions`` revolutions from ``state`` (a Poincaré section)."""
    spec = line_spec(
        (omega, omega),
        1,
        initial=state,
        sections=revolutions,
        transient="fixed",
        revolutions=revolutions,
        name="cloud",
        **options,
    )
    points = compute_line(spec).sections[0]
    return points[np.isfinite(points[:, 0])]


def steady_point(omega: float, tensile: str = LAW, **params):
    """``simulate_point`` from rest at θ = 0 with trace (Figs. 3, 8, 9)."""
    from ..views.point import simulate_point

    return simulate_point(omega, tensile=tensile, trace=True, **params)


def plane_path_job(omega: float, second: float, tensile: str = LAW, plane: str = FIG6_PLANE) -> Job:
    """The paper's path to one cell of a plane: the plane's job (its full grid's spacing,
    ``chains: {start: continue, direction: down}``) cut to end exactly at (ω, second).

    Its first column is the chain along the second axis at the plane's first ω from the
    plane's starting corner; its last row, the chain along ω at ``second`` started from
    that column's last state, ends at the cell: the state the 2-D continuation reaches.
    """
    base = plane_job(plane, "full", tensile)
    data = base.to_dict()
    name = base.second
    for axis, target in (("omega", omega), (name, second)):
        grid = data["sweep"][axis]
        start, stop, points = grid["from"], grid["to"], grid["points"]
        step = abs(stop - start) / (points - 1)
        if not min(start, stop) <= target <= max(start, stop):
            raise JobError(f"{axis} = {target:g} is outside the {plane} plane")
        count = max(2, int(np.ceil(abs(target - start) / step - 1e-9)) + 1)
        if target == start:  # the path's first cell itself (a zoom's starting edge)
            count = 1
        data["sweep"][axis] = {"from": start, "to": target, "points": count}
    data["chains"] = {"start": "continue", "direction": "down"}
    data["outputs"] = ["label", "dc", "eps"]
    data["tiles"] = {"rows": 1}
    data["name"] = f"path_{plane}_{omega:g}_{second:g}"
    return Job.from_dict(data, source=f"the {plane} plane's path to ({omega:g}, {second:g})")


def plane_path_state(job: Job) -> tuple[float, float]:
    """(y, y') at θ = 0 after the last cell of ``plane_path_job``'s last row."""
    from ..sweep.plan import Tile
    from ..sweep.tile import run_tile

    rows = job.shape[0]
    cells = run_tile(job, Tile(0, rows - 1, rows))
    y, v = cells["state"][0, -1]
    return float(y), float(v)


@dataclass(frozen=True)
class Portrait:
    """One attractor at a Fig. 6 cell, traced, with its σn cloud when not periodic."""

    result: object  # PointResult with trace, multipliers, Lyapunov exponent
    cloud: object  # (m, 2) σn points
    fraction: float  # share of the census' starts that reached it (NaN: not in the census)
    on_path: bool  # the attractor the paper's path (the plane's continuation) reaches


@dataclass(frozen=True)
class PathCell:
    """A Fig. 6 cell: the path's job and state, and every attractor found there."""

    omega: float
    job: Job  # plane_path_job
    state: tuple[float, float]  # where the path arrives
    portraits: tuple[Portrait, ...]  # the path's attractor first
    starts: int  # census starts
    unsettled: int  # starts that settled on no attractor


def path_cell(
    omega: float,
    second: float = FIG6_MU_KN,
    tensile: str = LAW,
    starts: int | None = None,
    plane: str = FIG6_PLANE,
) -> PathCell:
    """Reach (ω, second) along the plane's path, trace the attractor there, and run an
    attractor census of ``starts`` (default FIG6_STARTS) starts: rest, the path's state,
    Halton points."""
    starts = FIG6_STARTS if starts is None else starts
    from ..views.attractors import find_attractors
    from ..views.point import simulate_point

    job = plane_path_job(omega, second, tensile, plane)
    state = plane_path_state(job)
    params = {
        **{k: job.parameter(k) for k in ("f0", "mu_kn", "mu_cn", "zeta") if k != job.second},
        job.second: second,
    }

    def traced(y, v):
        result = simulate_point(
            omega,
            y0=y,
            v0=v,
            tensile=tensile,
            multipliers=True,
            lyapunov=True,
            trace=True,
            **params,
        )
        cloud = np.asarray(result.sections)
        if result.kind != "periodic":
            cloud = section_cloud(omega, (y, v), tensile=tensile, **params)
        return result, cloud

    census = find_attractors(omega, count=starts, given=[state], tensile=tensile, **params)
    given = 1 if state != (0.0, 0.0) else 0  # spread_starts: rest, then the given state
    on_path = int(census.basin[given])
    path_result, path_cloud = traced(*state)
    fraction = census.attractors[on_path].fraction if on_path >= 0 else float("nan")
    portraits = [Portrait(path_result, path_cloud, fraction, True)]
    for i, attractor in enumerate(census.attractors):
        if i != on_path:
            result, cloud = traced(*attractor.state)
            portraits.append(Portrait(result, cloud, attractor.fraction, False))
    return PathCell(omega, job, state, tuple(portraits), len(census.starts), len(census.unsettled))
