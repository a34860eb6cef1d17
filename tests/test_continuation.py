"""Continuation along ω and the early verdicts, against independent runs.

Warm starts (previous cell, linear, quadratic or cubic extrapolation through the
previous cells' cycles) must not change a label, only the cost; the chain's
cells are those SciPy finds from rest; the non-periodic verdicts must agree
with long SciPy runs of the same cell, and a cycle reached by a jump on
agreeing estimates must be one SciPy confirms.
"""

import numpy as np
import pytest
from support.jobs import plane_job, reference_case

from campar import simulate_point
from campar.bench import scipy_shooting
from campar.bench.common import Cell
from campar.bench.scipy_model import integrate
from campar.bench.scipy_peer import scipy_cell
from campar.continuation.orbit import find_cycle
from campar.core.codes import Flag, Kind
from campar.sweep.job import Job
from campar.sweep.plan import plan_tiles
from campar.sweep.tile import run_tile


def chain(extrapolate: int):
    """One continuation chain along ω from 3 to 1 at the base parameters (μcn 0.8)."""
    job = Job.from_dict(
        plane_job(
            "chain",
            (3.0, 1.0, 81),
            ("mu_cn", 0.8, 0.8, 1),
            fixed={"zeta": 0.2, "mu_kn": 0.8, "f0": 0.5},
            transient={"extrapolate": extrapolate},
            outputs=["label", "dc", "lyapunov"],
        )
    )
    (tile,) = plan_tiles(job)
    return job, {name: values[0] for name, values in run_tile(job, tile).items()}


@pytest.fixture(scope="module")
def chains():
    return {order: chain(order) for order in (0, 1, 2, 3)}


def test_warm_start_order_changes_no_label_only_the_cost(chains):
    plain, *extrapolating = (chains[order][1] for order in (0, 1, 2, 3))
    assert (plain["kind"] == Kind.PERIODIC).all()
    for other in extrapolating:
        np.testing.assert_array_equal(other["n"], plain["n"])
        np.testing.assert_array_equal(other["p"], plain["p"])
        np.testing.assert_allclose(other["dc"], plain["dc"], atol=1e-6)
    extrapolated = [(c["flags"] & Flag.WARM_EXTRAPOLATED) != 0 for c in (plain, *extrapolating)]
    assert not extrapolated[0].any()
    # extrapolated from the third cell on (two cycles of one period before it), by every order
    for order in (1, 2, 3):
        assert not extrapolated[order][:2].any() and extrapolated[order][2:].all(), order
    # each order of extrapolation lands closer to the next cycle: fewer revolutions
    revolutions = [c["revolutions"].sum() for c in (plain, *extrapolating)]
    assert revolutions[3] < revolutions[2] < revolutions[1] < revolutions[0], revolutions


# chain cells checked with SciPy: 1-1 at ω = 3 and 2, 1-2 at ω = 1.4, 1-1 at ω = 1
SCIPY_CELLS = (0, 40, 64, 80)


@pytest.mark.parametrize("k", SCIPY_CELLS)
def test_chain_cells_are_the_cycles_scipy_finds_from_rest(chains, k):
    """The warm-started chain lands on the cycle SciPy DOP853 reaches from rest (these
    cells are monostable): same n-p, duty cycle and section point."""
    job, warm = chains[3]
    omega = float(job.omega[k])
    cell = Cell("chain", omega, mu_cn=float(job.second_values[0]), **job.fixed)
    cold = scipy_cell(cell.scipy_model(), (0.0, 0.0), 60, 4, rtol=1e-10)
    assert cold.label == f"{warm['n'][k]}-{warm['p'][k]}", omega
    assert abs(cold.dc - warm["dc"][k]) < 1e-6, omega
    n = cold.n
    distance = np.abs(cold.sections[-n:] - warm["state"][k]).max(axis=1).min()
    assert distance < 1e-6, (omega, distance)


def test_chain_ends_on_the_reference_cell(chains):
    """The chain's last cell (ω = 1) is reference cell 102 (computed from rest)."""
    job, warm = chains[3]
    case = reference_case(102)
    assert case["clamp"] and job.model.tensile == "clamp"
    assert (float(job.omega[-1]), job.second_values[0]) == (case["omega"], case["mu_cn"])
    assert all(job.fixed[name] == case[name] for name in ("f0", "mu_kn", "zeta"))
    expected = case["expected"]
    assert f"{warm['n'][-1]}-{warm['p'][-1]}" == expected["label"]
    assert warm["dc"][-1] == pytest.approx(expected["DC"], abs=0.0025)


CHAOS = Cell("chaos", 4.5, mu_cn=0.97)
# A cell of the full (ω, μcn) plane, started where its chain left it: next to the period-1
# cycle, which is unstable with a multiplier just below −1, beside a stable 2-2 cycle.
ESCAPE = Cell("escape", 3.3472180451127818, mu_cn=0.831578947368421)
NEXT_TO_THE_1_CYCLE = {"y0": 0.3480952510082911, "v0": -0.6486579563160504}


@pytest.mark.slow  # a long transient near an unstable cycle
def test_the_slow_escape_from_an_unstable_cycle_is_not_read_as_a_torus():
    """The escape from a 1-cycle with multiplier μ ≈ −1.003 grows like |μ|^k: over a
    500-revolution window it looks like a torus (Lyapunov exponent ~0). The transient
    leaves the cycle along its unstable direction and settles on the 2-2 cycle, which an
    independent SciPy shooting confirms (stable, at campar's points), as it confirms the
    1-cycle's multiplier and that the orbit's slow growth is that multiplier's."""
    found = simulate_point(
        ESCAPE.omega,
        multipliers=True,
        y0=NEXT_TO_THE_1_CYCLE["y0"],
        v0=NEXT_TO_THE_1_CYCLE["v0"],
        **ESCAPE.parameters,
    )
    assert found.label == "2-2" and found.revolutions < 100
    assert "escaped" in found.flags
    parameters = {"omega": ESCAPE.omega, "mu_cn": ESCAPE.mu_cn}
    start = (NEXT_TO_THE_1_CYCLE["y0"], NEXT_TO_THE_1_CYCLE["v0"])
    one, m1 = scipy_shooting.fixed_point(parameters, start, 1)
    mu1 = scipy_shooting.multipliers(m1)[0]
    assert -1.01 < mu1.real < -1.0 and mu1.imag == 0.0  # a flip-unstable 1-cycle
    two, m2 = scipy_shooting.fixed_point(parameters, found.state, 2)
    # the map's cell reaches it to conv_tol / (1 − μ) ≈ 1e-6 (μ = 0.988); shooting to 1e-10
    assert np.abs(two - np.array(found.state)).max() < 1e-6
    shot = find_cycle(2, found.state, **parameters)
    assert shot.label == "2-2" and np.abs(two - np.array(shot.state)).max() < 1e-8
    assert np.abs(scipy_shooting.multipliers(m2)).max() < 1.0  # stable
    reference = scipy_shooting.multipliers(m2).real
    np.testing.assert_allclose(reference, [m.real for m in shot.multipliers], atol=1e-6)
    # the cell's, at its rtol 1e-7 and off the cycle by ~1e-6
    np.testing.assert_allclose(reference, [m.real for m in found.multipliers], atol=1e-3)
    # SciPy DOP853 from the same start, 300 revolutions: |x_k − x_{k−2}| (the distance
    # from a 2-cycle) grows at log|μ1| a revolution, the unstable 1-cycle's rate
    late = scipy_cell(ESCAPE.scipy_model(), start, 0, 300, rtol=1e-10)
    x = late.sections
    d2 = np.abs(x[2:] - x[:-2]).max(axis=1)
    growth = np.log(d2[-50:].mean() / d2[:50].mean()) / (len(d2) - 50)  # per revolution
    assert growth == pytest.approx(np.log(abs(mu1)), rel=0.25), (growth, mu1)


def test_a_budget_ending_on_a_slow_stable_cycle_is_that_cycle():
    """Just past a period doubling (μcn 0.8515, ω 2.3517) the 2-cycle's multiplier is
    0.998: from this start the transient's Newton jumps, from the Jacobian along a path
    that creeps towards it, and 500 revolutions close in on it by a factor 0.6 alone. The
    window's exponent is ~0, yet the motion sits on the stable 2-2 cycle that an
    independent SciPy shooting finds (rtol 1e-10); Newton's method on P² at the budget's
    end converges on it (within the 1e-4 the slow verdict asks: at rtol 1e-7 the kernel's
    cycle lies 2.5e-5 from SciPy's, 1 − μ dividing the integration's error), flagged
    slow."""
    parameters = {"omega": 2.351717171717172, "mu_cn": 0.8515151515151514}
    found = simulate_point(
        multipliers=True, y0=0.08519105224337234, v0=-1.0035574481119836, **parameters
    )
    assert found.label == "2-2" and 500 < found.revolutions <= 516
    assert "slow" in found.flags and "settled" not in found.flags
    two, m2 = scipy_shooting.fixed_point(parameters, found.state, 2)
    reference = scipy_shooting.multipliers(m2)
    assert 0.99 < np.abs(reference).max() < 1.0  # stable and slow
    assert np.abs(two - np.array(found.state)).max() < 1e-4
    np.testing.assert_allclose(
        sorted(reference.real), sorted(m.real for m in found.multipliers), atol=1e-3
    )


def one_cell(cell: Cell, y0: float, v0: float, **transient) -> dict:
    job = Job.from_dict(
        {
            "name": "one_cell",
            "sweep": {
                "omega": {"from": cell.omega, "to": cell.omega, "points": 1},
                "mu_cn": {"from": cell.mu_cn, "to": cell.mu_cn, "points": 1},
            },
            "fixed": {"zeta": cell.zeta, "mu_kn": cell.mu_kn, "f0": cell.f0},
            "initial": {"y": y0, "v": v0},
            "transient": transient,
            "outputs": ["label", "lyapunov"],
        }
    )
    (tile,) = plan_tiles(job)
    return {name: values[0, 0] for name, values in run_tile(job, tile).items()}


SLOW_CYCLE = Cell("slow 2-2", 3.45213, mu_cn=0.529474)


def test_a_slowly_attracting_cycle_is_found_by_jumps_on_agreeing_estimates():
    found = simulate_point(SLOW_CYCLE.omega, multipliers=True, **SLOW_CYCLE.parameters)
    # 28–82 revolutions as the step control varies at equal accuracy (the multiplier
    # 0.9984 amplifies the Jacobian's error 600× in each estimate; benchmarks/RESULTS.md)
    assert found.label == "2-2" and found.revolutions < 100
    assert "slow" in found.flags and 0.99 < abs(found.multipliers[0]) < 1.0
    # without them the transient is nowhere near the cycle after 150 revolutions
    plain = one_cell(SLOW_CYCLE, 0.0, 0.0, jump_agree=0.0, quasiperiodic_after=150)
    assert plain["kind"] == Kind.QUASIPERIODIC
    # SciPy DOP853 from campar's section point: a genuine 2-cycle, same duty cycle
    check = scipy_cell(SLOW_CYCLE.scipy_model(), tuple(found.sections[-1]), 0, 4, rtol=1e-10)
    assert check.label == "2-2" and abs(check.dc - found.dc) < 1e-6
    chaos = simulate_point(CHAOS.omega, **CHAOS.parameters)
    assert "slow" not in chaos.flags


@pytest.mark.slow  # 3000 SciPy revolutions, ~10 s
def test_plain_revolutions_from_rest_creep_towards_the_slow_cycle():
    """SciPy DOP853 from rest, no jumps: still more than 0.01 from the cycle campar found
    after 1000 revolutions (multiplier 0.998), within 0.01 of it after 3000."""
    found = simulate_point(SLOW_CYCLE.omega, **SLOW_CYCLE.parameters)
    model = SLOW_CYCLE.scipy_model()
    x1000, _, _ = integrate(model, (0.0, 0.0), 1000, rtol=1e-8, atol=1e-10)
    x3000, _, _ = integrate(model, x1000, 2000, rtol=1e-8, atol=1e-10)
    assert np.abs(found.sections - x1000).max(axis=1).min() > 0.01
    assert np.abs(found.sections - x3000).max(axis=1).min() < 0.01
