"""The dense-output search's probe (extrema.dense_kinematics) gives, bit for bit, what
model.acceleration and model.kinematics give at the dense output's state: it repeats their
arithmetic in one body (one cam evaluation), so a change to either must reach it too."""

import numpy as np
import pytest
from support.jit import cached_njit

from campar.core import model
from campar.core.cam import phased_cam
from campar.core.codes import OK
from campar.core.contact import contact_law
from campar.core.extrema import dense_kinematics
from campar.core.integrator import SolverOptions, advance, make_work
from campar.core.model import (
    FALL,
    FREE,
    LAW_CAM_LITERAL,
    LAW_CLAMP,
    PAPER_LAW,
    PUSH,
    RISE,
    Law,
    make_params,
)
from campar.core.stages import DOP853, dense_eval, method_tag, prepare_dense

LAWS = {
    "paper": PAPER_LAW,
    "cycloidal-lankarani-literal": Law(
        np.int64(LAW_CLAMP | LAW_CAM_LITERAL),
        phased_cam("cycloidal", "cycloidal"),
        contact_law("lankarani-nikravesh", 1.5),
    ),
}
THETAS = (0.0, 0.137, 0.5, 0.81, 1.0)


@cached_njit
def one_step(t, t_end, y, p, mode, opt, w):
    f = np.zeros(y.shape[0])
    model.rhs(t, y, p, mode, f)
    return advance(model.rhs, model.events, model.event_curvature, t, t_end, y, f, p, mode, opt, w)


@cached_njit
def cam_at(theta, phase, p):
    return model.cam(theta, phase, p.cam)


@cached_njit
def probe(method, t0, w, h, theta, p, mode, want_force):
    prepare_dense(model.rhs, method, t0, w.y_old[:2], h, p, mode, w)
    return dense_kinematics(model.rhs, method, w, t0, h, theta, p, mode, want_force)


@cached_njit
def reference(method, t, w, h, theta, p, mode):
    """model.acceleration, then model.kinematics, at the dense output's state."""
    dense_eval(method, w, w.y_old, w.y_new, h, theta, 2, w.y_stage)
    y = w.y_stage[0]
    v = w.y_stage[1]
    acc, _, _ = model.acceleration(t, y, v, p, mode)
    return model.kinematics(t, y, v, acc, p, mode)


@pytest.mark.parametrize("name", list(LAWS))
@pytest.mark.parametrize("phase, contact", [(RISE, PUSH), (FALL, FREE)])
def test_the_probe_is_the_models_kinematics(name, phase, contact):
    omega = 2.0
    p = make_params(omega, 0.2, 0.5, 0.8, 0.8, LAWS[name])
    bounds = p.cam.bounds
    t0 = (0.7 * bounds[phase] + 0.3 * bounds[phase + 1]) / omega
    yc, dyc, _ = cam_at(omega * t0, phase, p)
    # in contact: pressed 1e-3 into the cam at its speed; in flight: 0.05 above it
    y = np.array([yc - 1e-3, p.vcam * dyc] if contact == PUSH else [yc + 0.05, 0.0])
    mode = np.array([phase, contact], dtype=np.int64)
    opt = SolverOptions(method_tag(DOP853), 1e-7, 1e-10, 0.0, 1e-11, 1e-10, 2)
    w = make_work(2, 2, 0.05)
    status, t1, _ = one_step(t0, bounds[phase + 1] / omega, y, p, mode, opt, w)
    assert status == OK and t1 > t0
    h = t1 - t0
    pushed = 0
    for theta in THETAS:
        got = probe(opt.method, t0, w, h, theta, p, mode, True)
        want = reference(opt.method, t0 + theta * h, w, h, theta, p, mode)
        assert got == want  # every component, bit for bit
        eps_only = probe(opt.method, t0, w, h, theta, p, mode, False)
        assert eps_only[:3] == want[:3]
        pushed += want[3] > 0.0
    assert pushed == (len(THETAS) if contact == PUSH else 0)  # the force law was exercised
