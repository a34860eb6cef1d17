"""The paper's two ambiguities as options (docs/model.md): the duty cycle by separation or by
force, the cam velocity by the chain rule or as the paper's eq. 6 prints it.

Each option is checked against the independent SciPy model (campar.bench.scipy_model,
which implements both from docs/model.md), at cells where the option changes the answer,
so a kernel that ignored the option would fail here.
"""

import math

import numpy as np
import pytest

from campar.bench.scipy_model import Model, duty_cycle, integrate
from campar.core.jit import through_numba
from campar.core.model import (
    LAW_CAM_LITERAL,
    LAW_CLAMP,
    LAW_DC_FORCE,
    PUSH,
    SLACK,
    impact_mode,
    law_flags,
    make_params,
)
from campar.core.revolution import make_trace
from campar.core.tracer import trace_orbit
from campar.errors import JobError
from campar.sweep.job import Job, cell_job, job_digest
from campar.sweep.store._cf import global_attrs
from campar.sweep.tile import cell_settings, solver_options
from campar.views.point import EVENT_NAMES, simulate_point

RTOL = 1e-10

# (omega, f0, mu_kn, mu_cn, tensile, start, revolutions): the clamp holding Pn = 0 inside
# contact (μcn = 0.9), a slow cam (ω < 1: the literal velocity is the larger one), fast
# with strong damping, and the paper's unclamped law.
REGIMES = [
    (3.0, 0.5, 0.8, 0.9, "clamp", (0.0, 0.0), 4),
    (0.5, 0.5, 0.8, 0.8, "clamp", (0.0, 0.0), 2),
    (5.0, 0.2, 0.8, 0.95, "clamp", (0.0, 0.0), 3),
    (3.0, 0.5, 0.8, 0.8, "allow", (0.0, 0.0), 3),
]


def campar_orbit(omega, f0, mu_kn, mu_cn, tensile, x0, revolutions, cam_velocity):
    """Final state and events of campar's integration (DP54 at RTOL) from x0 at θ = 0."""
    job = cell_job(
        omega=omega,
        f0=f0,
        mu_kn=mu_kn,
        mu_cn=mu_cn,
        tensile=tensile,
        cam_velocity=cam_velocity,
        y0=x0[0],
        v0=x0[1],
        rtol=RTOL,
        atol=RTOL * 1e-2,
        method="dp54",
        outputs=["label"],
    )
    rec = make_trace(1, 1000, 1)  # one sample slot: recording on, so events are kept
    status, y, v = trace_orbit(
        omega,
        0.2,
        f0,
        mu_kn,
        mu_cn,
        job.model.law,
        np.array(x0, float),
        solver_options(job),
        cell_settings(job),
        revolutions,
        rec,
    )
    assert status == 0
    events = rec.events[: rec.count[1]]
    return np.array([y, v]), [(t, EVENT_NAMES[int(code)]) for t, _, _, code in events]


def scipy_orbit(omega, f0, mu_kn, mu_cn, tensile, x0, revolutions, cam_velocity):
    model = Model(
        omega, f0, mu_kn, mu_cn, zeta=0.2, clamp=tensile == "clamp", cam_velocity=cam_velocity
    )
    state, events, _ = integrate(model, x0, revolutions)
    return state, events


@pytest.mark.parametrize("regime", REGIMES, ids=lambda r: f"omega{r[0]}-{r[4]}")
def test_literal_cam_velocity_matches_scipy(regime):
    state, events = campar_orbit(*regime, cam_velocity="literal")
    ref_state, ref_events = scipy_orbit(*regime, cam_velocity="literal")
    assert np.max(np.abs(state - ref_state)) < 20 * RTOL
    assert [kind for _, kind in events] == [kind for _, kind in ref_events]
    times = np.array([t for t, _ in events]) - np.array([t for t, _ in ref_events])
    assert np.max(np.abs(times), initial=0.0) < 20 * RTOL
    # the option is not a no-op: the chain rule's orbit is elsewhere (ω ≠ 1)
    chain_state, _ = scipy_orbit(*regime, cam_velocity="chain")
    assert np.max(np.abs(chain_state - ref_state)) > 1e-3


def test_literal_cam_velocity_is_the_chain_rule_at_unit_speed():
    regime = (1.0, 0.5, 0.8, 0.9, "clamp", (0.0, 0.0), 3)
    literal, chain = (campar_orbit(*regime, cam_velocity=v) for v in ("literal", "chain"))
    np.testing.assert_array_equal(literal[0], chain[0])
    assert literal[1] == chain[1]


def test_literal_velocity_can_enter_contact_without_force():
    """At ω > 1 on the rise, the literal ε' = dyc/dθ − y' = dε/dt − (ω − 1) dyc/dθ is
    negative at a slow impact although ε rises; the clamp then holds Pn = 0 from the
    impact on (SLACK) until the force resumes. Found by SciPy, matched by campar."""
    regime = (3.0, 0.5, 0.8, 0.9, "clamp", (0.0, 1.0), 3)
    ref_state, ref_events = scipy_orbit(*regime, cam_velocity="literal")
    assert [kind for _, kind in ref_events[:2]] == ["impact", "force resumes"]
    state, events = campar_orbit(*regime, cam_velocity="literal")
    assert [kind for _, kind in events] == [kind for _, kind in ref_events]
    assert np.max(np.abs(state - ref_state)) < 20 * RTOL


# (omega, mu_cn, tensile, cam_velocity): a 2-2 cycle with the clamp active in contact, the
# same cell unclamped, and the literal cam velocity with the clamp.
DC_CELLS = [
    (3.0, 0.9, "clamp", "chain"),
    (3.0, 0.9, "allow", "chain"),
    (2.0, 0.9, "clamp", "literal"),
]


@pytest.mark.parametrize("cell", DC_CELLS, ids=lambda c: "-".join(map(str, c)))
def test_duty_cycle_by_force_and_by_separation_match_scipy(cell):
    omega, mu_cn, tensile, cam_velocity = cell
    found = {
        by: simulate_point(
            omega, mu_cn=mu_cn, tensile=tensile, cam_velocity=cam_velocity, duty_cycle=by, rtol=RTOL
        )
        for by in ("separation", "force")
    }
    sep, force = found["separation"], found["force"]
    assert sep.kind == "periodic" and (sep.label, sep.state) == (force.label, force.state)
    model = Model(
        omega, 0.5, 0.8, mu_cn, zeta=0.2, clamp=tensile == "clamp", cam_velocity=cam_velocity
    )
    for by, result in found.items():
        # SciPy over the cycle's n revolutions from campar's state on it
        assert abs(duty_cycle(model, result.state, result.n, by=by) - result.dc) < 1e-7, by
    if tensile == "clamp":
        assert force.dc > sep.dc + 0.01  # the clamp's SLACK time counts by force only
    else:
        assert force.dc == sep.dc  # unclamped, Pn = 0 only while separated


def test_law_bits_and_job_settings():
    assert law_flags() == LAW_CLAMP
    assert law_flags("allow", "force", "literal") == LAW_DC_FORCE | LAW_CAM_LITERAL
    with pytest.raises(ValueError, match="separation, force"):
        law_flags(duty_cycle="time")
    base = {
        "name": "x",
        "sweep": {
            "omega": {"from": 1, "to": 2, "points": 2},
            "f0": {"from": 1, "to": 2, "points": 2},
        },
    }
    job = Job.from_dict(base)
    literal = Job.from_dict({**base, "model": {"cam_velocity": "literal"}})
    by_force = Job.from_dict({**base, "model": {"duty_cycle": "force"}})
    assert literal.model.law_bits == LAW_CLAMP | LAW_CAM_LITERAL
    assert len({job.digest(), literal.digest(), by_force.digest()}) == 3
    # a store written before the options existed holds a job without them: same hash
    old = job.to_dict()
    del old["model"]["duty_cycle"], old["model"]["cam_velocity"]
    assert job_digest(old) == job.digest()
    for key, bad in (("duty_cycle", "time"), ("cam_velocity", 1.0)):
        with pytest.raises(JobError) as err:
            Job.from_dict({**base, "model": {key: bad}})
        assert str(err.value).count("\n") == 0 and f"model.{key}" in str(err.value)
    attrs = global_attrs(literal, "now")
    assert attrs["cam_velocity"] == "literal" and "eq. 6" in attrs["cam_velocity_definition"]
    assert attrs["duty_cycle"] == "separation" and "ε < 0" in attrs["duty_cycle_definition"]


def test_point_reports_its_options():
    result = simulate_point(2.0, duty_cycle="force", cam_velocity="literal")
    assert result.parameters["duty_cycle"] == "force"
    assert result.parameters["cam_velocity"] == "literal"
    assert math.isfinite(result.dc)


def test_an_impact_enters_slack_only_under_the_clamp_with_a_negative_bracket():
    clamped = make_params(3.0, 0.2, 0.5, 0.8, 0.9, LAW_CLAMP | LAW_CAM_LITERAL)
    assert through_numba(impact_mode)(-1.0 / clamped.c - 1e-9, clamped) == SLACK
    assert through_numba(impact_mode)(-1.0 / clamped.c + 1e-9, clamped) == PUSH
    allowed = make_params(3.0, 0.2, 0.5, 0.8, 0.9, LAW_CAM_LITERAL)
    assert through_numba(impact_mode)(-10.0, allowed) == PUSH  # unclamped, the force pulls instead
    assert clamped.vcam == 1.0 and make_params(3.0, 0.2, 0.5, 0.8, 0.9, 1).vcam == 3.0
