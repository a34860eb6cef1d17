"""Continuation along ω and the early verdicts, against independent runs.

Warm starts (previous cell, linear or quadratic extrapolation through the
previous cells' cycles) must not change a label, only the cost; the
non-periodic verdicts must agree with long runs of the same cell, and a cycle
reached by a jump on agreeing estimates must be one SciPy confirms.
"""

import numpy as np
import pytest

from campar import simulate_point
from campar.bench.common import Cell
from campar.bench.scipy_peer import scipy_cell
from campar.core.codes import Flag, Kind
from campar.sweep.job import Job
from campar.sweep.plan import plan_tiles
from campar.sweep.tile import run_tile


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
# a cell of the full (ω, μcn) plane started on its invariant circle (its chain's state)
QUASIPERIODIC = Cell("QP", 3.3472180451127818, mu_cn=0.831578947368421)
ON_THE_CIRCLE = {"y0": 0.3480952510082911, "v0": -0.6486579563160504}


def test_early_chaos_verdict_agrees_with_a_long_scipy_run():
    early = simulate_point(CHAOS.omega, lyapunov=True, **CHAOS.parameters)
    assert early.label == "chaos"
    assert 64 <= early.revolutions < 150  # the verdict came at chaos_after, not at the budget
    assert early.lyapunov * (2 * np.pi / CHAOS.omega) > 0.05  # per revolution
    # SciPy DOP853 from the same start: after 300 revolutions still no period ≤ 32
    late = scipy_cell(CHAOS.scipy_model(), (0.0, 0.0), 300, 64)
    assert late.n == 0


def one_cell(cell: Cell, y0: float, v0: float, **transient) -> dict:
    job = Job.from_dict({
        "name": "one_cell",
        "sweep": {"omega": {"from": cell.omega, "to": cell.omega, "points": 1},
                  "mu_cn": {"from": cell.mu_cn, "to": cell.mu_cn, "points": 1}},
        "fixed": {"zeta": cell.zeta, "mu_kn": cell.mu_kn, "f0": cell.f0},
        "initial": {"y": y0, "v": v0},
        "transient": transient,
        "outputs": ["label", "lyapunov"],
    })  # fmt: skip
    (tile,) = plan_tiles(job)
    return {name: values[0, 0] for name, values in run_tile(job, tile).items()}


def test_quasiperiodic_verdict_agrees_with_a_long_run():
    at_budget = simulate_point(QUASIPERIODIC.omega, lyapunov=True, **ON_THE_CIRCLE,
                               **QUASIPERIODIC.parameters)  # fmt: skip
    assert at_budget.label == "QP" and at_budget.revolutions == 500
    assert "slow" not in at_budget.flags  # no stable cycle nearby
    # the optional early verdict (quasiperiodic_after) says the same at revolution 150
    early = one_cell(QUASIPERIODIC, **ON_THE_CIRCLE, quasiperiodic_after=150)
    assert early["kind"] == Kind.QUASIPERIODIC and 150 <= early["revolutions"] < 200
    late = simulate_point(
        QUASIPERIODIC.omega, transient="fixed", revolutions=3000, lyapunov=True,
        **ON_THE_CIRCLE, **QUASIPERIODIC.parameters,
    )  # fmt: skip
    assert late.label == "QP"
    # no contraction after 3000 revolutions: |λ| per revolution ≪ lyap_tol
    assert abs(late.lyapunov * 2 * np.pi / QUASIPERIODIC.omega) < 5e-3


SLOW_CYCLE = Cell("slow 2-2", 3.45213, mu_cn=0.529474)


def test_a_slowly_attracting_cycle_is_found_by_jumps_on_agreeing_estimates():
    found = simulate_point(SLOW_CYCLE.omega, multipliers=True, **SLOW_CYCLE.parameters)
    assert found.label == "2-2" and found.revolutions < 60
    assert "slow" in found.flags and 0.99 < abs(found.multipliers[0]) < 1.0
    # without them the transient is nowhere near the cycle after 150 revolutions
    plain = one_cell(SLOW_CYCLE, 0.0, 0.0, jump_agree=0.0, quasiperiodic_after=150)
    assert plain["kind"] == Kind.QUASIPERIODIC
    # SciPy DOP853 from campar's section point: a genuine 2-cycle, same duty cycle
    check = scipy_cell(SLOW_CYCLE.scipy_model(), tuple(found.sections[-1]), 0, 4, rtol=1e-10)
    assert check.label == "2-2" and abs(check.dc - found.dc) < 1e-6
    # and 3000 plain revolutions from rest are still on the way to it (multiplier 0.998)
    late = simulate_point(SLOW_CYCLE.omega, transient="fixed", revolutions=3000,
                          **SLOW_CYCLE.parameters)  # fmt: skip
    assert np.abs(found.sections - np.array(late.state)).max(axis=1).min() < 0.01
    chaos = simulate_point(CHAOS.omega, **CHAOS.parameters)
    assert "slow" not in chaos.flags
