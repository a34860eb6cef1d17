"""One cell of a map computed again, exactly as its tile computed it: the reproduction of a
stored cell (``campar point --from``, ``campar.cell``).

A map's cell is the end of a chain: it starts from an extrapolation of the cells before
it along ω and inherits their step control, and the first cell of its chain starts from
the job's initial state or, with ``chains.start: continue``, from the chain along the
second axis. So the cell is replayed from its chain's start: the chain's cells up to the
cell (each depends on those before it alone), from the start ``chain_starts`` gives, with
the job's settings and the row's law. A store keeps no step-control state to restart
from; replaying costs one chain's first cells, and reproduces every stored variable bit
for bit. A basin's cell is one start of its own; a census is computed for the one cell;
a ``separation`` output, a property of the whole row, replays the whole row.
"""

import numpy as np

from .basin import basin_parameters
from .job import DIRECTIONS, Job
from .multistable import run_starts
from .plan import chain_order
from .tile import cell_settings, census_of, run_row, separation_of, solver_options


def replay_cell(job: Job, row: int, col: int, direction: str | None = None) -> dict:
    """Every per-cell array's value at cell (row, col) of ``job`` (a map or a basin), as
    the job's tile computes it — the arrays its store holds, and every other output the
    kernel gave the cell (``sections`` where computed); ``direction``: which of a ``both``
    job's chains (default down). ValueError for a curves job, a cell outside the grid or
    an unknown direction."""
    n_rows, n_cols = job.shape
    if job.kind == "curves":
        raise ValueError(f"job {job.name} computes bifurcation curves: it has no cells to replay")
    if not (0 <= row < n_rows and 0 <= col < n_cols):
        raise ValueError(f"cell ({row}, {col}) is outside the job's {n_rows} × {n_cols} grid")
    if job.kind == "basin":
        start = (job.first_values[col], job.second_values[row])
        records = run_starts(job, basin_parameters(job), [start], job.n_sections)
        return {name: values[0] for name, values in records._asdict().items() if len(values)}
    if job.chains.direction == "both":
        direction = direction or DIRECTIONS[0]
        if direction not in DIRECTIONS:
            raise ValueError(f"direction must be one of {', '.join(DIRECTIONS)}, got {direction!r}")
        job = job.one_direction(direction)
    k = int(np.flatnonzero(chain_order(job) == col)[0])  # the cell's place in its chain
    whole_row = job.wants("separation")
    par, out, law = run_row(job, row, None if whole_row else k + 1)
    one = {name: values[k : k + 1] for name, values in par.items()}
    extra = census_of(job, one, out.state[k : k + 1], law)
    values = {name: v[0] for name, v in extra.items()}
    if whole_row:
        found = separation_of(job, par, out, law, solver_options(job), cell_settings(job))
        values.update({name: v[k] for name, v in found.items()})
    kernel = {name: v[k] for name, v in out._asdict().items() if len(v)}
    return {**kernel, **values}
