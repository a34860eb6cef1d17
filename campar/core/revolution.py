"""One cam revolution of the hybrid system, and the recorder that traces it.

``run_revolution`` is where the model meets the integrator: it steps across
the four cam phases (every step ends on a phase boundary, and on the joins of a
composite law's pieces), switches the contact mode at every event the integrator
locates, counts detachments and folds every step into the revolution's statistics.
"""

import math
from typing import NamedTuple

import numpy as np

from . import model
from .analysis import REV_DETACH, add_step_stats, reset_revolution_stats
from .cam import next_join
from .codes import EVENT_LOOP, OK, STEP_LIMIT
from .contact import impact_velocity, note_impact
from .deferred import clear_deferred, defer_step
from .extrema import step_extremes, step_models
from .integrator import SolverOptions, advance
from .jit import hot
from .model import (
    FREE,
    N_PHASES,
    N_STATE,
    N_STATE_VARIATIONAL,
    RISE,
    TWO_PI,
    cam,
    contact_force,
    contact_kinematics,
    contact_mode,
    gap,
    impact_mode,
    is_detachment,
    mode_after_event,
    released,
)
from .stages import CTRL_DENSE, dense_eval, prepare_dense

MAX_STUCK_EVENTS = 8  # zero-length events in a row before a cell is declared stuck

# What a revolution folds into its statistics row (run_revolution's ``stats``).
NO_STATS = 0  # detachments alone (a label's p)
DUTY_STATS = 1  # … the time separated and ε's interior minima (the grazing flag) too
ALL_STATS = 2  # every REV_* column: ε's extremes, Pn's largest value, the touch


class Trace(NamedTuple):
    """Recorder of an orbit for figures; length-0 arrays record nothing.

    samples rows: t, y, y', yc, ε, Pn (the law's force, clamp applied), contact
    mode; events rows: t, y, y', code = 2·(mode before) + (event index).
    """

    samples: np.ndarray  # (N, 7)
    events: np.ndarray  # (M, 4)
    count: np.ndarray  # int64 [samples written, events written]
    t0: np.ndarray  # [time at θ = 0 of the current revolution]
    prev: np.ndarray  # (2,) state at the start of the current step
    per_step: int  # dense samples per step (≥ 1: the step end itself)


def make_trace(n_samples, n_events, per_step) -> Trace:
    return Trace(
        np.zeros((n_samples, 7)),
        np.zeros((n_events, 4)),
        np.zeros(2, dtype=np.int64),
        np.zeros(1),
        np.zeros(2),
        per_step,
    )


@hot
def record_sample(rec, t, y0, y1, p, mode):
    i = rec.count[0]
    if i >= rec.samples.shape[0]:
        return
    yc, dyc, _ = cam(p.omega * t, mode[0], p.cam)
    eps = yc - y0
    row = rec.samples[i]
    row[0] = rec.t0[0] + t
    row[1] = y0
    row[2] = y1
    row[3] = yc
    row[4] = eps
    row[5] = contact_force(eps, p.vcam * dyc - y1, p)
    row[6] = mode[1]
    rec.count[0] = i + 1


@hot
def record_step(rec, method, w, t_prev, t, x, p, mode):
    """Dense samples inside the step just taken, then its end point."""
    h = t - t_prev
    if rec.per_step > 1:
        prepare_dense(model.rhs, method, t_prev, rec.prev, h, p, mode, w)
    for j in range(1, rec.per_step):
        theta = j / rec.per_step
        dense_eval(method, w, rec.prev, x, h, theta, N_STATE, w.y_stage)
        record_sample(rec, t_prev + theta * h, w.y_stage[0], w.y_stage[1], p, mode)
    record_sample(rec, t, x[0], x[1], p, mode)


@hot
def record_event(rec, t, x, contact, which):
    i = rec.count[1]
    if i >= rec.events.shape[0]:
        return
    rec.events[i, 0] = rec.t0[0] + t
    rec.events[i, 1] = x[0]
    rec.events[i, 2] = x[1]
    rec.events[i, 3] = 2 * contact + which
    rec.count[1] = i + 1


@hot
def run_revolution(x, f, p, opt, w, mode, row, stats, step_limit, rec):
    """Integrate one cam revolution from θ = 0 to 2π, in place on x.

    Steps end on every cam phase boundary, every join of a composite cam law's pieces
    (cam.next_join) and every contact event; with the
    variational part, Φ starts at I, so x[2:6] ends as the Jacobian of the
    one-revolution map. Fills the revolution's statistics in ``row``, those ``stats``
    names (NO_STATS, DUTY_STATS, ALL_STATS); a row wider than
    N_REV_STATS (the chain's) keeps the steps whose extrema need the dense output for
    deferred.refine_window instead of refining them. Fails with STEP_LIMIT once the
    workspace has counted more than step_limit steps.
    Records the orbit into ``rec`` unless it is None: numba then prunes every
    recording branch before typing, so a map's kernel never compiles the recorder.
    """
    if x.shape[0] == N_STATE_VARIATIONAL:
        x[2] = 1.0
        x[3] = 0.0
        x[4] = 0.0
        x[5] = 1.0
    reset_revolution_stats(row)
    clear_deferred(row)
    mode[0] = RISE
    eps, deps = gap(0.0, x, p, mode[0])  # not RISE: numba would compile a variant for the literal
    mode[1] = contact_mode(eps, deps, p)
    t = 0.0
    k0 = (0.0, 0.0, 0.0, 0.0, 0.0)  # model.contact_kinematics at t in this mode (when fresh)
    if rec is not None:
        record_sample(rec, t, x[0], x[1], p, mode)
    for phase in range(N_PHASES):
        mode[0] = phase
        phase_end = p.cam.bounds[phase + 1] / p.omega
        model.rhs(t, x, p, mode, f)
        w.counts[2] += 1
        stuck = 0
        fresh = False  # k0 holds the kinematics at t in this mode
        while t < phase_end:
            if w.counts[0] + w.counts[1] > step_limit:
                return STEP_LIMIT
            t_end = min(phase_end, next_join(p.cam, phase, t, p.omega))
            t_prev = t
            contact = mode[1]
            if stats != NO_STATS and not fresh:
                k0 = contact_kinematics(t, x, f, p, mode)
            if rec is not None:
                rec.prev[0] = x[0]
                rec.prev[1] = x[1]
            status, t, which = advance(
                model.rhs, model.events, model.event_curvature, t, t_end, x, f, p, mode, opt, w
            )
            if status != OK:
                return status
            if t > t_prev:
                stuck = 0
                if rec is not None:
                    record_step(rec, opt.method, w, t_prev, t, x, p, mode)
                if stats != NO_STATS:
                    k1 = contact_kinematics(t, x, f, p, mode)
                    h = t - t_prev
                    free = released(contact, p)
                    extremes = stats == ALL_STATS
                    dense, pn_hi = step_models(h, mode, k0, k1, extremes)
                    if not dense:
                        add_step_stats(row, h, free, k0[0], k1[0], math.nan, math.nan, pn_hi)
                    else:
                        # the event search may have prepared the dense output already,
                        # from the integrator's own step size: keep its coefficients
                        prepared = w.ctrl[CTRL_DENSE] == 1.0
                        stages = w.F if prepared else w.K
                        impact = impact_velocity(p.contact)
                        if defer_step(
                            row,
                            w.y_old,
                            w.y_new,
                            stages,
                            prepared,
                            t_prev,
                            h,
                            mode,
                            free,
                            impact,
                            k0,
                            k1,
                        ):
                            pn_hi = max(k0[3], k1[3])
                            dip = math.nan
                            peak = math.nan
                        else:
                            dip, peak, pn_hi = step_extremes(
                                model.rhs, opt.method, w, t_prev, h, p, mode, k0, k1, extremes
                            )
                        add_step_stats(row, h, free, k0[0], k1[0], dip, peak, pn_hi)
                    k0 = k1
                    fresh = True
            elif which >= 0:
                stuck += 1
                if stuck > MAX_STUCK_EVENTS:
                    return EVENT_LOOP
            if which >= 0:
                if is_detachment(contact, which):
                    row[REV_DETACH] += 1.0
                if rec is not None:
                    record_event(rec, t, x, contact, which)
                if contact == FREE:
                    _, deps = gap(t, x, p, mode[0])
                    note_impact(p.contact, deps)
                    mode[1] = impact_mode(deps, p)
                else:
                    mode[1] = mode_after_event(contact, which)
                model.rhs(t, x, p, mode, f)
                w.counts[2] += 1
                fresh = False
    if rec is not None:
        rec.t0[0] += t
    return OK


@hot
def scale_solver_options(base, omega, rk4_steps):
    """The job's integrator options for a cell of cam speed ω: RK4's step (rk4_steps
    a revolution), the step floor and the event tolerance scale with the period 2π/ω."""
    period = TWO_PI / omega
    return SolverOptions(
        method=base.method,
        rtol=base.rtol,
        atol=base.atol,
        h_fixed=period / rk4_steps,
        h_min=1e-12 * max(1.0, period),
        event_tol=base.event_tol * max(1.0, period),
        n_err=N_STATE,
    )
