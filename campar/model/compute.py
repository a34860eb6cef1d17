"""From a model to kernel calls: the solver's options, the cell settings, output buffers,
and ``run_cells``, a chain of cells computed from a Model.

The settings functions take anything with a model's sections (``integrator``,
``transient``, ``classify``): a Model, or a sweep's Job, whose sections are the same
classes, so a map's tile and a single cell hand the kernel the same values.
"""

import threading
from statistics import NormalDist

import numpy as np

from ..core import split_compile
from ..core.integrator import SolverOptions
from ..core.jit import collector_paused
from ..core.jitcache import ensure_fresh_cache
from ..core.kernel import (
    CONVERGED,
    FIXED,
    OUT_EXTREMA,
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
from ..core.stages import DOP853, DP54, RK4, method_tag
from ..core.tracer import compile_tracer
from .laws import kernel_law
from .model import Model

METHODS = {"dp54": DP54, "dop853": DOP853, "rk4": RK4}  # integrator.method
# One compile at a time in a process: threads (a web server's) that ask for the same
# kernel wait for it rather than compiling it twice.
_COMPILING = threading.Lock()


def output_bits(outputs) -> int:
    """The kernel's OUT_* bits of the outputs named (a job's ``outputs`` names)."""
    bits = 0
    if any(name in outputs for name in ("dc", "eps", "pn", "separation")):
        bits |= OUT_STATS
    if any(name in outputs for name in ("eps", "pn", "separation")):
        bits |= OUT_EXTREMA
    if "sections" in outputs:
        bits |= OUT_SECTIONS
    if "multipliers" in outputs:
        bits |= OUT_MULTIPLIERS
    if "lyapunov" in outputs:
        bits |= OUT_LYAPUNOV
    return bits


def solver_options(spec) -> SolverOptions:
    """The integrator options of ``spec`` (a Model or a Job); the kernel scales h_fixed,
    h_min and event_tol to each cell's period (core.revolution.scale_solver_options)."""
    integ = spec.integrator
    return SolverOptions(
        method=method_tag(METHODS[integ.method]),
        rtol=integ.rtol,
        atol=integ.atol,
        h_fixed=0.0,
        h_min=0.0,
        event_tol=integ.event_tol,
        n_err=N_STATE,
    )


def cell_settings(spec, bits: int) -> CellSettings:
    """The kernel's settings of every cell of ``spec`` (a Model or a Job; field names as
    the sections', see CellSettings), computing the outputs of ``bits``."""
    tr = spec.transient
    cl = spec.classify
    integ = spec.integrator
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
        chaos_z=NormalDist().inv_cdf(tr.chaos_confidence),
        chaos_clear=tr.chaos_clear,
        chaos_sight=tr.chaos_sight,
        quasiperiodic_after=tr.quasiperiodic_after,
        output_bits=bits,
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


def model_law(model: Model):
    """The kernel's Law (campar.core.model.Law) of a model's laws and options."""
    return kernel_law(model.model)


def compile_cells(spec, law, bits: int, n_sections: int, share=None, trace: bool = False) -> None:
    """Load the compiled chain of ``spec`` (a Model or a Job) and ``law``, or compile it:
    with an empty cache on two cores in a process that may fork, split with the ranks of
    this node that share the cache (``share``: this rank's index and their number), else
    here (campar.core.split_compile); with ``trace`` the orbit tracer too. At once if this
    process holds the chain already (a point called again and again)."""
    ensure_fresh_cache()
    solver = solver_options(spec)
    if chain_loaded(solver, law):
        return
    with _COMPILING:
        if not chain_loaded(solver, law):
            _compile(spec, law, bits, n_sections, solver, share, trace)


def _compile(spec, law, bits, n_sections, solver, share, trace) -> None:
    settings = cell_settings(spec, bits)
    out = allocate_outputs(0, settings.output_bits, n_sections)
    x_init = np.array([spec.initial.y, spec.initial.v])
    with collector_paused():
        helper = split_compile.start_helper(solver, settings, trace, law)
        signature = chain_signature(law, x_init, solver, settings, out)
        split_compile.share_with_ranks(share, solver, settings, signature, law)
        compile_chain(signature, solver, settings, law)
        if trace:
            compile_tracer(law, solver, settings)
        split_compile.reap(helper)


CHAIN_PARAMETERS = ("omega", "zeta", "f0", "mu_kn", "mu_cn")  # run_chain's order


def run_chain_over(par: dict, law, x_init, solver, settings, out: CellOutputs) -> None:
    """The kernel's run_chain over the cells whose parameters ``par`` holds by name
    (CHAIN_PARAMETERS, arrays of one length); ``out`` is filled in place. The on-disk cache
    is checked first: a replay (``campar point --from``) may be the process's first use of
    the kernel, and numba would load an entry compiled from other sources of the core."""
    ensure_fresh_cache()
    run_chain(*(par[name] for name in CHAIN_PARAMETERS), law, x_init, solver, settings, out)


def run_cells(
    model: Model, omega=None, start=None, outputs=(), law=None, compile=True, **columns
) -> CellOutputs:
    """One continuation chain of the kernel from a Model: a cell at each ω of ``omega``
    (default the model's ω: one cell), in the order given, each warm-started from the
    one before, the first from ``start`` (default the model's ``initial``). ``columns``:
    other parameters that vary along the chain (arrays as long as ``omega``); ``law``:
    the kernel's Law (default the model's). The outputs named (a job's ``outputs``
    names) are computed beside the label, state and counts. ``compile``: load or compile
    the kernel first (``compile_cells``: on two cores when the cache is empty); else
    numba compiles it on the first call, on this thread."""
    unknown = set(columns) - {"f0", "mu_kn", "mu_cn", "zeta"}
    if unknown:
        raise TypeError(f"run_cells: no parameter column {', '.join(sorted(unknown))}")
    omega = np.atleast_1d(np.asarray(model.omega if omega is None else omega, float))
    values = {
        name: np.asarray(columns[name], float)
        if name in columns
        else np.full(omega.shape, getattr(model, name))
        for name in ("f0", "mu_kn", "mu_cn", "zeta")
    }
    law = model_law(model) if law is None else law
    bits = output_bits(outputs)
    if compile:
        compile_cells(model, law, bits, model.n_sections)
    x0 = np.array(model.start if start is None else start, dtype=float)
    settings = cell_settings(model, bits)
    out = allocate_outputs(len(omega), bits, model.n_sections)
    run_chain_over({"omega": omega, **values}, law, x0, solver_options(model), settings, out)
    return out
