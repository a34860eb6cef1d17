"""Continuation along ω and the early verdicts, against independent runs.

Warm starts (previous cell, linear or quadratic extrapolation through the
previous cells' cycles) must not change a label, only the cost; the early
chaos and quasi-periodic verdicts must agree with long runs of the same cell,
one of them by SciPy.
"""

import numpy as np
import pytest

from campar import simulate_point
from campar.bench.common import Cell
from campar.bench.scipy_peer import scipy_cell
from campar.job import Job
from campar.plan import plan_tiles
from campar.status import Flag, Kind
from campar.tile import run_tile


def chain(extrapolate: int):
    """One continuation chain along ω from 3 to 1 at the base parameters (μcn 0.8)."""
    job = Job.from_dict({
        "name": "chain",
        "sweep": {"omega": {"from": 3.0, "to": 1.0, "points": 81},
                  "mu_cn": {"from": 0.8, "to": 0.8, "points": 1}},
        "fixed": {"zeta": 0.2, "mu_kn": 0.8, "f0": 0.5},
        "transient": {"extrapolate": extrapolate},
        "outputs": ["label", "dc", "lyapunov"],
    })  # fmt: skip
    (tile,) = plan_tiles(job)
    return job, {name: values[0] for name, values in run_tile(job, tile).items()}


@pytest.fixture(scope="module")
def chains():
    return {order: chain(order) for order in (0, 1, 2)}


def test_warm_start_order_changes_no_label_only_the_cost(chains):
    plain, linear, quadratic = (chains[order][1] for order in (0, 1, 2))
    assert (plain["kind"] == Kind.PERIODIC).all()
    for other in (linear, quadratic):
        np.testing.assert_array_equal(other["n"], plain["n"])
        np.testing.assert_array_equal(other["p"], plain["p"])
        np.testing.assert_allclose(other["dc"], plain["dc"], atol=1e-6)
    extrapolated = [(c["flags"] & Flag.WARM_EXTRAPOLATED) != 0 for c in (plain, linear, quadratic)]
    assert not extrapolated[0].any()
    # extrapolated wherever the last fixed points are close (not across the 1-1/1-2 jump)
    assert extrapolated[1].mean() > 0.6 and (extrapolated[2] == extrapolated[1]).all()
    # each order of extrapolation lands closer to the next cycle: fewer revolutions
    revolutions = [c["revolutions"].sum() for c in (plain, linear, quadratic)]
    assert revolutions[2] < revolutions[1] < revolutions[0], revolutions


def test_chain_agrees_with_every_cell_computed_cold_by_the_papers_recipe(chains):
    job, warm = chains[2]
    for k in range(0, len(job.omega), 8):
        omega = float(job.omega[k])
        cold = simulate_point(omega, transient="fixed", revolutions=500)
        assert cold.label == f"{warm['n'][k]}-{warm['p'][k]}", omega
        assert abs(cold.dc - warm["dc"][k]) < 1e-6, omega


CHAOS = Cell("chaos", 4.5, mu_cn=0.97)
QUASIPERIODIC = Cell("QP", 3.45213, mu_cn=0.529474)


def test_early_chaos_verdict_agrees_with_a_long_scipy_run():
    early = simulate_point(CHAOS.omega, lyapunov=True, **CHAOS.parameters)
    assert early.label == "chaos"
    assert 64 <= early.revolutions < 150  # the verdict came at chaos_after, not at the budget
    assert early.lyapunov * (2 * np.pi / CHAOS.omega) > 0.05  # per revolution
    # SciPy DOP853 from the same start: after 300 revolutions still no period ≤ 32
    late = scipy_cell(CHAOS.scipy_model(), (0.0, 0.0), 300, 64)
    assert late.n == 0


def test_quasiperiodic_verdict_agrees_with_a_long_run():
    early = simulate_point(QUASIPERIODIC.omega, lyapunov=True, **QUASIPERIODIC.parameters)
    assert early.label == "QP"
    assert 150 <= early.revolutions < 200  # the verdict came at quasiperiodic_after
    late = simulate_point(
        QUASIPERIODIC.omega, transient="fixed", revolutions=3000, lyapunov=True,
        **QUASIPERIODIC.parameters,
    )  # fmt: skip
    assert late.label == "QP"
    # still no contraction after 3000 revolutions (|λ| per revolution ≪ lyap_tol); the
    # cell carries the slow flag: an invariant circle or a cycle with |multiplier| ≈ 1
    assert abs(late.lyapunov * 2 * np.pi / QUASIPERIODIC.omega) < 2e-3


SLOW_CYCLE = Cell("slow 1-1", 3.257293, mu_cn=0.504912)


def test_a_quasiperiodic_verdict_near_a_slow_stable_cycle_is_flagged_slow():
    early = simulate_point(SLOW_CYCLE.omega, **SLOW_CYCLE.parameters)
    assert early.label == "QP" and "slow" in early.flags
    late = simulate_point(SLOW_CYCLE.omega, transient="fixed", revolutions=3000,
                          **SLOW_CYCLE.parameters)  # fmt: skip
    assert late.n > 0  # the flag was right: a cycle the 150-revolution verdict did not reach
    chaos = simulate_point(CHAOS.omega, **CHAOS.parameters)
    assert "slow" not in chaos.flags
