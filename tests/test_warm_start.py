"""The chain's warm start: the polynomial through the last cells' cycle points.

Checked against closed forms: a polynomial branch of the order used is continued exactly
(Newton's backward-difference formula), the order is the highest the cells allow and the
differences support: where they grow (the cells' own convergence error on a flat branch)
the order stays low, and across a jump of the cycle there is none.
"""

import numpy as np
import pytest
from support.jit import cached_njit

from campar.core.kernel import EXTRAPOLATE_MAX, EXTRAPOLATE_ORDER, extrapolated, extrapolation_order


@cached_njit
def warm_start(prev, streak):
    """(order, start) as the chain computes them from ``prev`` (newest first)."""
    order = extrapolation_order(prev, streak)
    start = np.empty(2)
    for c in range(2):
        start[c] = extrapolated(prev, order, c)
    return order, start


def branch(z, omegas):
    """The cycle points z(ω) of the cells at ``omegas``, newest (last computed) first."""
    return np.array([z(w) for w in omegas])[::-1].copy()


def cubic(w):
    return np.array([0.3 + 0.2 * w - 0.05 * w**2 + 0.01 * w**3, -0.4 + 0.1 * w + 0.02 * w**3])


@pytest.mark.parametrize("streak", [2, 3, 4])
def test_a_polynomial_branch_is_continued_exactly_by_the_order_the_cells_allow(streak):
    """streak cells give order streak − 1, which continues a polynomial of that degree
    exactly: the start is the branch's next point."""
    h = 0.02
    omegas = 3.0 - h * np.arange(EXTRAPOLATE_ORDER + 1)[::-1]  # the chain runs down in ω
    degree = streak - 1
    coefficients = np.array([[0.3, 0.2, -0.05, 0.01], [-0.4, 0.1, 0.0, 0.02]])[:, : degree + 1]

    def z(w):
        return np.array([np.polyval(row[::-1], w) for row in coefficients])

    prev = branch(z, omegas[::-1])  # omegas[::-1]: the chain's order, so prev[0] is ω = 3 − 3h
    order, start = warm_start(prev, streak)
    assert order == degree
    np.testing.assert_allclose(start, z(omegas[0] - h), rtol=0, atol=1e-13)


def test_a_smooth_branch_gets_the_cubic_and_lands_closest():
    h = 0.02
    omegas = 3.0 - h * np.arange(4)
    prev = branch(cubic, omegas)
    order, start = warm_start(prev, 4)
    assert order == EXTRAPOLATE_ORDER == 3
    np.testing.assert_allclose(start, cubic(3.0 - 4 * h), rtol=0, atol=1e-13)


def test_where_the_differences_grow_the_order_stays_low():
    """A flat branch whose cycle points carry the cells' own convergence error, ±δ in turn:
    each difference is twice the one below, so the start is the linear one, 3δ off, where
    the cubic through the same points would be 15δ off."""
    delta = 1e-9
    prev = np.array(
        [[0.2 + delta, -0.1], [0.2 - delta, -0.1], [0.2 + delta, -0.1], [0.2 - delta, -0.1]]
    )
    order, start = warm_start(prev, 4)
    assert order == 1
    np.testing.assert_allclose(start, [0.2 + 3 * delta, -0.1], rtol=0, atol=1e-15)


def test_no_extrapolation_from_one_cycle_or_across_a_jump():
    prev = branch(cubic, 3.0 - 0.02 * np.arange(4))
    order, start = warm_start(prev, 1)
    assert order == 0
    np.testing.assert_array_equal(start, prev[0])
    jumped = prev.copy()
    jumped[0] += EXTRAPOLATE_MAX  # the last cycle point lies past the jump
    order, start = warm_start(jumped, 4)
    assert order == 0
    np.testing.assert_array_equal(start, jumped[0])
