"""A mode entered on its own switching surface leaves it at the next crossing, not at once.

Where a detachment happens with 1 + c ε' ≈ 0 (600 × 600 jobs/mu_cn.yaml, ω ≈ 0.72–0.76,
μcn ≈ 0.83–0.88), the free flight starts with −ε at the rounding level of ε = yc − y.
A step long enough to reach the next impact once put the impact at the step's start:
the follower swapped between contact and flight at one instant (status event_loop).
"""

import math

import numpy as np
import pytest
from scipy.optimize import brentq
from support.free_flight import damped_flight, step_to_event

from campar.core.integrator import SolverOptions
from campar.core.model import FALL, FREE, PAPER_LAW, make_params
from campar.core.stages import DOP853, method_tag

# The free flight after the detachment of the cell (ω, μcn) = (0.75876…, 0.88030…) of the
# 600 × 600 (ω, μcn) plane (f0 0.5, μkn 0.8, ζ 0.2), at the detachment, −ε = 5.6e-17.
OMEGA = 0.7587646076794652
MU_CN = 0.8803005008347244
T0 = 5.041938288581982
Y0 = (0.26850804780352705, -0.6694702171548769)
ZETA, F0 = 0.2, 0.5


free_flight = damped_flight(Y0, T0, ZETA, F0)


def cam_fall(t):
    """The paper's cosine fall, yc on θ ∈ [π, 4π/3]."""
    return 0.5 * (1.0 + math.cos(3.0 * (OMEGA * t - math.pi)))


@pytest.mark.parametrize("h", [0.05, 0.4, 1.0])
def test_a_free_flight_entered_on_the_surface_ends_at_the_impact(h):
    t_end = (4.0 * math.pi / 3.0) / OMEGA  # the fall's end; h = 1 stretches to it
    p = make_params(OMEGA, ZETA, F0, 0.8, MU_CN, PAPER_LAW)
    opt = SolverOptions(method_tag(DOP853), 1e-7, 1e-10, 0.0, 1e-11, 8.3e-12, 2)
    y = np.array(Y0)
    assert 0.0 < -(cam_fall(T0) - y[0]) < 1e-15  # on the surface, by rounding
    mode = np.array([FALL, FREE], dtype=np.int64)
    t, which = step_to_event(T0, t_end, y, p, mode, opt, h)
    impact = brentq(lambda s: cam_fall(s) - free_flight(s), T0 + 1e-3, t_end)
    assert which == 0
    assert t == pytest.approx(impact, abs=1e-7)
    assert t - T0 > 0.3
