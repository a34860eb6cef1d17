"""From a validated job to kernel calls: settings, output buffers, ``run_tile``.

``run_tile(job, tile)`` is the worker task of every runner (serial and MPI):
a plain function of plain data with no MPI and no files inside. Where each
chain starts (``chain_starts``) depends on the job alone, so the numbers do not
depend on the number of ranks or on interruptions.
"""

import numpy as np

from ..core.jitcache import ensure_fresh_cache, located_cache_dir  # noqa: F401 (runner's)
from ..core.kernel import CellOutputs, CellSettings
from ..core.model import N_STATE
from ..core.revolution import make_trace
from ..core.tracer import trace_orbit
from ..model import compute
from ..model.compute import allocate_outputs, output_bits  # noqa: F401 (the sweep's users)
from ..model.laws import LAW_PARAMETERS
from .arrays import array_names, array_spec
from .basin import run_basin_tile
from .curves_job import NOT_THE_KERNELS
from .job import Job
from .multistable import census_row
from .plan import Tile, chain_order, chain_parameters, first_column_parameters
from .separation import SEPARATION_ARRAYS, separation_row


def solver_options(job: Job):
    """The job's integrator options (``campar.model.compute.solver_options``)."""
    return compute.solver_options(job)


def cell_settings(job: Job) -> CellSettings:
    """The kernel's settings of every cell of the job, its outputs' bits included."""
    return compute.cell_settings(job, output_bits(job.outputs))


def run_tile(job: Job, tile: Tile) -> dict[str, np.ndarray]:
    """Compute every chain of a tile; arrays shaped (tile rows, ω points, …) in the job's
    ω order, whichever way the chains ran. A ``both`` job's tile is computed as its
    direction's one-direction job computes it (same starts, settings and outputs); a
    basin's tile by ``basin.run_basin_tile``; a curves job's tiles are not the kernel's
    (``curves_job.CurvesWork``)."""
    ensure_fresh_cache()
    if job.kind == "basin":
        return run_basin_tile(job, tile, array_names(job))
    if job.kind == "curves":
        raise ValueError(NOT_THE_KERNELS)
    if tile.direction is not None:
        job = job.one_direction(tile.direction)
    elif job.chains.direction == "both":
        raise ValueError(f"tile {tile.index} of a both-direction job names no direction")
    _, n_omega = job.shape
    names = array_names(job)
    result = {}
    for name in names:
        dtype, tail = array_spec(job, name)
        result[name] = np.zeros((tile.n_rows, n_omega, *tail), dtype)
    order = chain_order(job)
    for r, row in enumerate(range(tile.row_start, tile.row_stop)):
        par, out, law = run_row(job, row)
        extra = census_of(job, par, out.state, law)
        if job.wants("separation"):
            extra.update(separation_of(job, par, out, law, solver_options(job), cell_settings(job)))
        for name in names:
            result[name][r][order] = extra[name] if name in extra else getattr(out, name)
    return result


def run_row(job: Job, row: int, cells: int | None = None):
    """(parameters, outputs, law) of chain ``row`` of a one-direction map job, its cells in
    the order the chain runs: all of them, or its first ``cells`` (each cell depends on
    those before it alone, so a chain's first cells are the whole chain's bit for bit)."""
    par = chain_parameters(job, row)
    if cells is not None:
        par = {name: values[:cells] for name, values in par.items()}
    settings = cell_settings(job)
    out = allocate_outputs(len(par["omega"]), settings.output_bits, job.n_sections)
    law = job.law(row)
    compute.run_chain_over(par, law, chain_starts(job)[row], solver_options(job), settings, out)
    return par, out, law


def load_kernel(job: Job, share=None) -> None:
    """Bring the job's compiled kernel into this process (numba's on-disk cache, or a
    compile) and compute its chains' starts, as a first tile would: a runner calls it on
    a lane's thread while the store opens, so the first tile starts at full speed
    (benchmarks/RESULTS.md). A chain of no cells: nothing is computed.
    ``share``: as compile_kernel's."""
    if job.chains.direction == "both":
        job = job.one_direction(job.directions[0])
    compile_kernel(job, share)
    if job.kind != "basin":  # a basin's chains start from its grid of initial states
        chain_starts(job)


def compile_kernel(job: Job, share=None, trace: bool = False) -> None:
    """Load the job's compiled chain, or compile it: with an empty cache on two cores in a
    process that may fork, split with the ranks of this node that share the cache
    (``share``: this rank's index and their number, wire.cache_sharers), else here
    (campar.core.split_compile); with ``trace`` the orbit tracer too. A chain of no cells;
    at once if this process holds the chain already (a point called again and again)."""
    ensure_fresh_cache()
    if job.kind == "curves":
        raise ValueError(NOT_THE_KERNELS)
    if job.chains.direction == "both":
        job = job.one_direction(job.directions[0])
    # every row's law has one type: one kernel serves the job
    compute.compile_cells(job, job.law(), output_bits(job.outputs), job.n_sections, share, trace)


def census_of(job: Job, par: dict, state: np.ndarray, law) -> dict[str, np.ndarray]:
    """The ``attractors`` census arrays of a chain (``multistable.census_row``); {} if off."""
    if job.attractors is None:
        return {}
    return census_row(job, par, state, law)


def separation_of(job: Job, par: dict, out: CellOutputs, law, solver, settings) -> dict:
    """The ``separation`` arrays of a chain: its row's values in every cell (one chunk a
    tile, as every per-cell array)."""

    def allocate(n):
        return allocate_outputs(n, settings.output_bits, job.n_sections)

    values = separation_row(job, par, out, law, solver, settings, allocate)
    return {name: np.full(len(out.n), v) for name, v in zip(SEPARATION_ARRAYS, values, strict=True)}


# Seeds of ``chains.start: continue`` by job digest: every rank computes the same first
# column once (tens of milliseconds warm), so neither the runner nor the store knows of it.
_FIRST_COLUMN_STARTS: dict[str, np.ndarray] = {}


def chain_starts(job: Job) -> np.ndarray:
    """(rows, 2): the state (y, y') at θ = 0 from which each row's chain starts.

    rest: the job's initial state for every row. continue: the final state of the
    row's first cell computed by the chain along the second axis (from the job's
    initial state at its first value), or the initial state where that cell failed.
    Where the second axis is a law parameter (job.LAW_PARAMETERS), each row has a law of
    its own: that chain is a run of one-cell chains, each from the one before's final
    state (or the initial state after a failure).
    """
    n_rows, _ = job.shape
    x_init = np.array([job.initial.y, job.initial.v])
    if job.chains.start == "rest":
        return np.tile(x_init, (n_rows, 1))
    key = job.digest()
    if key not in _FIRST_COLUMN_STARTS:
        settings = cell_settings(job)._replace(output_bits=0)  # states only
        par = first_column_parameters(job)
        out = allocate_outputs(n_rows, 0, job.n_sections)
        if job.second in LAW_PARAMETERS:
            state = x_init
            for row in range(n_rows):
                cell = {name: values[row : row + 1] for name, values in par.items()}
                one = allocate_outputs(1, 0, job.n_sections)
                law = job.law(row)
                compute.run_chain_over(cell, law, state, solver_options(job), settings, one)
                out.state[row] = one.state[0]
                state = one.state[0] if np.all(np.isfinite(one.state[0])) else x_init
        else:
            compute.run_chain_over(par, job.law(), x_init, solver_options(job), settings, out)
        ok = np.all(np.isfinite(out.state), axis=1)[:, None]
        _FIRST_COLUMN_STARTS[key] = np.where(ok, out.state, x_init)
    return _FIRST_COLUMN_STARTS[key]


def warm_up() -> float:
    """Compile the kernel into numba's on-disk cache, as the first map or point of a fresh
    install would (one cell of the paper's set-up), and the orbit tracer a plotted point
    uses; returns the seconds it took. Every later process loads the cache instead
    (benchmarks/RESULTS.md)."""
    import time

    start = time.perf_counter()
    job = Job.from_dict(
        {
            "name": "warm_up",
            "sweep": {
                "omega": {"from": 3.0, "to": 3.0, "points": 1},
                "mu_cn": {"from": 0.8, "to": 0.8, "points": 1},
            },
        },
        source="warm-up",
    )
    compile_kernel(job, trace=True)
    run_tile(job, Tile(0, 0, 1))
    par = chain_parameters(job, 0)
    trace_orbit(
        par["omega"][0],
        par["zeta"][0],
        par["f0"][0],
        par["mu_kn"][0],
        par["mu_cn"][0],
        job.law(),
        np.zeros(N_STATE),
        solver_options(job),
        cell_settings(job),
        1,
        make_trace(16, 16, 2),
    )
    return time.perf_counter() - start
