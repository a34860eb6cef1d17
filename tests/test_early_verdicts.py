"""The transient's early chaos verdict (campar.core.transient.nonperiodic_verdict): its
confidence bound against SciPy's statistics, a chaotic cell declared chaotic early against
the Lyapunov exponent of the independent SciPy model, and cycles that are never."""

import math
from statistics import NormalDist

import numpy as np
import pytest
from scipy import stats

from campar import simulate_point
from campar.bench.common import Cell
from campar.bench.scipy_model import integrate
from campar.bench.scipy_peer import scipy_cell
from campar.core import analysis
from campar.core.analysis import BATCH_REVOLUTIONS, MIN_BATCHES, N_REV_STATS, REV_LOG_STRETCH
from campar.core.jit import through_numba
from campar.model.sections import DEFAULT_CLASSIFY

CHAOS = Cell("chaos", 4.5, mu_cn=0.97)  # benchmarks/RESULTS.md, precision
SLOW_CYCLE = Cell("slow 2-2", 3.45213, mu_cn=0.529474)  # a 2-cycle, multiplier 0.998
# the early verdict: from revolution 18 (16 revolutions read after the first 2), clear of
# Newton jumps and of stable cycles in sight (within 0.2) for 16 revolutions
EARLY = {"chaos_after": 18, "chaos_clear": 16, "chaos_sight": 0.2}

exponent_bounds = through_numba(analysis.exponent_bounds)
student_quantile = through_numba(analysis.student_quantile)


def test_student_quantile_is_scipys_within_its_stated_error():
    for confidence, low in ((0.9, 0.999), (0.99, 0.995), (0.999, 0.97)):
        z = NormalDist().inv_cdf(confidence)
        for dof in range(MIN_BATCHES - 1, 60):
            exact = stats.t.ppf(confidence, dof)
            assert low * exact <= student_quantile(z, dof) <= 1.0001 * exact


def test_exponent_bounds_are_the_batch_means_interval():
    rng = np.random.default_rng(7)
    revs = np.zeros((40, N_REV_STATS))
    revs[:, REV_LOG_STRETCH] = rng.normal(0.3, 0.5, 40)
    first, count, confidence = 5, 30, 0.95
    mean, half = exponent_bounds(revs, first, count, NormalDist().inv_cdf(confidence))
    stretch = revs[first : first + count, REV_LOG_STRETCH]
    batches = count // BATCH_REVOLUTIONS
    means = stretch[count - batches * BATCH_REVOLUTIONS :].reshape(batches, -1).mean(axis=1)
    expected = stats.t.ppf(confidence, batches - 1) * stats.sem(means)
    assert mean == pytest.approx(stretch.mean(), rel=1e-12)
    assert half == pytest.approx(expected, rel=2e-3)
    # fewer batches than MIN_BATCHES: no bound at all
    short = (MIN_BATCHES * BATCH_REVOLUTIONS) - 1
    assert exponent_bounds(revs, first, short, 2.0)[1] == math.inf


def scipy_exponent(cell: Cell, revolutions: int, skip: int = 8, d0: float = 1e-7):
    """Largest Lyapunov exponent per revolution of the SciPy model from rest (two nearby
    trajectories renormalised every revolution, Benettin's method) and the standard error
    of its mean from 8-revolution batch means."""
    model = cell.scipy_model()
    x, _, _ = integrate(model, (0.0, 0.0), skip, rtol=1e-9, atol=1e-11)
    y = x + np.array([d0, 0.0])
    logs = []
    for _ in range(revolutions):
        x, _, _ = integrate(model, x, 1, rtol=1e-9, atol=1e-11)
        y, _, _ = integrate(model, y, 1, rtol=1e-9, atol=1e-11)
        d = float(np.linalg.norm(y - x))
        logs.append(math.log(d / d0))
        y = x + (y - x) * (d0 / d)
    means = np.reshape(logs, (-1, 8)).mean(axis=1)
    return float(np.mean(logs)), float(stats.sem(means))


@pytest.mark.slow  # 2 × 128 SciPy revolutions, ~10 s
def test_a_chaotic_cell_is_declared_chaotic_before_32_revolutions():
    exponent, error = scipy_exponent(CHAOS, 128)
    assert exponent - 3 * error > DEFAULT_CLASSIFY.lyap_tol  # SciPy: surely positive
    found = simulate_point(CHAOS.omega, lyapunov=True, **EARLY, **CHAOS.parameters)
    assert found.label == "chaos" and found.revolutions < 32
    assert found.lyapunov * 2 * math.pi / CHAOS.omega > DEFAULT_CLASSIFY.lyap_tol


def test_a_slowly_attracting_cycle_is_not_declared_chaotic_early():
    found = simulate_point(SLOW_CYCLE.omega, **EARLY, **SLOW_CYCLE.parameters)
    assert found.label == "2-2"
    # SciPy DOP853 from campar's section point: a genuine 2-cycle
    check = scipy_cell(SLOW_CYCLE.scipy_model(), tuple(found.sections[-1]), 0, 4, rtol=1e-10)
    assert check.label == "2-2"


# a start from which the motion is chaotic for tens of revolutions, then settles on a
# 5-cycle: a cell of jobs/mu_cn.yaml whose warm start came from a chaotic neighbour
SETTLING = Cell("chaotic transient", 5.235639097744361, mu_cn=0.9224310776942355)
SETTLING_START = (0.5073835741912888, -0.39669707808439947)


@pytest.mark.slow  # 420 SciPy revolutions, ~8 s
def test_a_chaotic_transient_that_settles_is_its_cycle_by_default():
    found = simulate_point(SETTLING.omega, state=SETTLING_START, **SETTLING.parameters)
    assert found.label == "5-4" and found.revolutions > 20  # past the early verdict's time
    check = scipy_cell(SETTLING.scipy_model(), SETTLING_START, 400, 20, rtol=1e-9)
    assert check.label == found.label
