"""A basin of attraction: one parameter point, every cell of the grid a start of its own.

A basin job sweeps the initial state (y0, ydot0) at θ = 0 over a box (``BASIN_AXES``)
with every model parameter fixed. Each cell is run from its own start to its steady
motion as ``campar point --attractors`` runs each of its starts (the job's settings,
chaos called only at the end of the budget, the census's outputs: window statistics,
a whole read window of σn points, multipliers), so a basin cell is bit for bit the
record ``find_attractors`` makes of that start. The runner tiles, distributes,
stores and resumes a basin like a map; no cell depends on another, so the numbers
never depend on the ranks or on interruptions. Which attractor each cell reached is
decided when the store is read (``campar.views.basins``), by the census's rules.
"""

import numpy as np

from .job import Job
from .multistable import run_starts
from .plan import Tile


def basin_parameters(job: Job) -> dict[str, np.ndarray]:
    """The fixed parameters of a basin job as one-cell arrays, as ``run_chain`` takes them."""
    return {
        name: np.array([job.parameter(name)]) for name in ("omega", "zeta", "f0", "mu_kn", "mu_cn")
    }


def run_basin_tile(job: Job, tile: Tile, names: list[str]) -> dict[str, np.ndarray]:
    """Every cell of a basin tile, each a one-cell chain from its (y0, ydot0)
    (``multistable.run_starts``): arrays ``names`` shaped (tile rows, y0 points, …)."""
    cell = basin_parameters(job)
    y0, ydot0 = job.first_values, job.second_values
    rows = [
        run_starts(job, cell, [(y, ydot0[row]) for y in y0], job.n_sections)
        for row in range(tile.row_start, tile.row_stop)
    ]
    return {name: np.stack([getattr(records, name) for records in rows]) for name in names}
