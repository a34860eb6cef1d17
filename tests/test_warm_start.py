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
    """The cycle points z(ω) of the cells at ``omegas`` (in the chain's order), newest
    first."""
    return np.array([z(w) for w in omegas])[::-1].copy()


COEFFICIENTS = np.array([[0.3, 0.2, -0.05, 0.01], [-0.4, 0.1, 0.0, 0.02]])  # of 1, ω, ω², ω³


def polynomial(degree):
    """A branch of cycle points z(ω), polynomial of ``degree`` in ω."""
    rows = COEFFICIENTS[:, : degree + 1]
    return lambda w: np.array([np.polyval(row[::-1], w) for row in rows])


cubic = polynomial(3)


@pytest.mark.parametrize("streak", [2, 3, 4])
def test_a_polynomial_branch_is_continued_exactly_by_the_order_the_cells_allow(streak):
    """streak cells give order streak − 1 (the cubic, EXTRAPOLATE_ORDER, from four), which
    continues a polynomial of that degree exactly: the start is the branch's next point."""
    h = 0.02
    omegas = 3.0 - h * np.arange(EXTRAPOLATE_ORDER + 1)  # the chain runs down in ω
    z = polynomial(streak - 1)
    order, start = warm_start(branch(z, omegas), streak)
    assert order == streak - 1 <= EXTRAPOLATE_ORDER
    np.testing.assert_allclose(start, z(omegas[-1] - h), rtol=0, atol=1e-13)


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
