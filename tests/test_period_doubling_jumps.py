"""Newton jumps just past a period doubling (campar.core.analysis.assess_revolution): the
motion alternates about the unstable 1-cycle it left, the Jacobian along its path is
stable and the period-1 estimates agree on that unstable cycle; a jump is taken only for a
period at which the motion evidently repeats; and a budget that ends there without a
verdict ends with Newton's method on P² (transient.settle_at_budget). Checked on a
synthetic history and on cells of the (ω, μkn) plane against the independent SciPy
model."""

import numpy as np
import pytest

from campar import simulate_point
from campar.api import job_of
from campar.bench import scipy_shooting
from campar.core import analysis as A
from campar.core.codes import Flag
from campar.core.jit import through_numba
from campar.sweep.replay import replay_cell
from campar.views.dataset import cell_labels

# A cell of jobs/mu_kn_tongue.yaml on 600 × 600 cells (row 510, column 512) and the final
# state of the cell before it along its chain, a 2-2 cycle's: from there the agreeing
# period-1 estimates pointed at the unstable 1-cycle, and the transient took 967
# revolutions where plain iteration takes 62.
PAST_DOUBLING = {"omega": 2.3631051752921537, "mu_kn": 0.8563439065108513, "mu_cn": 0.8}
HAND_OFF = (0.13503923831453424, -1.0972018876786755)


def test_agreeing_estimates_of_a_period_the_motion_does_not_repeat_are_not_jumped_to():
    # a 2-cycle a, b (the motion shrinking onto it) along the flip direction of a
    # one-revolution Jacobian of −0.99: from either point the period-1 Newton estimate lies
    # about halfway between them, consecutive estimates agree and the Jacobian along the
    # path is stable, but the motion repeats every 2 revolutions thousands of times closer
    # than every 1
    a, b = np.array([0.14, -1.10]), np.array([0.30, -1.10])
    xs = np.array([(a, b)[k % 2] + 1e-4 * 0.9**k for k in range(8)])
    flip = np.diag([-0.99, 0.3])
    jac = np.tile(flip.ravel(), (7, 1))
    estimate = through_numba(A.newton_fixed_point)(*xs[3], *xs[2], flip.ravel())
    assert abs(estimate[0] - 0.5 * (a[0] + b[0])) < 0.01 <= A.TRUSTED_JUMP_MAX - estimate[2]
    est = np.full((32, 32, 3), -1.0)
    assess = through_numba(A.assess_revolution)
    for k in range(1, 8):
        period, jump, z0, z1 = assess(xs, jac, est, k, 0, 32, 1e-9, 1e-6, 1e-3, 0.02, 0.1)
        assert jump != 1
        if jump:  # a period-2 jump lands on the cycle the motion repeats
            assert min(np.abs([z0, z1] - a).max(), np.abs([z0, z1] - b).max()) < 1e-3


def scipy_cycles(parameters: dict, x):
    """SciPy's cycles near x (campar.bench.scipy_shooting): the 1-cycle's multipliers,
    the 2-cycle's two section points and its multipliers."""
    _, one = scipy_shooting.fixed_point(parameters, x, 1)
    two, m2 = scipy_shooting.fixed_point(parameters, x, 2)
    points = (two, scipy_shooting.section_map(parameters, two, 1))
    return scipy_shooting.multipliers(one), points, scipy_shooting.multipliers(m2)


def distance(points, x) -> float:
    """The ∞-norm distance from x to the nearest of ``points``."""
    return min(np.abs(np.asarray(x) - point).max() for point in points)


def test_a_cell_past_a_period_doubling_converges_on_its_two_cycle_at_once():
    cell = simulate_point(state=HAND_OFF, **PAST_DOUBLING)
    assert cell.label == "2-2"
    assert cell.revolutions <= 20
    one_multipliers, two, two_multipliers = scipy_cycles(PAST_DOUBLING, HAND_OFF)
    assert min(one_multipliers.real) < -1.0  # the 1-cycle is past its period doubling
    assert max(abs(two_multipliers)) < 1.0  # and the 2-cycle is the attractor
    assert distance(two, cell.state) < 1e-6


# Cells of jobs/mu_kn_tongue.yaml on 600 × 600 cells next to the 2-2 tongue's period
# doubling whose budget ended without a verdict (quasi-periodic, unconverged): plain
# Newton jumps from the path's Jacobian crept for hundreds of revolutions there. (row,
# column): the tolerance on the final state against SciPy's 2-cycle (settled: within
# analysis.SETTLED_DISTANCE; converged: to the integrator's accuracy).
AT_THE_BUDGET = {(445, 347): 1e-4, (581, 510): 1e-6}


@pytest.mark.parametrize("cell", AT_THE_BUDGET)
def test_a_budget_that_ends_next_to_a_period_doubling_ends_on_its_two_cycle(cell):
    job = job_of("jobs/mu_kn_tongue.yaml", {f"sweep.{a}.points": 600 for a in ("omega", "mu_kn")})
    row, col = cell
    values = replay_cell(job, row, col)
    assert cell_labels(values["kind"], values["n"], values["p"]) == "2-2"
    settled = bool(values["flags"] & Flag.SETTLED)
    assert settled == (AT_THE_BUDGET[cell] > 1e-6)
    parameters = {"omega": float(job.first_values[col]), "mu_kn": float(job.second_values[row])}
    one_multipliers, two, two_multipliers = scipy_cycles(parameters, values["state"])
    assert min(one_multipliers.real) < -1.0  # the 1-cycle is past its period doubling
    assert max(abs(two_multipliers)) < 1.0
    assert distance(two, values["state"]) < AT_THE_BUDGET[cell]


def test_the_dominant_direction_is_numpys_eigenvector():
    rng = np.random.default_rng(7)
    direction = through_numba(A.real_dominant_direction)
    for _ in range(200):
        m = rng.normal(size=(2, 2))
        values, vectors = np.linalg.eig(m)
        lam, v0, v1 = direction(tuple(m.ravel()))
        if np.iscomplexobj(values) and values.imag.any():
            assert np.isnan(lam)
            continue
        i = int(np.argmax(np.abs(values)))
        assert lam == pytest.approx(values[i].real, rel=1e-12, abs=1e-12)
        assert abs(abs(np.dot([v0, v1], vectors[:, i].real)) - 1.0) < 1e-9


# Cells of jobs/design_f0_modified-trapezoid.yaml on 600 × 600 cells whose budget ended
# quasi-periodic: Newton on P² from the motion converged to the 1-cycle, past its period
# doubling (multiplier −1.0013, −1.0014), and a start off it along its flip direction
# reaches the stable 2-cycle (P² multiplier 0.995, 0.994). (row, column).
OFF_THE_FLIP = [(298, 19), (300, 14)]


@pytest.mark.slow  # the modified trapezoid's kernel
@pytest.mark.parametrize("cell", OFF_THE_FLIP)
def test_a_budget_that_ends_on_the_unstable_one_cycle_starts_off_it_to_the_two_cycle(cell):
    job = job_of(
        "jobs/design_f0_modified-trapezoid.yaml",
        {f"sweep.{a}.points": 600 for a in ("omega", "f0")},
    )
    row, col = cell
    values = replay_cell(job, row, col)
    assert cell_labels(values["kind"], values["n"], values["p"]) == "2-2"
    parameters = {
        "omega": float(job.first_values[col]),
        "f0": float(job.second_values[row]),
        "rise": "modified-trapezoid",
        "fall": "modified-trapezoid",
    }
    one_multipliers, two, two_multipliers = scipy_cycles(parameters, values["state"])
    assert min(one_multipliers.real) < -1.0
    assert max(abs(two_multipliers)) < 1.0
    assert distance(two, values["state"]) < 1e-6


def test_a_cycle_too_weakly_attracting_for_the_jobs_tolerance_is_settled_at_a_tighter_one():
    # (77, 507) of jobs/mu_kn_tongue.yaml at 600²: SciPy's 1-cycle −1.0000021, its 2-cycle
    # 0.9999917; at the job's tolerance DP² was anywhere in 0.9992 … 1.00017 (QP)
    job = job_of("jobs/mu_kn_tongue.yaml", {f"sweep.{a}.points": 600 for a in ("omega", "mu_kn")})
    values = replay_cell(job, 77, 507)
    assert cell_labels(values["kind"], values["n"], values["p"]) == "2-2"
    parameters = {"omega": float(job.first_values[507]), "mu_kn": float(job.second_values[77])}
    one_multipliers, two, two_multipliers = scipy_cycles(parameters, values["state"])
    assert min(one_multipliers.real) < -1.0
    assert max(abs(two_multipliers)) < 1.0
    assert distance(two, values["state"]) < 1e-6
