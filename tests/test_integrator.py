"""The Runge–Kutta machinery on problems with exact solutions."""

import math
from typing import NamedTuple

import numpy as np
import pytest
from numba import njit

from campar.core import dopri5, stages
from campar.core import integrator as I
from campar.core.hermite import hermite_extremum
from campar.core.jit import through_numba


class Omega(NamedTuple):
    w: float
    dip: float = 0.0  # which event ``crossing`` watches: y = 0 (0.0) or the dip (1.0)


@njit
def oscillator(t, y, p, mode, dy):
    # y'' = -w² y: y = cos(w t) from (1, 0); with w = 0, y = t from (0, 1)
    dy[0] = y[1]
    dy[1] = -p.w * p.w * y[0]


@njit
def crossing(t, y, f, p, mode, g, dg):
    # p.dip == 0: y crosses zero downward (mode 0) or upward (mode 1). p.dip == 1:
    # (y - 1)² − 1e-4, positive but for a dip of width 0.02 around y = 1 (mode 0), and its
    # negative inside the dip (mode 1): roots at y = 1 ∓ 0.01. One function for both: the
    # tests of a method share one compilation of the integrator.
    sign = 1.0 if mode[0] == 0 else -1.0
    if p.dip != 0.0:
        g[0] = sign * ((y[0] - 1.0) ** 2 - 1e-4)
        dg[0] = sign * 2.0 * (y[0] - 1.0) * f[0]
    else:
        g[0] = sign * y[0]
        dg[0] = sign * f[0]
    return 1


@njit
def no_curvature(y, p, mode):
    """No bound on the event functions' curvature: the cubic model's dip test."""
    return math.inf


def run(rhs, events, y0, t_end, p, opt, max_steps):
    """Step to t_end; returns the final state and the times of events (stopping at each)."""
    return run_compiled(
        rhs, events, y0.copy(), t_end, p, opt, max_steps, I.make_work(y0.shape[0], 2, 1e-3)
    )


@njit
def run_compiled(rhs, events, y, t_end, p, opt, max_steps, w):
    """``run`` with the buffers the core's callers allocate in Python (``make_work``)."""
    f = np.zeros(y.shape[0])
    mode = np.zeros(2, dtype=np.int64)
    rhs(0.0, y, p, mode, f)
    times = np.full(16, np.nan)
    n_events = 0
    t = 0.0
    for _ in range(max_steps):
        if t >= t_end:
            break
        status, t, which = I.advance(rhs, events, no_curvature, t, t_end, y, f, p, mode, opt, w)
        if which >= 0:
            times[n_events] = t
            n_events += 1
            mode[0] = 1 - mode[0]
            rhs(t, y, p, mode, f)
    return y, times[:n_events], w.counts.copy()


def options(method=stages.DP54, rtol=1e-10, h_fixed=0.0):
    return I.SolverOptions(stages.method_tag(method), rtol, rtol * 1e-2, h_fixed, 1e-14, 1e-13, 2)


def test_tableau_invariants():
    np.testing.assert_allclose(dopri5.A.sum(axis=1), dopri5.C, atol=1e-15)  # row sums are the nodes
    assert dopri5.B.sum() == pytest.approx(1.0, abs=1e-15)
    assert dopri5.E.sum() == pytest.approx(0.0, abs=1e-15)  # both solutions are consistent
    np.testing.assert_allclose(dopri5.A[6], dopri5.B[:6], atol=0)  # FSAL: stage 7 is the solution
    # the dense output at θ = 1 is the 5th-order solution
    np.testing.assert_allclose(dopri5.P.sum(axis=1), dopri5.B, atol=1e-14)
    # order conditions of the 5th-order weights up to b·c⁴ = 1/5
    for q in range(5):
        assert (dopri5.B * dopri5.C**q).sum() == pytest.approx(1.0 / (q + 1), abs=1e-14)


@pytest.mark.parametrize("rtol", [1e-6, 1e-8, 1e-10])
@pytest.mark.slow  # compiles the integrator for a field and a method of its own
def test_dp54_error_tracks_rtol_on_an_oscillator(rtol):
    p = Omega(2.0)
    # to t = 1 the solution crosses y = 0 once (t = π/4): an event on the way
    y, _, counts = run(
        oscillator, crossing, np.array([1.0, 0.0]), 1.0, p, options(rtol=rtol), 10**6
    )
    exact = np.array([math.cos(2.0), -2.0 * math.sin(2.0)])
    assert np.max(np.abs(y - exact)) < 10 * rtol
    assert counts[0] < 2000


def test_events_are_located_on_exact_roots():
    p = Omega(1.5)
    _, times, _ = run(oscillator, crossing, np.array([1.0, 0.0]), 10.0, p, options(), 10**6)
    roots = (np.arange(len(times)) + 0.5) * math.pi / 1.5
    assert len(times) == 5  # roots of cos(1.5 t) in (0, 10]: (k + 1/2) π / 1.5
    np.testing.assert_allclose(times, roots, atol=1e-9)


@pytest.mark.slow  # compiles the integrator for a field and a method of its own
def test_rk4_fixed_step_error_is_fourth_order():
    p = Omega(1.0)
    errs = []
    for h in (0.1, 0.05):
        y, _, _ = run(
            oscillator,
            crossing,
            np.array([1.0, 0.0]),
            1.4,
            p,
            options(stages.RK4, h_fixed=h),
            10**6,
        )
        errs.append(abs(y[0] - math.cos(1.4)))
    assert 12 < errs[0] / errs[1] < 20


@pytest.mark.slow  # compiles the integrator for a field and a method of its own
def test_two_roots_inside_one_step_are_found():
    # RK4 steps of 0.8 jump over the whole dip of g between y = 0.99 and 1.01: the step
    # (0.8, 1.6] has g > 0 at both ends; on y = t (RK4 exact) the roots are t = 1 ∓ 0.01
    p = Omega(0.0, dip=1.0)
    y0 = np.array([0.0, 1.0])
    _, times, _ = run(oscillator, crossing, y0, 1.6, p, options(stages.RK4, h_fixed=0.8), 100)
    np.testing.assert_allclose(times, [0.99, 1.01], rtol=0, atol=1e-9)


def test_hermite_extremum_of_a_known_cubic():
    # g(θ) = (θ - 0.5)² - 0.01 has its minimum -0.01 at θ = 0.5
    g0, g1 = 0.24, 0.24
    d0, d1 = -1.0, 1.0
    theta, value = through_numba(hermite_extremum)(g0, d0, g1, d1, True)
    assert theta == pytest.approx(0.5)
    assert value == pytest.approx(-0.01)
    assert through_numba(hermite_extremum)(g0, d0, g1, d1, False)[0] == -1.0
