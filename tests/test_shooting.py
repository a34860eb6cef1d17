"""The section map Pⁿ and its Jacobian (campar.core.shooting, campar.continuation.section_map)
against closed forms, difference quotients and an independent SciPy shooting."""

import math

import numpy as np
import pytest

from campar.bench import scipy_shooting
from campar.continuation.orbit import find_cycle, minimal_period
from campar.continuation.section_map import SectionMap, parameter_vector
from campar.errors import ContinuationError, JobError


@pytest.fixture(scope="module")
def smap():
    return SectionMap()


def test_free_flight_jacobian_is_the_damped_oscillators_exponential(smap):
    """Held off the cam (f0 = −2: rest at y = 2), one revolution is x' = A x over 2π/ω with
    A = [[0, 1], [−1, −2ζ]]: DP = exp(A T), eigenvalues exp(T(−ζ ± i√(1 − ζ²)))."""
    omega, zeta = 1.0, 0.2
    par = np.array([omega, zeta, -2.0, 0.8, 0.8])
    shot = smap.shoot((2.0, 0.0), par, 1)
    assert np.abs(shot.residual).max() < 1e-14  # the rest point
    exact = np.exp(2 * math.pi / omega * complex(-zeta, math.sqrt(1 - zeta**2)))
    got = sorted(np.linalg.eigvals(shot.jacobian), key=lambda z: z.imag)
    np.testing.assert_allclose(
        got, sorted([exact.conjugate(), exact], key=lambda z: z.imag), rtol=1e-9
    )
    assert shot.detachments == 0 and shot.time_free == pytest.approx(2 * math.pi)


def test_jacobian_is_the_derivative_of_the_image(smap):
    """DPⁿ from the variational equations against central differences of Pⁿ itself, on an
    impacting 2-cycle (contact, detachment and the clamp's force-zero switch inside)."""
    par = parameter_vector({"omega": 3.54, "mu_kn": 0.91})
    x = np.array([0.5318516885, -0.7189890713])
    shot = smap.shoot(x, par, 2)
    h = 1e-6
    columns = []
    for j in range(2):
        e = np.zeros(2)
        e[j] = h
        plus, minus = smap.shoot(x + e, par, 2).image, smap.shoot(x - e, par, 2).image
        columns.append((plus - minus) / (2 * h))
    np.testing.assert_allclose(shot.jacobian, np.column_stack(columns), atol=2e-6)


def test_parameter_derivative_is_the_difference_of_images(smap):
    par = parameter_vector({"omega": 3.0})
    x = np.array([0.5, -0.5])
    got = smap.parameter_derivative(x, par, 1, 0)
    for h in (1e-4, 1e-3):
        up, down = par.copy(), par.copy()
        up[0] += h
        down[0] -= h
        ref = (smap.shoot(x, up, 1).image - smap.shoot(x, down, 1).image) / (2 * h)
        np.testing.assert_allclose(got, ref, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize(
    ("parameters", "guess", "n", "label"),
    [
        ({"omega": 3.54, "mu_kn": 0.91}, (0.54, -0.72), 1, "1-1"),  # unstable, μ < −1
        ({"omega": 3.54, "mu_kn": 0.91}, (0.5318, -0.7190), 2, "2-2"),  # stable, μ ≈ 0.985
        ({"omega": 5.6, "mu_kn": 0.91}, (-0.55, -0.45), 3, "3-1"),
    ],
)
def test_cycles_agree_with_an_independent_scipy_shooting(smap, parameters, guess, n, label):
    """Newton with the exact Jacobian against SciPy's Newton with a difference Jacobian
    (rtol 1e-12): states to 1e-8, multipliers to 1e-6."""
    orbit = find_cycle(n, guess, section_map=smap, **parameters)
    assert orbit.label == label and orbit.residual <= 1e-10
    x, m = scipy_shooting.fixed_point(parameters, guess, n)  # from the guess, not campar's x
    assert np.abs(x - np.array(orbit.state)).max() < 1e-8
    np.testing.assert_allclose(
        np.array(orbit.multipliers), scipy_shooting.multipliers(m), atol=1e-6
    )


def test_an_unstable_cycle_past_a_period_doubling_has_a_multiplier_below_minus_one(smap):
    orbit = find_cycle(1, (0.54, -0.72), section_map=smap, omega=3.54, mu_kn=0.91)
    assert not orbit.stable
    assert orbit.multipliers[0].imag == 0.0 and orbit.multipliers[0].real < -1.0
    # and Newton converges quadratically: a handful of iterations from 0.01 away
    assert orbit.iterations <= 5


def test_newton_on_a_double_period_finds_the_cycle_of_the_divisor(smap):
    """From the 1-cycle's state, P² has the 1-cycle as a fixed point: reported as period 1."""
    orbit = find_cycle(2, (0.5405, -0.7247), section_map=smap, omega=3.54, mu_kn=0.91)
    assert orbit.n == 1 and len(orbit.sections) == 1
    assert minimal_period(np.array([[0.0, 1.0], [0.0, 1.0 + 1e-9]])) == 1
    assert minimal_period(np.array([[0.0, 1.0], [0.5, 1.0]])) == 2


def test_bad_requests_are_refused_in_one_line(smap):
    with pytest.raises(JobError, match="mu_kn must be in"):
        find_cycle(1, (0.5, -0.5), section_map=smap, omega=3.0, mu_kn=1.5)
    with pytest.raises(JobError, match="unknown parameter"):
        find_cycle(1, (0.5, -0.5), section_map=smap, omega=3.0, mukn=0.9)
    with pytest.raises(ContinuationError, match="period must be"):
        find_cycle(0, (0.5, -0.5), section_map=smap, omega=3.0)
    with pytest.raises(ContinuationError, match="found no 1-cycle"):
        find_cycle(1, (1e6, 1e6), section_map=smap, omega=3.0)
