"""Floquet multipliers of periodic cells against independent SciPy computations."""

import math

import numpy as np
import pytest

from campar import simulate_point
from campar.bench.scipy_model import Model, integrate

CELLS = [
    dict(omega=3.15, mu_kn=0.91),  # 2-2 with the clamp active
    dict(omega=1.0, f0=0.5),  # 1-1
    dict(omega=0.3),  # 1-0, permanent contact
    dict(omega=3.5, mu_cn=0.5),  # 2-2 (reference cell 29)
]


@pytest.mark.parametrize("cell", CELLS, ids=lambda c: "-".join(f"{k}{v}" for k, v in c.items()))
def test_multipliers_obey_liouville_and_match_finite_differences(cell):
    r = simulate_point(**cell, rtol=1e-10, multipliers=True, lyapunov=True)
    assert r.kind == "periodic"
    model = Model(
        cell["omega"],
        cell.get("f0", 0.5),
        cell.get("mu_kn", 0.8),
        cell.get("mu_cn", 0.8),
        0.2,
        True,
    )
    state = np.array(r.state)
    # Liouville: det DP^n = exp(∮ div f dt) along the orbit (SciPy integrates div f)
    _, _, integral = integrate(model, state, r.n, rtol=1e-11, atol=1e-13, with_divergence=True)
    product = np.prod(r.multipliers)
    assert product.real == pytest.approx(math.exp(integral), rel=1e-5)
    assert abs(product.imag) < 1e-12
    # the multipliers themselves: eigenvalues of a central-difference Jacobian of P^n
    jac = np.zeros((2, 2))
    for j in range(2):
        step = np.zeros(2)
        step[j] = 1e-6
        plus = integrate(model, state + step, r.n, rtol=1e-11, atol=1e-13)[0]
        minus = integrate(model, state - step, r.n, rtol=1e-11, atol=1e-13)[0]
        jac[:, j] = (plus - minus) / 2e-6
    ref = sorted(np.linalg.eigvals(jac), key=abs, reverse=True)
    np.testing.assert_allclose(sorted(r.multipliers, key=abs, reverse=True), ref, atol=2e-4)
    # a periodic cell's Lyapunov exponent is log|λ_max| per unit time
    assert r.lyapunov == pytest.approx(
        math.log(abs(r.multipliers[0])) / (r.n * 2 * math.pi / cell["omega"]), rel=1e-9
    )
