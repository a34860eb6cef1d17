"""The n-revolution section map Pⁿ of the stroboscopic section θ = 0, with its exact Jacobian.

A periodic orbit of period n is a fixed point of Pⁿ; continuation (campar.continuation)
solves for it by Newton's method with the Jacobian DPⁿ = J_n ⋯ J_1, the product of the
one-revolution Jacobians the variational equations give (model.rhs with a 6-state; the
field is continuous across every switching surface, so no saltation matrix enters). One
call of ``shoot_compiled`` integrates n revolutions from one state and returns the image,
DPⁿ and the contact pattern of those revolutions (detachments, the signed extremum of ε
nearest 0 where grazing happens, the ε and Pn extremes and the time separated).

Like the chain (campar.core.kernel), the entry calls the revolution through its address
(campar.core.revolution_call): it is the chain's own compiled revolution, so a process
that has the map kernel compiles only this small driver.
"""

import math

import numpy as np
from numba import njit, typeof, types

from . import model
from .analysis import (
    N_REV_STATS,
    REV_DETACH,
    REV_EPS_MAX,
    REV_EPS_MIN,
    REV_PN_MAX,
    REV_T_FREE,
    REV_TOUCH,
)
from .codes import NONFINITE, OK
from .entry_steps import forget
from .integrator import SolverOptions, initial_step, make_work, restart_control
from .jitcache import ensure_fresh_cache
from .model import (
    MAX_EVENTS,
    N_STATE_VARIATIONAL,
    RISE,
    contact_mode,
    gap,
    kernel_law,
    make_params,
    start_chain,
)
from .revolution import ALL_STATS, scale_solver_options
from .revolution_call import call_revolution, revolution_link

LINK = types.Array(types.int64, 1, "C")  # revolution_link's [address, fingerprint]

# Columns of a shot's result vector.
SHOT_Y = 0  # y at θ = 0 after n revolutions
SHOT_V = 1  # y' …
SHOT_DETACH = 2  # detachments in the n revolutions
SHOT_TOUCH = 3  # ε at the interior extremum of ε nearest 0, signed (analysis.REV_TOUCH)
SHOT_EPS_MIN = 4
SHOT_EPS_MAX = 5
SHOT_PN_MAX = 6
SHOT_T_FREE = 7  # time separated (model.released) in the n revolutions
SHOT_STEPS = 8  # accepted steps
N_SHOT = 9


class Shooter:
    """Pⁿ(x; parameters) and DPⁿ for one force law and one set of solver options.

    ``law``: the job's model.Law (or LAW_* bits: the paper's laws, ``model.kernel_law``);
    ``solver``: integrator.SolverOptions (the kernel scales its
    step floor and event tolerance to each ω); ``cs``: kernel.CellSettings (its
    ``rk4_steps`` and ``max_steps``, the step budget of one revolution). Buffers are
    allocated once; a Shooter is not thread-safe.
    """

    def __init__(self, law, solver, cs):
        self.law = kernel_law(law)
        self.solver = solver
        self.rk4_steps = np.int64(cs.rk4_steps)
        self.max_steps = np.int64(cs.max_steps)
        self.work = make_work(N_STATE_VARIATIONAL, MAX_EVENTS, 0.0)
        self.link = revolution_link(solver, cs, self.work, law=self.law)
        self.x = np.zeros(N_STATE_VARIATIONAL)
        self.x2 = np.zeros(2)
        self.f = np.zeros(N_STATE_VARIATIONAL)
        self.mode = np.zeros(2, dtype=np.int64)
        self.row = np.zeros(N_REV_STATS)
        self.shots = 0  # calls, for the benchmarks

    def __call__(self, par, x0, n: int, jacobian: bool = True):
        """Integrate n revolutions from x0 = (y, y') at θ = 0 with parameters
        ``par`` = (ω, ζ, f0, μkn, μcn).

        Returns (status, result, M, points): result (N_SHOT,) by the SHOT_* columns; M
        (2, 2) is DPⁿ at x0 (NaN without ``jacobian``); points (n, 2) the states at θ = 0
        after 1, …, n revolutions; status a codes.Status value (OK = 0).
        """
        result = np.full(N_SHOT, np.nan)
        jac = np.full(4, np.nan)
        points = np.full((n, 2), np.nan)
        x = self.x if jacobian else self.x2
        x[0] = x0[0]
        x[1] = x0[1]
        start_chain(self.law)  # every shot from the same memory of impacts
        status = shoot_compiled(
            np.asarray(par, dtype=np.float64),
            self.law,
            np.int64(n),
            self.solver,
            self.rk4_steps,
            self.max_steps,
            self.link,
            x,
            self.f,
            self.work,
            self.mode,
            self.row,
            result,
            jac,
            points,
        )
        self.shots += 1
        return int(status), result, jac.reshape(2, 2), points


def compile_shooter(law, solver, cs) -> None:
    """Compile (or load) the shooting entry for these options, and link its revolution,
    once the on-disk cache is checked against the core's sources (jitcache)."""
    ensure_fresh_cache()
    shooter = Shooter(law, solver, cs)
    args = (
        np.zeros(5),
        shooter.law,
        np.int64(1),
        solver,
        shooter.rk4_steps,
        shooter.max_steps,
        shooter.link,
        shooter.x,
        shooter.f,
        shooter.work,
        shooter.mode,
        shooter.row,
        np.zeros(N_SHOT),
        np.zeros(4),
        np.zeros((1, 2)),
    )
    shoot_compiled.compile(tuple(typeof(a) for a in args))


@njit(cache=True, _nrt=False)
def shoot_compiled(
    par, law, n, solver, rk4_steps, max_steps, link, x, f, w, mode, row, result, jac, points
):
    """Shooter.__call__'s compiled body: integrates in place on x (2 or 6 components; with
    6 the variational part gives DPⁿ into jac, row-major); the state after revolution k
    into points[k − 1] while there are rows."""
    omega = par[0]
    p = make_params(omega, par[1], par[2], par[3], par[4], law)
    # every component error-controlled, Φ too: in a long free flight (y, y') alone allow
    # steps that lose Φ's accuracy (tests/test_kernel.py, the free-flight multipliers)
    scaled = scale_solver_options(solver, omega, rk4_steps)
    opt = SolverOptions(
        scaled.method,
        scaled.rtol,
        scaled.atol,
        scaled.h_fixed,
        scaled.h_min,
        scaled.event_tol,
        x.shape[0],
    )
    mode[0] = RISE
    eps, deps = gap(0.0, x, p, mode[0])  # not RISE: numba would compile a variant for the literal
    mode[1] = contact_mode(eps, deps, p)
    model.rhs(0.0, x, p, mode, f)
    # a shot is a function of (x, parameters, n) alone: no step size, error history or
    # remembered entry step of an earlier shot (difference quotients of Pⁿ stay smooth)
    restart_control(
        w, initial_step(model.rhs, 0.0, x, f, p, mode, solver.rtol, solver.atol, 2, 0.1)
    )
    forget(w.h_memory)
    variational = x.shape[0] == N_STATE_VARIATIONAL
    m0, m1, m2, m3 = 1.0, 0.0, 0.0, 1.0
    detach = 0.0
    touch = math.inf
    eps_min = math.inf
    eps_max = -math.inf
    pn_max = 0.0
    t_free = 0.0
    steps0 = w.counts[0]
    for k in range(n):
        limit = w.counts[0] + w.counts[1] + max_steps
        status = call_revolution(link, x, f, p, opt, w, mode, row, ALL_STATS, limit, None)
        if status != OK:
            return status
        if not (math.isfinite(x[0]) and math.isfinite(x[1])):
            return NONFINITE
        if k < points.shape[0]:
            points[k, 0] = x[0]
            points[k, 1] = x[1]
        if variational:  # M ← J M, J = Φ of this revolution
            a0 = x[2] * m0 + x[3] * m2
            a1 = x[2] * m1 + x[3] * m3
            a2 = x[4] * m0 + x[5] * m2
            a3 = x[4] * m1 + x[5] * m3
            m0, m1, m2, m3 = a0, a1, a2, a3
        detach += row[REV_DETACH]
        if abs(row[REV_TOUCH]) < abs(touch):
            touch = row[REV_TOUCH]
        eps_min = min(eps_min, row[REV_EPS_MIN])
        eps_max = max(eps_max, row[REV_EPS_MAX])
        pn_max = max(pn_max, row[REV_PN_MAX])
        t_free += row[REV_T_FREE]
    result[SHOT_Y] = x[0]
    result[SHOT_V] = x[1]
    result[SHOT_DETACH] = detach
    result[SHOT_TOUCH] = touch
    result[SHOT_EPS_MIN] = eps_min
    result[SHOT_EPS_MAX] = eps_max
    result[SHOT_PN_MAX] = pn_max
    result[SHOT_T_FREE] = t_free
    result[SHOT_STEPS] = w.counts[0] - steps0
    if variational:
        jac[0] = m0
        jac[1] = m1
        jac[2] = m2
        jac[3] = m3
    return OK
