"""The compiled chain (``run_chain``) against SciPy, closed forms and itself.

Chains are run directly, with the settings and buffers campar.sweep.tile builds
from a job; parameters the job schema refuses (a negative preload, a NaN) reach
the kernel this way and put it where the answer is known.
"""

import math

import numpy as np
import pytest

from campar.bench.scipy_model import Model
from campar.bench.scipy_peer import scipy_cell
from campar.core.codes import Flag, Kind, Status
from campar.core.kernel import CellOutputs, run_chain
from campar.sweep.job import OUTPUT_NAMES, Job
from campar.sweep.tile import allocate_outputs, cell_settings, solver_options

# ω decreasing at μcn = 0.9 in steps of 0.1: chaos, 14-12, 8-6, then 2-1, 2-2, 1-1,
# 1-2, 1-1 and 1-0 cells, some from extrapolated starts.
OMEGA = np.linspace(4.8, 0.6, 43)
MU_CN = 0.9


def run(
    omega,
    *,
    f0=0.5,
    mu_kn=0.8,
    mu_cn=0.8,
    zeta=0.2,
    clamp=True,
    x_init=(0.0, 0.0),
    outputs=OUTPUT_NAMES,
    **sections,
) -> CellOutputs:
    """run_chain over the cells ``omega`` with a job's settings (``sections``: its
    transient, classify, … mappings); the other parameters are numbers or per-cell
    arrays. Argument types as run_tile's, so the cached kernel serves."""
    job = Job.from_dict(
        {
            "name": "kernel",
            "sweep": {
                "omega": {"from": 1.0, "to": 1.0, "points": 1},
                "mu_cn": {"from": 0.8, "to": 0.8, "points": 1},
            },
            "outputs": list(outputs),
            **sections,
        }
    )
    settings = cell_settings(job)
    omega = np.array(omega, dtype=float)

    def per_cell(value):
        return np.broadcast_to(np.asarray(value, dtype=float), omega.shape).copy()

    out = allocate_outputs(omega.shape[0], settings.output_bits, job.n_sections)
    run_chain(
        omega,
        per_cell(zeta),
        per_cell(f0),
        per_cell(mu_kn),
        per_cell(mu_cn),
        clamp,
        np.array(x_init, dtype=float),
        solver_options(job),
        settings,
        out,
    )
    return out


def test_every_periodic_cell_of_a_chain_is_a_cycle_scipy_confirms():
    out = run(OMEGA, mu_cn=MU_CN)
    periodic = np.flatnonzero(out.kind == Kind.PERIODIC)
    assert {f"{out.n[i]}-{out.p[i]}" for i in periodic} >= {"2-1", "2-2", "1-1", "1-2", "1-0"}
    # cells reached from extrapolated starts and by Newton jumps are among them
    assert (out.flags[periodic] & Flag.WARM_EXTRAPOLATED).any()
    assert (out.flags[periodic] & Flag.NEWTON).any()
    for i in periodic:
        n = int(out.n[i])
        state = out.state[i]
        # SciPy DOP853, n revolutions from the final state (its p and dc over them)
        peer = scipy_cell(Model(OMEGA[i], mu_cn=MU_CN), tuple(state), 0, n, rtol=1e-10)
        assert peer.p == out.p[i], OMEGA[i]
        assert abs(peer.dc - out.dc[i]) < 1e-7 * n, OMEGA[i]
        # back on the start after n revolutions and not before; campar (rtol 1e-8) is
        # off the exact orbit by ≤ 20 rtol a revolution
        tol = 4e-7 * n
        distance = np.abs(peer.sections - state).max(axis=1)
        assert distance[n] < tol and (distance[1:n] > 1e-6).all(), OMEGA[i]
        # the stored σn points are the cycle's n section points
        for point in peer.sections[:n]:
            assert np.abs(out.sections[i, :n] - point).max(axis=1).min() < tol, OMEGA[i]
        assert np.isnan(out.sections[i, n:]).all()


@pytest.mark.parametrize("transient", ["converged", "fixed"])
def test_outputs_not_asked_for_are_not_computed_and_change_nothing(transient):
    settings = {"transient": {"mode": transient, "max_revolutions": 100}}
    full = run(OMEGA, mu_cn=MU_CN, **settings)
    bare = run(OMEGA, mu_cn=MU_CN, outputs=["label"], **settings)
    assert (full.status == Status.OK).all()
    for name in ("n", "p", "kind", "status", "state", "revolutions", "steps"):
        np.testing.assert_array_equal(getattr(bare, name), getattr(full, name), err_msg=name)
    # only the grazing flag needs ε along the orbit, which a label-only chain skips
    keep = ~int(Flag.GRAZING)
    np.testing.assert_array_equal(bare.flags & keep, full.flags & keep)
    assert not (bare.flags & Flag.GRAZING).any()
    for name in ("dc", "eps_min", "eps_max", "pn_max"):
        assert np.isnan(getattr(bare, name)).all() and np.isfinite(getattr(full, name)).all()
    for name in ("lyapunov", "multipliers", "sections"):
        assert getattr(bare, name).shape[0] == 0 and getattr(full, name).shape[0] == len(OMEGA)


def test_a_failed_cell_leaves_nans_and_the_next_one_restarts_as_if_it_began_the_chain():
    # f0 = NaN: the middle cell's field cannot be integrated
    out = run([2.4, 2.0, 2.0], f0=[0.5, math.nan, 0.5])
    alone = run([2.0])
    assert out.status[0] == Status.OK and out.status[1] != Status.OK
    assert out.kind[1] == Kind.FAILED
    for name in (
        "dc",
        "eps_min",
        "eps_max",
        "pn_max",
        "state",
        "lyapunov",
        "multipliers",
        "sections",
    ):
        assert np.isnan(getattr(out, name)[1]).all(), name
    # from x_init with a fresh step size: bit for bit the cell computed on its own
    assert out.flags[2] == alone.flags[0] | Flag.RESTARTED
    for name in CellOutputs._fields:
        if name != "flags":
            np.testing.assert_array_equal(getattr(out, name)[2], getattr(alone, name)[0], name)


# f0 = −2 pulls the follower to rest at y = 2, above the cam's whole lift (0 … 1):
# free flight throughout, y'' + 2ζ y' + y = 2, a linear damped oscillator.
FREE_FLIGHT = dict(f0=-2.0, x_init=(2.5, 0.3))


@pytest.mark.parametrize("omega", [3.0, 1.0, 0.3])
def test_a_follower_held_off_the_cam_settles_at_the_closed_form_rest(omega):
    out = run([omega], **FREE_FLIGHT)
    assert out.kind[0] == Kind.PERIODIC and (out.n[0], out.p[0]) == (1, 0)
    np.testing.assert_allclose(out.state[0], [2.0, 0.0], rtol=0, atol=1e-7)
    assert out.dc[0] == pytest.approx(1.0, abs=1e-12)  # separated all the time
    # ε = yc − 2 runs between the cam's lowest and highest lift, less 2; no force
    assert out.eps_min[0] == pytest.approx(-2.0, abs=1e-7)
    assert out.eps_max[0] == pytest.approx(-1.0, abs=1e-7)
    assert out.pn_max[0] == 0.0


@pytest.mark.xfail(
    strict=True,
    reason="only (y, y') are error-controlled (n_err = 2): at rest their error estimate "
    "vanishes, steps grow to a whole cam phase and the variational part Φ loses accuracy",
)
def test_free_flight_multipliers_are_the_damped_oscillators():
    omega, zeta = 1.0, 0.2
    out = run([omega], **FREE_FLIGHT)
    # one revolution of x' = A x, A = [[0, 1], [−1, −2ζ]]: eigenvalues of exp(A T)
    exact = np.exp(2 * np.pi / omega * complex(-zeta, math.sqrt(1 - zeta**2)))
    got = sorted((complex(re, im) for re, im in out.multipliers[0]), key=lambda z: z.imag)
    np.testing.assert_allclose(got, [exact.conjugate(), exact], rtol=1e-6)
    assert out.lyapunov[0] == pytest.approx(-zeta, rel=1e-6)
