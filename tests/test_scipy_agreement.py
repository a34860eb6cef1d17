"""campar's integrator against an independent SciPy implementation (DOP853, rtol 1e-12)."""

import numpy as np
import pytest

from campar.bench.scipy_model import Model, integrate
from campar.core.revolution import make_trace
from campar.core.tracer import trace_orbit
from campar.sweep.job import cell_job
from campar.sweep.tile import cell_settings, solver_options
from campar.views.point import EVENT_NAMES

# (omega, f0, mu_kn, mu_cn, clamp, start state, revolutions): contact only, impacting,
# a 2-cycle with the clamp active, the paper's literal law, and fast with strong damping.
REGIMES = [
    (0.3, 0.5, 0.8, 0.8, True, (0.0, 0.0), 2),
    (1.0, 0.5, 0.8, 0.8, True, (0.0, 0.0), 3),
    (3.0, 0.5, 0.91, 0.8, True, (0.5, -0.5), 3),
    (3.0, 0.5, 0.8, 0.8, False, (0.0, 0.0), 3),
    (5.0, 0.2, 0.8, 0.95, True, (0.0, 0.0), 3),
]


def campar_orbit(
    omega, f0, mu_kn, mu_cn, clamp, x0, revolutions, rtol, method="dp54", rk4_steps=600
):
    """Final state and events of campar's integration of whole revolutions from x0."""
    job = cell_job(
        omega=omega,
        f0=f0,
        mu_kn=mu_kn,
        mu_cn=mu_cn,
        zeta=0.2,
        tensile="clamp" if clamp else "allow",
        y0=x0[0],
        v0=x0[1],
        rtol=rtol,
        atol=rtol * 1e-2,
        method=method,
        outputs=["label"],
    )
    settings = cell_settings(job)._replace(rk4_steps=rk4_steps)
    rec = make_trace(1, 1000, 1)  # one sample slot: recording on, so events are kept
    status, y, v = trace_orbit(
        omega,
        0.2,
        f0,
        mu_kn,
        mu_cn,
        clamp,
        np.array(x0, float),
        solver_options(job),
        settings,
        revolutions,
        rec,
    )
    assert status == 0
    events = rec.events[: rec.count[1]]
    return np.array([y, v]), [(t, EVENT_NAMES[int(code)]) for t, _, _, code in events]


@pytest.fixture(scope="module")
def references():
    return {
        regime: integrate(Model(*regime[:4], zeta=0.2, clamp=regime[4]), regime[5], regime[6])
        for regime in REGIMES
    }


@pytest.mark.parametrize("regime", REGIMES, ids=lambda r: f"omega{r[0]}-clamp{r[4]}")
@pytest.mark.parametrize("rtol", [1e-6, 1e-8, 1e-10])
def test_state_and_events_match_scipy(regime, rtol, references):
    ref_state, ref_events, _ = references[regime]
    state, events = campar_orbit(*regime, rtol=rtol)
    # the global error of a revolution stays within a small multiple of rtol
    assert np.max(np.abs(state - ref_state)) < 20 * rtol + 1e-12
    assert [kind for _, kind in events] == [kind for _, kind in ref_events]
    times = np.array([t for t, _ in events])
    ref_times = np.array([t for t, _ in ref_events])
    assert np.max(np.abs(times - ref_times), initial=0.0) < 20 * rtol + 1e-12


@pytest.mark.parametrize(
    "regime, min_ratio",
    [
        # in permanent contact the field is smooth: 4th order, error / 16 per halving
        (REGIMES[0], 14.0),
        # at an impact the force grows like s^{3/2} (s = time since contact), and
        # RK4's quadrature of s^{3/2} over the first step errs by O(h^{5/2}): order 2.5
        (REGIMES[1], 4.5),
    ],
    ids=["contact-only", "impacting"],
)
def test_rk4_order(regime, min_ratio, references):
    ref_state, _, _ = references[regime]
    errors = [
        np.max(np.abs(campar_orbit(*regime, rtol=1e-8, method="rk4", rk4_steps=n)[0] - ref_state))
        for n in (480, 960)
    ]
    assert errors[0] / errors[1] > min_ratio, errors
