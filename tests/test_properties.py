"""Properties of any valid result over the parameter box (hypothesis)."""

import math

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from campar import simulate_point

box = dict(
    omega=st.floats(0.05, 6.0),
    f0=st.floats(0.0, 3.0),
    mu_kn=st.floats(0.5, 0.95),
    mu_cn=st.floats(0.3, 0.99),
    zeta=st.floats(0.05, 0.5),
    tensile=st.sampled_from(["clamp", "allow"]),
    y0=st.floats(-1.0, 2.0),
    v0=st.floats(-2.0, 2.0),
)


@given(**box)
@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_valid_results_are_finite_and_physical(omega, f0, mu_kn, mu_cn, zeta, tensile, y0, v0):
    r = simulate_point(
        omega,
        f0=f0,
        mu_kn=mu_kn,
        mu_cn=mu_cn,
        zeta=zeta,
        tensile=tensile,
        y0=y0,
        v0=v0,
        revolutions=120,
        rtol=1e-7,
        trace=True,
    )
    if r.status != "ok":
        assert r.kind == "failed" and math.isnan(r.dc)
        return
    for value in (r.dc, r.eps_min, r.eps_max, r.pn_max, *r.state):
        assert math.isfinite(value)
    assert 0.0 <= r.dc <= 1.0
    assert r.eps_min <= r.eps_max
    assert (r.p == 0) == (r.eps_min >= -1e-9) or r.kind != "periodic"
    tr = r.trace
    assert tr is not None and np.all(np.isfinite(tr.y))
    assert np.all(tr.pn[tr.eps <= 0] == 0.0)  # no force without contact
    if tensile == "clamp":
        assert r.pn_max >= 0.0 and np.all(tr.pn >= 0.0)
