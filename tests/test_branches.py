"""Branches of periodic orbits, their special points, branch switching and two-parameter
curves (campar.continuation), against SciPy shooting, the map kernel and invariants."""

import json
import subprocess
import sys

import numpy as np
import pytest

from campar.bench import scipy_shooting
from campar.bench.scipy_model import Model, integrate
from campar.continuation.branch import BranchSettings, continue_branch
from campar.continuation.curves import CurveSettings, continue_curve
from campar.continuation.orbit import find_cycle
from campar.continuation.section_map import SectionMap
from campar.continuation.switching import continue_with_switching
from campar.views.continuation import continue_from_cell
from campar.views.point import simulate_point

MU_KN = 0.91  # the paper's line of Figs 4d and 5c
SETTINGS = BranchSettings(max_step=0.02)


@pytest.fixture(scope="module")
def smap():
    return SectionMap()


@pytest.fixture(scope="module")
def period_one(smap):
    """The 1-1 branch at μkn = 0.91 from ω = 5 down to 2, with one doubling followed."""
    orbit = find_cycle(1, (0.6, -0.6), section_map=smap, omega=5.0, mu_kn=MU_KN)
    return continue_with_switching(
        orbit, "omega", (2.0, 5.0), 1, direction=-1.0, section_map=smap, settings=SETTINGS
    )


@pytest.fixture(scope="module")
def period_three(smap):
    """The 3-cycle branch at μkn = 0.91 from ω = 6 (the cell's attractor from rest)."""
    return continue_from_cell("omega", (6.0, 5.0), {"mu_kn": MU_KN}, section_map=smap).root


def test_the_period_one_branch_loses_stability_by_period_doubling_and_regains_it(period_one):
    pds = [sp for sp in period_one.special if sp.type == "PD"]
    assert [round(sp.value, 6) for sp in pds] == [3.542608, 2.366412]
    for sp in pds:
        assert sp.accuracy <= 1e-8
        assert abs(sp.multipliers[0] + 1.0) < 1e-8  # the multiplier is −1 there
    # stable above the first PD point, unstable between them, stable again below
    omega, stable = period_one.values, period_one.stable
    assert stable[omega > 3.55].all() and not stable[(omega < 3.53) & (omega > 2.37)].any()
    assert stable[omega < 2.36].all()
    assert {sp.type for sp in period_one.special} == {"PD"}  # no fold, grazing or NS
    assert (period_one.p == 1).all()


@pytest.mark.slow  # SciPy shooting of the augmented system, ~5 s
def test_the_period_doubling_agrees_with_scipy(period_one):
    sp = period_one.special[0]
    value, state = scipy_shooting.bifurcation_point(
        "PD", {"omega": sp.value, "mu_kn": MU_KN}, "omega", sp.state, 1
    )
    assert abs(value - sp.value) <= 1e-6
    assert np.abs(state - np.array(sp.state)).max() <= 1e-6


def test_switching_follows_the_doubled_branch_round_its_bubble(period_one):
    """The 2-cycles born at ω = 3.5426 return onto the 1-cycles at the other PD point;
    that point is not switched again (it is the same bubble)."""
    (child,) = period_one.children
    assert child.n == 2 and child.origin.value == period_one.special[0].value
    assert child.returned and abs(child.values[-1] - period_one.special[1].value) < 1e-6
    assert set(child.labels) == {"2-2"} and child.stable[1:-1].all()
    # its points are genuine 2-cycles: the two halves differ inside the bubble
    inside = (child.values < 3.5) & (child.values > 2.4)
    halves = np.abs(child.sections[inside, 0] - child.sections[inside, 1]).max(axis=1)
    assert halves.min() > 1e-3


def test_a_doubled_cycle_is_the_attractor_a_simulation_finds(period_one):
    """Mid-bubble the stable 2-cycle of the switched branch is the map kernel's 2-2 cell."""
    child = period_one.children[0]
    i = int(np.argmin(np.abs(child.values - 3.0)))
    omega, state = child.values[i], child.states[i]
    cell = simulate_point(float(omega), mu_kn=MU_KN, y0=state[0], v0=state[1], rtol=1e-10)
    assert cell.label == "2-2"
    shifts = [np.abs(np.roll(cell.sections, k, axis=0) - child.sections[i]).max() for k in (0, 1)]
    assert min(shifts) < 1e-6


def test_the_branch_turns_at_a_fold_where_a_multiplier_crosses_plus_one(period_three):
    kinds = [sp.type for sp in period_three.special]
    assert kinds == ["G", "SN"]
    fold = period_three.special[1]
    assert abs(fold.multipliers[0] - 1.0) < 1e-8 and fold.stable == (True, False)
    # the branch turns back: ω falls to the fold, then rises again
    turn = int(np.argmin(period_three.values))
    assert abs(period_three.values[turn] - fold.value) < 1e-3
    assert period_three.values[-1] > fold.value + 0.5


@pytest.mark.slow  # SciPy shooting of the augmented system for a 3-cycle, ~15 s
def test_the_fold_agrees_with_scipy(period_three):
    fold = period_three.special[1]
    value, _ = scipy_shooting.bifurcation_point(
        "SN", {"omega": fold.value, "mu_kn": MU_KN}, "omega", fold.state, 3
    )
    assert abs(value - fold.value) <= 1e-6


def test_grazing_is_where_the_map_kernel_changes_the_detachment_count(period_three):
    """At the located G point the orbit's extremum of ε touches 0; on either side the
    simulation (the map kernel, started on the cycle) counts the branch's detachments."""
    graze = period_three.special[0]
    assert graze.labels == ("3-1", "3-2") and graze.accuracy <= 1e-8
    for side, label in ((+1e-5, "3-1"), (-1e-5, "3-2")):
        cell = simulate_point(
            graze.value + side, mu_kn=MU_KN, y0=graze.state[0], v0=graze.state[1], rtol=1e-11
        )
        assert cell.label == label, side


def test_grazing_agrees_with_scipys_contact_events(period_three):
    """SciPy's own events on its own cycle, 1e-4 either side of the located G point."""
    graze = period_three.special[0]
    for side, detachments in ((+1e-4, 1), (-1e-4, 2)):
        parameters = {"omega": graze.value + side, "mu_kn": MU_KN}
        x, _ = scipy_shooting.fixed_point(parameters, graze.state, 3)
        _, events, _ = integrate(Model(**parameters), x, 3, rtol=1e-12, atol=1e-14, max_step=1e-3)
        assert sum(kind == "detachment" for _, kind in events) == detachments, side


def test_no_neimark_sacker_point_exists_det_dp_is_below_one(period_one, period_three):
    """Liouville: det DPⁿ = exp(∮ div f dt) < 1 for ζ > 0, so a complex pair never reaches
    the unit circle. The branches' det DPⁿ against SciPy's ∮ div f at one point each."""
    for branch in (period_one, period_three):
        det = np.abs(branch.multipliers[:, 0] * branch.multipliers[:, 1])
        assert det.max() < 1.0
        i = len(branch.values) // 2
        parameters = {"omega": float(branch.values[i]), "mu_kn": MU_KN}
        ref = scipy_shooting.liouville_determinant(parameters, branch.states[i], branch.n)
        assert det[i] == pytest.approx(ref, rel=1e-7)
    assert "NS" not in {sp.type for b in period_one.walk() for sp in b.special}


def test_the_pd_curve_passes_through_the_pd_points_of_other_lines(smap, period_one):
    """A point of the PD curve continued from μkn = 0.91 is a PD point of the line through
    it: a branch along ω at that point's μkn locates its PD at the curve's ω."""
    curve = continue_curve(
        period_one.special[0], "mu_kn", ((2.0, 5.0), (0.84, 0.93)), section_map=smap
    )
    assert curve.type == "PD" and len(curve.values) > 20
    assert curve.values[:, 1].min() < 0.85  # the tongue closes below μkn = 0.85
    k = int(np.argmin(np.abs(curve.values[:, 1] - 0.88)))
    omega, mu_kn = curve.values[k]
    orbit = find_cycle(1, curve.states[k], section_map=smap, omega=omega + 0.05, mu_kn=mu_kn)
    line = continue_branch(
        orbit,
        "omega",
        (omega - 0.05, omega + 0.05),
        direction=-1.0,
        section_map=smap,
        settings=SETTINGS,
    )
    (pd,) = [sp for sp in line.special if sp.type == "PD"]
    assert abs(pd.value - omega) < 1e-7
    # every point of the curve has the multiplier −1
    assert np.abs(curve.multipliers[:, 0] + 1.0).max() < 1e-7


@pytest.mark.parametrize("max_points", [2, 7])
def test_a_curve_has_at_most_max_points_in_both_directions_together(smap, period_one, max_points):
    """The seed lies inside the window: the curve goes both ways from it, and a curves job
    stores at most ``max_points`` points a curve."""
    settings = CurveSettings(max_points=max_points)
    curve = continue_curve(
        period_one.special[0],
        "mu_kn",
        ((2.0, 5.0), (0.84, 0.93)),
        section_map=smap,
        settings=settings,
    )
    assert len(curve.values) == max_points
    assert "max_points" in curve.end


@pytest.mark.process
def test_campar_continue_prints_the_branch_as_json():
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "campar.cli",
            "continue",
            "--omega",
            "6:5",
            "--mu-kn",
            "0.91",
            "--json",
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    data = json.loads(out.stdout)
    assert data["start"]["label"] == "3-1" and data["branch"]["n"] == 3
    assert [sp["type"] for sp in data["special"]] == ["G", "SN"]
    assert data["special"][1]["labels"] == ["3-2", "3-2"]


@pytest.mark.process
def test_campar_point_cycle_finds_the_unstable_cycle():
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "campar.cli",
            "point",
            "--omega",
            "3.54",
            "--mu-kn",
            "0.91",
            "--cycle",
            "1",
            "--json",
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    orbit = json.loads(out.stdout)
    assert orbit["label"] == "1-1" and not orbit["stable"]
    assert orbit["multipliers"][0][0] < -1.0 and orbit["residual"] <= 1e-10


@pytest.mark.process
def test_bad_continuation_requests_are_one_line():
    for argv, message in (
        (["--omega", "6", "--mu-kn", "0.91"], "exactly one parameter a range"),
        (["--omega", "6:2", "--mu-kn", "0.8:0.9"], "exactly one parameter a range"),
        (["--omega", "6:2", "--curves", "PD"], "second parameter"),
        (["--omega", "6:2", "--switch", "-1"], "--switch must be"),
    ):
        out = subprocess.run(
            [sys.executable, "-m", "campar.cli", "continue", *argv], capture_output=True, text=True
        )
        assert out.returncode == 2 and message in out.stderr, (argv, out.stderr)
        assert len(out.stderr.strip().splitlines()) == 1
