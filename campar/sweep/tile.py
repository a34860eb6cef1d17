"""From a validated job to kernel calls: settings, output buffers, ``run_tile``.

``run_tile(job, tile)`` is the worker task of every runner (serial and MPI):
a plain function of plain data with no MPI and no files inside. Where each
chain starts (``chain_starts``) depends on the job alone, so the numbers do not
depend on the number of ranks or on interruptions.
"""

import numpy as np

from ..core import split_compile
from ..core.integrator import DOP853, DP54, RK4, SolverOptions, method_tag
from ..core.jit import collector_paused
from ..core.jitcache import ensure_fresh_cache, located_cache_dir  # noqa: F401 (runner's)
from ..core.kernel import (
    CONVERGED,
    FIXED,
    OUT_LYAPUNOV,
    OUT_MULTIPLIERS,
    OUT_SECTIONS,
    OUT_STATS,
    CellOutputs,
    CellSettings,
    chain_loaded,
    chain_signature,
    compile_chain,
    run_chain,
)
from ..core.model import N_STATE
from ..core.revolution import make_trace
from ..core.tracer import compile_tracer, trace_orbit
from .arrays import array_names, array_spec
from .curves_job import NOT_THE_KERNELS
from .job import Job
from .laws import LAW_PARAMETERS
from .plan import Tile, chain_order, chain_parameters, first_column_parameters


def output_bits(job: Job) -> int:
    bits = 0
    if any(job.wants(name) for name in ("dc", "eps", "pn", "separation")):
        bits |= OUT_STATS
    if job.wants("sections"):
        bits |= OUT_SECTIONS
    if job.wants("multipliers"):
        bits |= OUT_MULTIPLIERS
    if job.wants("lyapunov"):
        bits |= OUT_LYAPUNOV
    return bits


METHODS = {"dp54": DP54, "dop853": DOP853, "rk4": RK4}  # the job's integrator.method


def solver_options(job: Job) -> SolverOptions:
    """The job's integrator options; the kernel scales h_fixed, h_min and event_tol
    to each cell's period (core.revolution.scale_solver_options)."""
    integ = job.integrator
    return SolverOptions(
        method=method_tag(METHODS[integ.method]),
        rtol=integ.rtol,
        atol=integ.atol,
        h_fixed=0.0,
        h_min=0.0,
        event_tol=integ.event_tol,
        n_err=N_STATE,
    )


def cell_settings(job: Job) -> CellSettings:
    """The kernel's settings for every cell of the job (field names as the job's, see
    CellSettings)."""
    tr = job.transient
    cl = job.classify
    integ = job.integrator
    return CellSettings(
        transient=CONVERGED if tr.mode == "converged" else FIXED,
        max_revolutions=tr.max_revolutions,
        window_revolutions=cl.window_revolutions,
        n_max=cl.n_max,
        conv_tol=tr.conv_tol,
        window_tol=tr.window_tol,
        period_tol=cl.period_tol,
        newton=tr.newton,
        jump_residual=tr.jump_residual,
        jump_cap=tr.jump_cap,
        max_jumps=tr.max_jumps,
        jump_agree=tr.jump_agree,
        lyap_tol=cl.lyap_tol,
        max_steps=integ.max_steps,
        extrapolate=tr.extrapolate,
        rk4_steps=integ.rk4_steps,
        chaos_after=tr.chaos_after,
        chaos_lyapunov=tr.chaos_lyapunov,
        quasiperiodic_after=tr.quasiperiodic_after,
        output_bits=output_bits(job),
    )


def allocate_outputs(n_cells: int, bits: int, n_sections: int) -> CellOutputs:
    """Kernel output buffers for n_cells; unrequested optional arrays have length 0."""

    def cells(wanted: bool) -> int:
        return n_cells if wanted else 0

    return CellOutputs(
        n=np.zeros(n_cells, np.int32),
        p=np.zeros(n_cells, np.int32),
        kind=np.zeros(n_cells, np.int8),
        status=np.zeros(n_cells, np.int8),
        flags=np.zeros(n_cells, np.int16),
        dc=np.full(n_cells, np.nan),
        eps_min=np.full(n_cells, np.nan),
        eps_max=np.full(n_cells, np.nan),
        pn_max=np.full(n_cells, np.nan),
        state=np.zeros((n_cells, N_STATE)),
        revolutions=np.zeros(n_cells, np.int32),
        steps=np.zeros(n_cells, np.int64),
        lyapunov=np.full(cells(bool(bits & OUT_LYAPUNOV)), np.nan),
        multipliers=np.full((cells(bool(bits & OUT_MULTIPLIERS)), 2, 2), np.nan),
        sections=np.full((cells(bool(bits & OUT_SECTIONS)), n_sections, 2), np.nan),
    )


def run_tile(job: Job, tile: Tile) -> dict[str, np.ndarray]:
    """Compute every chain of a tile; arrays shaped (tile rows, ω points, …) in the job's
    ω order, whichever way the chains ran. A ``both`` job's tile is computed as its
    direction's one-direction job computes it (same starts, settings and outputs); a
    basin's tile by ``basin.run_basin_tile``; a curves job's tiles are not the kernel's
    (``curves_job.CurvesWork``)."""
    ensure_fresh_cache()
    if job.kind == "basin":
        from .basin import run_basin_tile  # it builds on this module's settings and buffers

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
    solver = solver_options(job)
    settings = cell_settings(job)
    starts = chain_starts(job)
    order = chain_order(job)
    for r, row in enumerate(range(tile.row_start, tile.row_stop)):
        par = chain_parameters(job, row)
        out = allocate_outputs(n_omega, settings.output_bits, job.n_sections)
        run_chain(
            par["omega"],
            par["zeta"],
            par["f0"],
            par["mu_kn"],
            par["mu_cn"],
            job.law(row),
            starts[row],
            solver,
            settings,
            out,
        )
        extra = census_of(job, par, out.state, job.law(row))
        if job.wants("separation"):
            extra.update(separation_of(job, par, out, job.law(row), solver, settings))
        for name in names:
            result[name][r][order] = extra[name] if name in extra else getattr(out, name)
    return result


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
    solver = solver_options(job)
    law = job.law()  # every row's law has one type: one kernel serves the job
    if chain_loaded(solver, law):
        return
    settings = cell_settings(job)
    out = allocate_outputs(0, settings.output_bits, job.n_sections)
    x_init = np.array([job.initial.y, job.initial.v])
    with collector_paused():
        helper = split_compile.start_helper(solver, settings, trace, law)
        signature = chain_signature(law, x_init, solver, settings, out)
        split_compile.share_with_ranks(share, solver, settings, signature, law)
        compile_chain(signature, solver, settings, law)
        if trace:
            compile_tracer(law, solver, settings)
        split_compile.reap(helper)


def census_of(job: Job, par: dict, state: np.ndarray, law) -> dict[str, np.ndarray]:
    """The ``attractors`` census arrays of a chain (``multistable.census_row``); {} if off."""
    if job.attractors is None:
        return {}
    from .multistable import census_row  # it builds on this module's settings and buffers

    return census_row(job, par, state, law)


def separation_of(job: Job, par: dict, out: CellOutputs, law, solver, settings) -> dict:
    """The ``separation`` arrays of a chain: its row's values in every cell (one chunk a
    tile, as every per-cell array)."""
    from .separation import SEPARATION_ARRAYS, separation_row

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
                run_chain(
                    cell["omega"],
                    cell["zeta"],
                    cell["f0"],
                    cell["mu_kn"],
                    cell["mu_cn"],
                    job.law(row),
                    state,
                    solver_options(job),
                    settings,
                    one,
                )
                out.state[row] = one.state[0]
                state = one.state[0] if np.all(np.isfinite(one.state[0])) else x_init
        else:
            run_chain(
                par["omega"],
                par["zeta"],
                par["f0"],
                par["mu_kn"],
                par["mu_cn"],
                job.law(),
                x_init,
                solver_options(job),
                settings,
                out,
            )
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
