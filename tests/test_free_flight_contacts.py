"""A contact inside one free-flight step is found: the first root of ε, not a later one.

In free flight the field does not see the cam, so the step size knows nothing of the
cam's lift: a step over most of a cycloidal fall (0.75 rad at ω ≈ 1.35, μkn 0.95) can hold
a whole contact of 0.17 rad, ε up to 0.07, between two ends in flight, and a step that
ends in contact can hold three roots of ε, of which the first is the event. The search
bounds |ε''| by the phase's largest |S''| and the free follower's energy
(model.event_curvature, event_roots.may_cross) and reads the dense output where the bound
cannot rule a root out. Independent references: the free flight in closed form with the
cycloidal fall (brentq), SciPy's shooting of the cell's cycle, and along a chain every
step's dense output read against the cam's exact lift.
"""

import math

import numpy as np
import pytest
from scipy.optimize import brentq
from support.free_flight import damped_flight, step_to_event

import campar
from campar.core import event_roots
from campar.core.integrator import SolverOptions
from campar.core.jit import through_numba
from campar.core.model import FALL, FREE, make_params
from campar.core.stages import DOP853, method_tag
from campar.model.compute import model_law, run_cells
from campar.model.model import Model

ZETA, F0, MU_KN, MU_CN = 0.2, 0.5, 0.95, 0.8
OMEGA = 1.3541666666666667  # a cell of the chain ω 6 → 1 (241 cells) at μkn 0.95
CYCLOIDAL = {"model": {"cam": {"rise": "cycloidal", "fall": "cycloidal"}}}
FALL_START, FALL_WIDTH = math.pi, math.pi / 3.0  # the paper's angles
# The follower at the fall's start, in flight (ε = −0.097), on that cell's cycle.
Y0 = (1.0970359770278213, -1.2355374019733933)


T0 = FALL_START / OMEGA
free_flight = damped_flight(Y0, T0, ZETA, F0)


def cycloidal_fall(theta):
    u = (theta - FALL_START) / FALL_WIDTH
    return 1.0 - (u - math.sin(2.0 * math.pi * u) / (2.0 * math.pi))


def first_contact(t_end):
    """The first root of ε = yc − y after T0: a sign change on a fine grid, then brentq."""

    def eps(t):
        return cycloidal_fall(OMEGA * t) - free_flight(t)

    grid = np.linspace(T0, t_end, 20001)
    values = np.array([eps(t) for t in grid])
    k = int(np.flatnonzero(values > 0.0)[0])
    return brentq(eps, grid[k - 1], grid[k], xtol=1e-14), int(np.sum(np.diff(values > 0) != 0))


def cell_model(omega=OMEGA):
    return Model.build({"omega": omega, "f0": F0, "mu_kn": MU_KN, "mu_cn": MU_CN, **CYCLOIDAL})


@pytest.mark.slow  # compiles the integrator for the cycloidal cam
@pytest.mark.parametrize("h", [0.05, 0.55, 1.0])
def test_a_free_flight_step_over_a_cycloidal_fall_ends_at_the_first_contact(h):
    t_end = (FALL_START + FALL_WIDTH) / OMEGA  # the fall's end; h = 1 stretches to it
    impact, crossings = first_contact(t_end)
    assert crossings == 3  # in, out and in again within the fall: the case at hand
    p = make_params(OMEGA, ZETA, F0, MU_KN, MU_CN, model_law(cell_model()))
    opt = SolverOptions(method_tag(DOP853), 1e-7, 1e-10, 0.0, 1e-11, 1e-11, 2)
    y = np.array(Y0)
    mode = np.array([FALL, FREE], dtype=np.int64)
    t, which = step_to_event(T0, t_end, y, p, mode, opt, h)
    assert which == 0
    assert t == pytest.approx(impact, abs=1e-7)
    assert y[0] == pytest.approx(free_flight(t), abs=1e-7)


def scipy_stable_cycle(parameters: dict, guess) -> tuple[np.ndarray, int]:
    """SciPy's 1-cycle near ``guess`` (campar.bench.scipy_shooting), asserted stable, and its
    detachments counted with SciPy's steps of at most 0.005: no contact shorter than that
    is missed."""
    from campar.bench import scipy_shooting
    from campar.bench.scipy_model import Model as ScipyModel
    from campar.bench.scipy_model import integrate

    x, jac = scipy_shooting.fixed_point(parameters, guess, 1)
    assert np.max(np.abs(np.linalg.eigvals(jac))) < 1.0
    _, events, _ = integrate(ScipyModel(**parameters), x, 1, rtol=1e-11, max_step=0.005)
    return x, sum(kind == "detachment" for _, kind in events)


@pytest.mark.slow  # SciPy's shooting at rtol 1e-12
def test_the_cell_is_scipys_cycle_with_its_three_detachments():
    cell = campar.simulate_point(cell_model(), state=(0.04699127614187787, 0.08432856508758493))
    parameters = {"omega": OMEGA, "f0": F0, "mu_kn": MU_KN, "mu_cn": MU_CN}
    parameters.update(rise="cycloidal", fall="cycloidal")
    x, detachments = scipy_stable_cycle(parameters, cell.state)
    assert (cell.label, detachments) == ("1-3", 3)
    np.testing.assert_allclose(cell.state, x, atol=1e-6)


@pytest.mark.slow  # SciPy's shooting at rtol 1e-12
def test_a_contact_between_a_detachment_and_the_next_flight_is_scipys():
    """3-4-5 laws, rise Φ1 = 0.806 (the design_rise_polynomial-345 job's row 82 at 400²): a
    flight of 0.06 rad after a detachment, then a contact of 0.5 rad, both inside one
    free-flight step that starts on the surface ε = 0."""
    angles = (0.8055137844611528, math.pi / 3.0, 2.0 * math.pi / 3.0)
    angles = (*angles, 2.0 * math.pi - sum(angles))
    cam = {"rise": "polynomial-345", "fall": "polynomial-345"}
    cam.update(zip(("phi1", "phi2", "phi3", "phi4"), angles, strict=True))
    omega = 1.2428571428571429
    cell = campar.simulate_point({"omega": omega, "model": {"cam": cam}})
    parameters = {"omega": omega, "rise": cam["rise"], "fall": cam["fall"], "angles": angles}
    x, detachments = scipy_stable_cycle(parameters, cell.state)
    assert (cell.label, detachments) == ("1-2", 2)
    np.testing.assert_allclose(cell.state, x, atol=1e-7)


def lower_envelope_minimum(g0, d0, g1, d1, bound):
    s = np.linspace(0.0, 1.0, 200001)
    left = g0 + d0 * s - 0.5 * bound * s * s
    right = g1 - d1 * (1.0 - s) - 0.5 * bound * (1.0 - s) ** 2
    return float(np.min(np.maximum(left, right)))


def test_may_cross_says_whether_the_lowest_g_the_bound_allows_reaches_zero():
    may_cross = through_numba(event_roots.may_cross)
    rng = np.random.default_rng(9)
    decided = {True: 0, False: 0}
    for _ in range(2000):
        g0, g1 = rng.uniform(1e-3, 1.0, 2)
        d0, d1 = rng.uniform(-2.0, 2.0, 2)
        bound = 10.0 ** rng.uniform(-2.0, 1.5)
        lowest = lower_envelope_minimum(g0, d0, g1, d1, bound)
        if abs(lowest) < 1e-6:
            continue  # at the grid's resolution
        assert may_cross(g0, d0, g1, d1, bound) == (lowest < 0.0), (g0, d0, g1, d1, bound)
        decided[lowest < 0.0] += 1
    assert min(decided.values()) > 200
    assert not may_cross(0.5, -0.3, 0.4, 0.2, 0.0)  # a linear g between positive ends


def wrong_steps(trace) -> np.ndarray:
    """Steps of an OrbitTrace whose dense samples leave their mode's side of ε = 0 (beyond
    1e-9, ε's rounding near an event): in flight ε ≤ 0, in contact ε ≥ 0."""
    eps = trace.by_step(trace.eps)[:, :-1]
    mode = trace.by_step(trace.contact)[:, -1]
    return np.where(mode == FREE, eps.max(axis=1) > 1e-9, eps.min(axis=1) < -1e-9)


@pytest.mark.slow  # compiles the orbit tracer for the cycloidal cam
def test_no_step_of_a_steady_orbit_holds_a_contact_or_a_flight_without_its_events():
    """Cycloidal laws at μkn 0.95, f0 1.0, the chain ω 1.60 → 1.46 from rest: at ω 1.52 the
    steady orbit's flight over the fall holds a second contact (1-2); every step of every
    cell's orbit, read on its dense output against the cam's exact lift, stays on its
    mode's side of ε = 0."""
    omega = np.linspace(6.0, 1.0, 241)[211:219]
    model = Model.build({"omega": omega[0], "f0": 1.0, "mu_kn": MU_KN, "mu_cn": MU_CN, **CYCLOIDAL})
    out = run_cells(model, omega=omega, outputs=("label",))
    labels = []
    for i, w in enumerate(omega):
        cell = model.replace(omega=w)
        result = campar.simulate_point(cell, state=tuple(out.state[i]), trace=True)
        labels.append(result.label)
        assert not wrong_steps(result.trace).any(), (w, result.label)
    assert labels == ["1-1"] * 4 + ["1-2"] * 4
