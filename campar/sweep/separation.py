"""The separation speed of a map row: where, along the chain's path, the follower first
leaves the cam.

For the cam designer the question of a row is the highest speed up to which the follower
stays on the cam: the lowest ω at which a cell detaches (p > 0: ε crosses 0, the
duty cycle is positive). On the grid it lies between the row's lowest detaching cell
and the contact cell below it; ``separation_row`` locates it between them to
``OMEGA_TOL`` by bisection, each trial a cell of its own started, as the chain would
start it, from the final state of the cell the chain came from (ω decreasing: the
detaching side; ω increasing: the contact side), so the bisection follows the chain's
attractor. Below that speed the follower holds contact: the row's largest intrusion
(max ε) and contact force (max Pn) there, over the grid's cells and the bisection's
contact cells, are the loads the design must carry.

A row whose lowest cell already detaches, or none of whose cells does, has no
separation speed on its grid: NaN (and its largest intrusion and force over the
contact cells it has, NaN where none).
"""

import numpy as np

from ..core.codes import OK
from ..model.compute import run_chain_over
from .job import Job

OMEGA_TOL = 1e-6  # the bracket of the separation speed at the end of the bisection
SEPARATION_ARRAYS = ("separation_omega", "separation_eps_max", "separation_pn_max")


def separation_row(job: Job, par: dict, out, law, solver, settings, allocate) -> tuple:
    """(separation speed, largest intrusion, largest contact force below it) of one chain:
    ``par`` its per-cell parameters and ``out`` its outputs, both in chain order; ``law``,
    ``solver``, ``settings`` those it ran with; ``allocate(n)`` output buffers of n cells."""
    omega = par["omega"]
    ok = out.status == OK
    detached = ok & (out.p > 0)
    contact = ok & (out.p == 0)
    if not detached.any():
        return np.nan, *_loads(out, contact, ())
    hi = int(np.flatnonzero(detached)[np.argmin(omega[detached])])
    below = contact & (omega < omega[hi])
    if not below.any():
        return np.nan, np.nan, np.nan
    lo = int(np.flatnonzero(below)[np.argmax(omega[below])])
    down = job.chains.direction != "up"
    w_hi, w_lo = float(omega[hi]), float(omega[lo])
    state = out.state[hi if down else lo].copy()
    trials = []  # (eps_max, pn_max) of the bisection's contact cells
    while w_hi - w_lo > OMEGA_TOL:
        mid = 0.5 * (w_hi + w_lo)
        cell = {
            name: np.array([values[hi] if name != "omega" else mid]) for name, values in par.items()
        }
        one = allocate(1)
        run_chain_over(cell, law, state, solver, settings, one)
        if one.status[0] != OK:
            break  # the bracket so far: the chain cannot be followed further
        if one.p[0] > 0:
            w_hi = mid
            if down:
                state = one.state[0].copy()
        else:
            w_lo = mid
            trials.append((one.eps_max[0], one.pn_max[0]))
            if not down:
                state = one.state[0].copy()
    return 0.5 * (w_hi + w_lo), *_loads(out, contact & (omega <= w_lo), trials)


def _loads(out, cells: np.ndarray, trials) -> tuple[float, float]:
    """Largest intrusion and contact force over the chosen cells and the trial cells."""
    eps = [*out.eps_max[cells], *(e for e, _ in trials)]
    pn = [*out.pn_max[cells], *(f for _, f in trials)]
    return (float(np.nanmax(eps)) if eps else np.nan, float(np.nanmax(pn)) if pn else np.nan)
