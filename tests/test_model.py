"""The model: cam law, contact force, vector field and its Jacobian, event functions."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from campar.core import model as M
from campar.core.cam import PAPER_CAM
from campar.core.jit import through_numba

BOUNDARIES = M.PHASE_BOUNDS[1:]


@pytest.mark.parametrize("i", range(4))
def test_cam_is_c1_across_phase_boundaries(i):
    theta = BOUNDARIES[i]
    before = through_numba(M.cam)(theta, i, PAPER_CAM)
    after = through_numba(M.cam)(theta if i < 3 else 0.0, (i + 1) % 4, PAPER_CAM)
    assert before[0] == pytest.approx(after[0], abs=1e-15)  # lift continuous
    assert before[1] == pytest.approx(after[1], abs=1e-14)  # velocity continuous
    assert abs(before[2] - after[2]) == pytest.approx(4.5)  # acceleration jumps by 4.5


def cam_at(theta):
    return through_numba(M.cam)(theta, through_numba(M.phase_of)(theta), PAPER_CAM)


def test_cam_law_values():
    assert cam_at(math.pi / 6)[0] == pytest.approx(0.5)  # half the rise
    assert cam_at(2.0)[0] == 1.0 and cam_at(5.0)[0] == 0.0
    assert cam_at(math.pi + math.pi / 6)[0] == pytest.approx(0.5)


params = st.builds(
    # the model's parameters, and its k and c as MODEL.md defines them from μkn, μcn, ζ
    lambda kn, cn, zeta, clamp: (
        through_numba(M.make_params)(1.0, zeta, 0.5, kn, cn, clamp),
        kn / (1 - kn),
        2 * zeta * cn / (1 - cn),
    ),
    st.floats(0.01, 0.999),
    st.floats(0.01, 0.999),
    st.floats(0.0, 2.0),
    st.booleans(),
)


@given(params, st.floats(-2, 2), st.floats(-50, 50))
@settings(max_examples=300, deadline=None)
def test_contact_force_laws(model, eps, deps):
    p, k, c = model
    force = through_numba(M.contact_force)(eps, deps, p)
    if eps <= 0:
        assert force == 0.0  # no force while separated
    elif p.clamp:
        assert force >= 0.0  # contact cannot pull
        assert force == pytest.approx(max(0.0, k * eps**1.5 * (1 + c * deps)))
    else:
        assert force == pytest.approx(k * eps**1.5 * (1 + c * deps))


@pytest.mark.parametrize("contact", [M.FREE, M.PUSH])
@pytest.mark.parametrize("phase", range(4))
def test_variational_part_is_the_jacobian_of_the_field(contact, phase):
    p = through_numba(M.make_params)(2.0, 0.2, 0.5, 0.9, 0.8, True)
    mode = np.array([phase, contact])
    t = 0.5 * (M.PHASE_BOUNDS[phase] + M.PHASE_BOUNDS[phase + 1]) / p.omega
    yc = through_numba(M.cam)(p.omega * t, phase, p.cam)[0]
    x = np.array([yc - 0.05, 0.1, 1.0, 0.0, 0.0, 1.0])  # ε = 0.05 > 0
    dx = np.zeros(6)
    through_numba(M.rhs)(t, x, p, mode, dx)
    jac = np.zeros((2, 2))
    for j in range(2):
        for sign in (1, -1):
            xp = x[:2].copy()
            xp[j] += sign * 1e-7
            out = np.zeros(2)
            through_numba(M.rhs)(t, xp, p, mode, out)
            jac[:, j] += sign * out / 2e-7
    # Φ = I, so dΦ/dt = A: rows (dΦ00, dΦ01), (dΦ10, dΦ11)
    np.testing.assert_allclose(dx[2:].reshape(2, 2), jac, rtol=1e-6, atol=1e-7)


def test_event_functions_are_positive_inside_their_mode():
    p = through_numba(M.make_params)(1.0, 0.2, 0.5, 0.8, 0.8, True)
    g, dg, f = np.zeros(2), np.zeros(2), np.zeros(2)
    mode = np.array([M.FAR_DWELL, M.FREE])
    assert through_numba(M.events)(2.0, np.array([1.2, 0.0]), f, p, mode, g, dg) == 1 and g[0] > 0
    mode[1] = M.PUSH
    assert through_numba(M.events)(2.0, np.array([0.9, 0.0]), f, p, mode, g, dg) == 2
    assert g[0] > 0 and g[1] > 0
    assert through_numba(M.contact_mode)(0.1, -10.0, p) == M.SLACK  # 1 + c ε' < 0
    assert through_numba(M.mode_after_event)(M.PUSH, 0) == M.FREE and through_numba(
        M.is_detachment
    )(M.SLACK, 0)
    assert (
        not through_numba(M.is_detachment)(M.FREE, 0)
        and through_numba(M.mode_after_event)(M.FREE, 0) == M.PUSH
    )


def test_hot_functions_refuse_python_callers():
    # compiled without a CPython wrapper (campar.core.jit): a call from Python must raise,
    # not jump through numba's null entry pointer
    with pytest.raises(TypeError, match="compiled callers only"):
        M.cam(0.1, 0, PAPER_CAM)
    assert through_numba(M.cam)(0.0, M.RISE, PAPER_CAM)[0] == 0.0
