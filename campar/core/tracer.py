"""One orbit traced revolution by revolution into a recorder: the figures of a steady
orbit (``campar point --plot``, the paper's figures) and the integrator's checks against
SciPy. Like the chain (campar.core.kernel), the tracer calls the revolution through its
address (campar.core.revolution_call): the revolution with a recorder is a variant of
its own, which a forked helper compiles while this process compiles the tracer
(campar.core.split_compile)."""

import numpy as np
from numba import njit, typeof, types

from . import model
from .analysis import N_REV_STATS
from .codes import OK
from .integrator import CTRL_H, initial_step, make_work
from .model import (
    MAX_EVENTS,
    N_STATE,
    PAPER_LAW,
    RISE,
    contact_mode,
    gap,
    kernel_law,
    make_params,
    start_chain,
)
from .revolution import NO_STATS, make_trace, scale_solver_options
from .revolution_call import call_revolution, revolution_link

LINK = types.Array(types.int64, 1, "C")  # revolution_link's [address, fingerprint]


def trace_orbit(omega, zeta, f0, mu_kn, mu_cn, law, x0, solver, cs, revolutions, rec):
    """Integrate ``revolutions`` revolutions from x0 (at θ = 0), recording into rec
    (``law`` as run_chain's).

    Returns (status, final y, final y'). For figures of a steady orbit: start
    from a cell's final state and trace its period.
    """
    args = trace_arguments(omega, zeta, f0, mu_kn, mu_cn, law, x0, solver, cs, revolutions, rec)
    start_chain(args[5])
    return trace_compiled(*args, tracer_link(solver, cs, rec, args[5]))


def trace_arguments(omega, zeta, f0, mu_kn, mu_cn, law, x0, solver, cs, revolutions, rec):
    """trace_compiled's arguments but its last, the revolution's link (tracer_link):
    trace_orbit's, then the buffers."""
    buffers = (
        make_work(N_STATE, MAX_EVENTS, 0.0),
        np.zeros(N_STATE),
        np.zeros(2, dtype=np.int64),
        np.zeros(N_REV_STATS),
    )
    parameters = (float(omega), float(zeta), float(f0), float(mu_kn), float(mu_cn))
    return (
        *parameters,
        kernel_law(law),
        np.array(x0, dtype=np.float64),
        solver,
        cs,
        np.int64(revolutions),
        rec,
        *buffers,
    )


def tracer_link(solver, cs, rec, law=PAPER_LAW) -> np.ndarray:
    """The link to the revolution that records into a recorder of rec's type."""
    return revolution_link(solver, cs, make_work(N_STATE, MAX_EVENTS, 0.0), typeof(rec), law)


def compile_tracer(law, solver, cs) -> None:
    """Compile (or load) the orbit tracer, then link the revolution with a recorder it
    calls: in this order a cold tracer compiles while a forked helper compiles that
    revolution (campar.core.split_compile)."""
    rec = make_trace(0, 0, 1)
    args = trace_arguments(1.0, 0.2, 0.5, 0.8, 0.8, law, np.zeros(N_STATE), solver, cs, 1, rec)
    trace_compiled.compile((*(typeof(a) for a in args), LINK))
    tracer_link(solver, cs, rec, law)


@njit(cache=True, _nrt=False)
def trace_compiled(
    omega, zeta, f0, mu_kn, mu_cn, law, x, solver, cs, revolutions, rec, w, f, mode, row, link
):
    """trace_orbit's compiled body: integrates in place on x with the buffers w, f, mode, row;
    ``link``: revolution_link's for a recorder of rec's type."""
    p = make_params(omega, zeta, f0, mu_kn, mu_cn, law)
    opt = scale_solver_options(solver, omega, cs.rk4_steps)
    mode[0] = RISE
    eps, deps = gap(0.0, x, p, mode[0])  # not RISE: numba would compile a variant for the literal
    mode[1] = contact_mode(eps, deps, p)
    model.rhs(0.0, x, p, mode, f)
    w.ctrl[CTRL_H] = initial_step(model.rhs, 0.0, x, f, p, mode, solver.rtol, solver.atol, 2, 0.1)
    for _ in range(revolutions):
        status = call_revolution(link, x, f, p, opt, w, mode, row, NO_STATS, cs.max_steps, rec)
        if status != OK:
            return status, x[0], x[1]
    return OK, x[0], x[1]
