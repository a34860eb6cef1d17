"""Section analysis on synthetic sequences with known answers."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from campar.core import analysis as A
from campar.core.codes import CHAOTIC, QUASIPERIODIC, UNCONVERGED
from campar.core.hermite import quintic_extremum
from campar.core.jit import through_numba


def linear_history(z, L, x0, revolutions):
    """Section points and Jacobians of the affine map x ↦ z + L (x − z)."""
    xs = np.zeros((revolutions + 1, 2))
    jac = np.tile(L.ravel(), (revolutions, 1))
    xs[0] = x0
    for k in range(revolutions):
        xs[k + 1] = z + L @ (xs[k] - z)
    return xs, jac


def assess(xs, jac, k, base=0, conv_tol=1e-9):
    est = np.full((32, 32, 3), -1.0)
    return through_numba(A.assess_revolution)(
        xs, jac, est, k, base, 32, conv_tol, 1e-6, 0.05, 0.02, 0.0
    )


def test_slow_one_cycle_is_not_taken_for_a_two_cycle():
    # multiplier −0.99: x_k − x_{k−2} shrinks 50× faster than the distance to the cycle,
    # so a plain repeat test at 1e-6 would call this a 2-cycle long before it converges
    z = np.array([0.3, -0.2])
    L = np.diag([-0.99, 0.5])
    xs, jac = linear_history(z, L, z + [1e-4, 0.0], 10)
    assert np.max(np.abs(xs[10] - xs[8])) < 1e-5  # the naive 2-cycle test would pass
    period, jump, z0, z1 = assess(xs, jac, 10)
    assert period == 0
    assert jump == 1  # …and a Newton jump lands on the 1-cycle exactly (the map is affine)
    np.testing.assert_allclose([z0, z1], z, atol=1e-15)


def test_converged_one_cycle_is_accepted():
    z = np.array([0.3, -0.2])
    xs, jac = linear_history(z, np.diag([-0.99, 0.5]), z + [1e-11, 0.0], 3)
    assert assess(xs, jac, 3)[0] == 1


def test_two_cycle_is_found_and_not_mistaken_for_one():
    a, b = np.array([0.1, 0.2]), np.array([0.1 + 1e-3, 0.2])
    xs = np.array([a, b, a, b, a])
    # Jacobian of one revolution: swap-like, with a stable 2-cycle (DP² = 0.25 I)
    jac = np.tile(np.array([[0.0, 0.5], [0.5, 0.0]]).ravel(), (4, 1))
    period, *_ = assess(xs, jac, 4)
    assert period == 2


def test_unstable_cycle_is_never_accepted():
    z = np.array([0.0, 0.0])
    xs, jac = linear_history(z, np.diag([1.5, 0.5]), z + [1e-12, 0.0], 3)
    period, jump, *_ = assess(xs, jac, 3)
    assert period == 0 and jump == 0


def assess_each_revolution(xs, jac, agree):
    """assess_revolution after every revolution, as the kernel calls it (one est buffer)."""
    est = np.full((32, 32, 3), -1.0)
    assess_revolution = through_numba(A.assess_revolution)
    return [
        assess_revolution(xs, jac, est, k, 0, 32, 1e-9, 1e-6, 1e-3, 0.02, agree)
        for k in range(1, xs.shape[0])
    ]


def test_slow_cycle_far_away_is_reached_by_a_jump_on_agreeing_estimates():
    # multiplier 0.998: |x_k − x_{k−1}| is 500× smaller than the distance 0.1 to the
    # cycle, far beyond the jump cap; on an affine map every estimate is exact, so the
    # estimates agree and the jump is trusted from the second revolution on
    z = np.array([0.3, -0.2])
    xs, jac = linear_history(z, np.diag([0.998, 0.5]), z + [0.1, 0.0], 4)
    assert all(jump == 0 for _, jump, *_ in assess_each_revolution(xs, jac, agree=0.0))
    results = assess_each_revolution(xs, jac, agree=0.1)
    assert results[0][1] == 0  # one estimate alone is not trusted
    period, jump, z0, z1 = results[1]
    assert period == 0 and jump == 1
    np.testing.assert_allclose([z0, z1], z, atol=1e-12)


def test_estimates_that_disagree_are_not_trusted():
    # x ↦ z + λ e + a e² (e = x − z), stable but strongly nonlinear at e = 0.1: each
    # Newton estimate moves by about a fifth of its distance from one to the next
    lam, a, z = 0.95, -1.5, 0.3
    xs = np.zeros((6, 2))
    jac = np.zeros((5, 4))
    xs[0] = [z + 0.1, 0.0]
    for k in range(5):
        e = xs[k, 0] - z
        xs[k + 1] = [z + lam * e + a * e * e, 0.0]
        jac[k] = [lam + 2 * a * e, 0.0, 0.0, 0.5]
    assert all(jump == 0 for _, jump, *_ in assess_each_revolution(xs, jac, agree=0.1))
    assert any(jump == 1 for _, jump, *_ in assess_each_revolution(xs, jac, agree=0.5))


def test_distinct_period_merges_points_within_tolerance():
    xs = np.array([[0, 0], [1, 0], [0, 0], [1 + 1e-8, 0], [0, 1e-9]], float)
    assert through_numba(A.distinct_period)(xs, 4, 4, 1e-6) == 2
    assert through_numba(A.distinct_period)(xs, 4, 4, 1e-10) == 4


def test_a_two_cycle_within_reach_of_a_stable_one_cycle_is_the_one_cycle():
    # two points 2e-6 apart (beyond period_tol 1e-6): with the 1-cycle's multiplier −0.979
    # (stable, next to a flip) the cycle is the 1-cycle; at −1.02 (unstable, just past the
    # flip) a genuine 2-cycle; 1e-3 apart it is a 2-cycle whatever the multiplier
    def cycle(gap, multiplier):
        a, b = np.array([0.19, -1.12]), np.array([0.19 + gap, -1.12])
        xs = np.array([a, b, a, b, a])
        jac = np.tile(np.diag([multiplier, 0.1]).ravel(), (4, 1))
        return through_numba(A.stable_subperiod)(
            xs, jac, 4, through_numba(A.distinct_period)(xs, 4, 2, 1e-6), 1e-5
        )

    assert cycle(2e-6, -0.979) == 1
    assert cycle(2e-6, -1.02) == 2
    assert cycle(1e-3, -0.979) == 2


def test_quintic_extremum_matches_a_sampled_quintic():
    rng = np.random.default_rng(7)
    th = np.linspace(0, 1, 200001)
    checked = 0
    for _ in range(50):
        q = np.polynomial.Polynomial(rng.normal(size=6))
        dq, ddq = q.deriv(), q.deriv(2)
        ends = (q(0), dq(0), ddq(0), q(1), dq(1), ddq(1))
        for want_min in (True, False):
            t, value = through_numba(quintic_extremum)(*ends, want_min)
            if t <= 0.0:
                continue  # no interior extremum of that kind in the cubic through the ends
            # a true local extremum of the quintic (not just a value of it), located to 1e-9
            assert abs(dq(t)) < 1e-9 * (1 + np.abs(dq(th)).max())
            assert (ddq(t) > 0) == want_min
            assert value == pytest.approx(q(t), abs=1e-12)
            checked += 1
    assert checked >= 20


def test_repeat_period_needs_two_full_periods():
    cycle = np.array([[0, 0], [1, 0], [2, 0]], float)
    xs = np.vstack([cycle] * 3)
    assert through_numba(A.repeat_period)(xs, 0, 8, 32, 1e-9) == 3
    assert through_numba(A.repeat_period)(xs, 0, 4, 32, 1e-9) == 0  # fewer than 2 periods seen


@given(st.lists(st.floats(-10, 10), min_size=4, max_size=4))
@settings(max_examples=200, deadline=None)
def test_eig2_matches_numpy(entries):
    m = np.array(entries).reshape(2, 2)
    re0, im0, re1, im1 = through_numba(A.eig2)(tuple(entries))
    ours = sorted([complex(re0, im0), complex(re1, im1)], key=lambda c: (c.real, c.imag))
    ref = sorted(np.linalg.eigvals(m), key=lambda c: (c.real, c.imag))
    scale = 1 + np.abs(m).max()
    tol = 1e-9 * scale
    if abs(ref[0] - ref[1]) < 1e-4 * scale:
        # Near a double eigenvalue, rounding the entries (ε) moves the eigenvalues by
        # O(√ε · |m|) in any method, numpy's included.
        tol += 4 * np.sqrt(np.finfo(float).eps) * scale
    np.testing.assert_allclose(ours, ref, atol=tol)
    assert abs(complex(re0, im0)) >= abs(complex(re1, im1)) - 1e-12


def test_nonperiodic_kind_thresholds():
    assert through_numba(A.nonperiodic_kind)(0.2, 0.01) == CHAOTIC
    assert through_numba(A.nonperiodic_kind)(0.004, 0.01) == QUASIPERIODIC
    assert through_numba(A.nonperiodic_kind)(-0.3, 0.01) == UNCONVERGED


def test_lyapunov_of_a_constant_map_is_log_of_its_spectral_radius():
    jac = np.array([2.0, 1.0, 0.0, 0.5])
    u = np.array([1.0, 1.0]) / np.sqrt(2)
    logs = [through_numba(A.stretch_tangent)(jac, u) for _ in range(200)]
    assert np.mean(logs[50:]) == pytest.approx(np.log(2.0), abs=1e-9)
