"""The follower in free flight: its closed form, and the integrator stepped to the event.

y'' + 2ζ y' + y = −f0 has a closed-form solution; tests of the impact event step
``campar.core.integrator.advance`` through a flight and compare where it stops with the
closed form's first crossing of the cam.
"""

import math

import numpy as np

from campar.core import model
from campar.core.codes import OK
from campar.core.integrator import advance, make_work
from support.jit import cached_njit


def damped_flight(y0, t0, zeta, f0):
    """y(t) of y'' + 2ζ y' + y = −f0 from the state y0 = (y, y') at t0, in closed form."""
    wd = math.sqrt(1.0 - zeta * zeta)
    a = y0[0] + f0
    b = (y0[1] + zeta * a) / wd

    def y(t):
        s = t - t0
        return -f0 + math.exp(-zeta * s) * (a * math.cos(wd * s) + b * math.sin(wd * s))

    return y


@cached_njit
def free_step(t, t_end, y, p, mode, opt, w):
    f = np.zeros(y.shape[0])
    model.rhs(t, y, p, mode, f)
    return advance(model.rhs, model.events, model.event_curvature, t, t_end, y, f, p, mode, opt, w)


def step_to_event(t, t_end, y, p, mode, opt, h, max_steps=200):
    """``advance`` from (t, y) in ``mode`` with first step h until an event fires or t_end is
    reached, every step OK; returns (t, the event's index or −1). y ends as the state."""
    w = make_work(2, 2, h)
    which = -1
    for _ in range(max_steps):
        status, t, which = free_step(t, t_end, y, p, mode, opt, w)
        assert status == OK
        if which >= 0 or t >= t_end:
            break
    return t, which
