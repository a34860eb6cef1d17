"""From a validated job to kernel calls: settings, output buffers, ``run_tile``.

``run_tile(job, tile)`` is the worker task of every runner (serial and MPI):
a plain function of plain data with no MPI and no files inside.
"""

import numpy as np

from ..core.integrator import DP54, RK4, SolverOptions
from ..core.jitcache import ensure_fresh_cache
from ..core.kernel import (
    CONVERGED,
    FIXED,
    OUT_LYAPUNOV,
    OUT_MULTIPLIERS,
    OUT_SECTIONS,
    OUT_STATS,
    CellOutputs,
    CellSettings,
    run_chain,
)
from ..core.model import N_STATE
from .arrays import array_names, array_spec
from .job import Job
from .plan import Tile, chain_parameters


def output_bits(job: Job) -> int:
    bits = 0
    if job.wants("dc") or job.wants("eps") or job.wants("pn"):
        bits |= OUT_STATS
    if job.wants("sections"):
        bits |= OUT_SECTIONS
    if job.wants("multipliers"):
        bits |= OUT_MULTIPLIERS
    if job.wants("lyapunov"):
        bits |= OUT_LYAPUNOV
    return bits


def solver_options(job: Job) -> SolverOptions:
    integ = job.integrator
    method = DP54 if integ.method == "dp54" else RK4
    return SolverOptions(method, integ.rtol, integ.atol, 0.0, 0.0, integ.event_tol, N_STATE)


def cell_settings(job: Job) -> CellSettings:
    tr = job.transient
    cl = job.classify
    return CellSettings(
        CONVERGED if tr.mode == "converged" else FIXED,
        tr.max_revolutions,
        cl.window_revolutions,
        cl.n_max,
        tr.conv_tol,
        tr.window_tol,
        cl.period_tol,
        tr.newton,
        tr.jump_residual,
        tr.jump_cap,
        tr.max_jumps,
        tr.jump_agree,
        cl.lyap_tol,
        job.integrator.max_steps,
        tr.extrapolate,
        job.integrator.rk4_steps,
        tr.chaos_after,
        tr.chaos_lyapunov,
        tr.quasiperiodic_after,
        output_bits(job),
    )


def allocate_outputs(n_cells: int, bits: int, n_sections: int) -> CellOutputs:
    """Kernel output buffers for n_cells; unrequested optional arrays have length 0."""

    def cells(wanted: bool) -> int:
        return n_cells if wanted else 0

    return CellOutputs(
        np.zeros(n_cells, np.int32),
        np.zeros(n_cells, np.int32),
        np.zeros(n_cells, np.int8),
        np.zeros(n_cells, np.int8),
        np.zeros(n_cells, np.int16),
        np.full(n_cells, np.nan),
        np.full(n_cells, np.nan),
        np.full(n_cells, np.nan),
        np.full(n_cells, np.nan),
        np.zeros((n_cells, N_STATE)),
        np.zeros(n_cells, np.int32),
        np.zeros(n_cells, np.int64),
        np.full(cells(bool(bits & OUT_LYAPUNOV)), np.nan),
        np.full((cells(bool(bits & OUT_MULTIPLIERS)), 2, 2), np.nan),
        np.full((cells(bool(bits & OUT_SECTIONS)), n_sections, 2), np.nan),
    )


def run_tile(job: Job, tile: Tile) -> dict[str, np.ndarray]:
    """Compute every chain of a tile; arrays shaped (tile rows, ω points, …)."""
    ensure_fresh_cache()
    _, n_omega = job.shape
    names = array_names(job)
    result = {}
    for name in names:
        dtype, tail = array_spec(job, name)
        result[name] = np.zeros((tile.n_rows, n_omega, *tail), dtype)
    solver = solver_options(job)
    settings = cell_settings(job)
    x_init = np.array([job.initial.y, job.initial.v])
    clamp = job.model.tensile == "clamp"
    for r, row in enumerate(range(tile.row_start, tile.row_stop)):
        par = chain_parameters(job, row)
        out = allocate_outputs(n_omega, settings.outputs, job.n_sections)
        run_chain(
            par["omega"], par["zeta"], par["f0"], par["mu_kn"], par["mu_cn"],
            clamp, x_init, solver, settings, out,
        )  # fmt: skip
        for name in names:
            result[name][r] = getattr(out, name)
    return result
