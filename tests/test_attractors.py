"""Coexisting attractors of one cell (``campar.views.attractors``, ``campar point
--attractors``): the matching rule on synthetic cycles and clouds, and the attractors found
against SciPy DOP853 (``campar.bench.scipy_peer``, an implementation outside campar)."""

import json
import subprocess
import sys

import numpy as np
import pytest

from campar.bench.scipy_model import Model
from campar.bench.scipy_peer import scipy_cell
from campar.views.attractors import (
    BOX_Y,
    CAM_PEAK_SPEED,
    clouds_overlap,
    describe_attractors,
    find_attractors,
    match_tolerance,
    same_cycle,
    spread_starts,
)
from campar.views.point import simulate_point

# The bistable cell: 1-1 from rest, 3-2 from this start (both stable; SciPy DOP853
# at rtol 1e-10 agrees, below).
BISTABLE = {"omega": 5.8, "mu_kn": 0.86}
START_3_2 = (-0.35507, -2.29022)
# campar (rtol 1e-8) and SciPy (rtol 1e-10) settle on one cycle to well within this.
PEER_TOL = 1e-5

# -- the matching rule, on synthetic section sequences -------------------------------------


CYCLE = np.array([[0.1, -1.2], [2.3, 0.4], [-0.5, 1.7]])


@pytest.mark.parametrize("shift", [0, 1, 2])
def test_a_cycle_matches_itself_after_any_cyclic_shift(shift):
    assert same_cycle(CYCLE, np.roll(CYCLE, shift, axis=0), 1e-12)


def test_cycles_match_within_the_tolerance_and_not_beyond():
    tol = match_tolerance()
    rng = np.random.default_rng(1)
    within = np.roll(CYCLE, 1, axis=0) + rng.uniform(-0.9, 0.9, CYCLE.shape) * tol
    assert same_cycle(CYCLE, within, tol)
    beyond = np.roll(CYCLE, 2, axis=0).copy()
    beyond[1, 0] += 1.5 * tol  # one coordinate of one point off
    assert not same_cycle(CYCLE, beyond, tol)


def test_cycles_of_other_order_or_points_do_not_match():
    tol = match_tolerance()
    assert not same_cycle(CYCLE, CYCLE[[0, 2, 1]], tol)  # same points, other order: not a shift
    assert not same_cycle(CYCLE, CYCLE[:2], tol)  # a 2-cycle is not a 3-cycle
    two = np.array([[0.5, 0.1], [0.7, -0.3]])
    assert same_cycle(np.vstack([two, two]), two, tol)  # recorded over twice its period: one orbit
    assert not same_cycle(np.vstack([two, two[::-1]]), two, tol)


def test_the_tolerance_follows_from_the_convergence_tolerances():
    # two records of one cycle differ by ≤ 2 window_tol: 2e-6 with the defaults
    assert match_tolerance() == pytest.approx(1e-5)
    assert match_tolerance(window_tol=1e-5) == pytest.approx(1e-4)


def test_clouds_of_one_circle_overlap_and_apart_do_not():
    golden = (np.sqrt(5) - 1) / 2  # an irrational rotation: a quasi-periodic section

    def circle(start, count=64, centre=(0.0, 0.0)):
        phase = 2 * np.pi * (start + golden * np.arange(count))
        return np.c_[centre[0] + np.cos(phase), centre[1] + np.sin(phase)]

    assert clouds_overlap(circle(0.0), circle(0.37))
    arc = np.c_[np.cos(np.linspace(0, 1, 40)), np.sin(np.linspace(0, 1, 40))]
    assert clouds_overlap(circle(0.0), arc)  # a part of the set (a transient dwelling there)
    assert not clouds_overlap(circle(0.0), circle(0.37, centre=(0.5, 0.0)))
    assert not clouds_overlap(circle(0.0), circle(0.37, centre=(3.0, 0.0)))


def test_starts_are_rest_the_given_ones_then_nested_halton_points_in_the_box():
    starts = spread_starts(16, 2.0, given=[START_3_2])
    assert starts.shape == (16, 2)
    assert tuple(starts[0]) == (0.0, 0.0) and tuple(starts[1]) == START_3_2
    spread = starts[2:]
    assert np.all((spread[:, 0] >= BOX_Y[0]) & (spread[:, 0] <= BOX_Y[1]))
    assert np.all(np.abs(spread[:, 1]) <= CAM_PEAK_SPEED * 2.0)
    assert len(np.unique(starts, axis=0)) == 16
    np.testing.assert_array_equal(spread_starts(32, 2.0, given=[START_3_2])[:16], starts)
    assert tuple(spread_starts(4, 2.0, given=[(0.0, 0.0)])[1]) != (0.0, 0.0)  # rest once


# -- attractors of real cells ---------------------------------------------------------------


@pytest.fixture(scope="module")
def bistable():
    return find_attractors(BISTABLE["omega"], count=16, mu_kn=BISTABLE["mu_kn"])


def test_the_bistable_cell_has_the_two_cycles_scipy_settles_on(bistable):
    """SciPy DOP853 (rtol 1e-10) from rest and from the issue's start settles on a 1-1 and
    a 3-2 cycle, distinct; the spread alone (no given start) finds both, and nothing else."""
    model = Model(BISTABLE["omega"], mu_kn=BISTABLE["mu_kn"])
    peers = [scipy_cell(model, start, 60, 6, rtol=1e-10) for start in ((0.0, 0.0), START_3_2)]
    assert [p.label for p in peers] == ["1-1", "3-2"]
    cycles = [p.sections[-p.n :] for p in peers]
    # distinct: the 1-cycle's point is none of the 3-cycle's points
    assert np.abs(cycles[1] - cycles[0][0]).max(axis=1).min() > 0.1
    assert [a.label for a in bistable.attractors] == ["1-1", "3-2"]
    assert not bistable.unsettled
    for attractor, cycle in zip(bistable.attractors, cycles, strict=True):
        assert same_cycle(attractor.result.sections, cycle, PEER_TOL)
        # stable: both multipliers inside the unit circle
        assert max(abs(m) for m in attractor.result.multipliers) < 1.0
    fractions = [a.fraction for a in bistable.attractors]
    assert sum(fractions) == pytest.approx(1.0) and min(fractions) >= 2 / 16


def test_the_given_start_reaches_the_3_2_cycle():
    census = find_attractors(BISTABLE["omega"], count=8, given=[START_3_2], mu_kn=BISTABLE["mu_kn"])
    labels = [census.attractors[g].label for g in census.basin]
    assert labels[:2] == ["1-1", "3-2"]
    assert census.basin.min() >= 0


def test_each_attractor_is_what_campar_point_gives_from_its_start(bistable):
    for attractor in bistable.attractors:
        y0, v0 = bistable.starts[attractor.starts[0]]
        alone = simulate_point(BISTABLE["omega"], mu_kn=BISTABLE["mu_kn"], y0=y0, v0=v0)
        assert alone.label == attractor.label and alone.state == attractor.state
        # … and its state is a point of the cycle: started there, campar stays on it
        again = simulate_point(
            BISTABLE["omega"], mu_kn=BISTABLE["mu_kn"], y0=attractor.state[0], v0=attractor.state[1]
        )
        assert same_cycle(again.sections, attractor.result.sections, match_tolerance())


@pytest.mark.parametrize("omega", [3.0, 0.3])  # 1-1 and 1-0 at the paper's base values
def test_a_monostable_cell_has_one_attractor_with_fraction_one(omega):
    census = find_attractors(omega, count=16)
    assert len(census.attractors) == 1 and census.attractors[0].fraction == 1.0
    assert not census.unsettled
    # SciPy from the spread's farthest start settles on the same cycle
    attractor = census.attractors[0]
    far = census.starts[np.argmax(np.abs(census.starts).sum(axis=1))]
    peer = scipy_cell(Model(omega), tuple(far), 60, 4, rtol=1e-10)
    assert peer.n == attractor.result.n
    assert same_cycle(attractor.result.sections, peer.sections[-peer.n :], PEER_TOL)


def test_starts_that_settle_on_nothing_are_no_attractor():
    # a budget of 4 revolutions: every start is still on its way to the 1-1 cycle
    census = find_attractors(3.0, count=8, revolutions=4)
    assert census.attractors == () and (census.basin == -1).all()
    assert [r.kind for _, r in census.unsettled] == ["unconverged"] * 8
    assert "8 start(s) settled on no attractor" in describe_attractors(census)


@pytest.mark.process
def test_point_attractors_json_lists_each_attractor_with_its_fraction():
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "campar.cli",
            "point",
            "--omega",
            "5.8",
            "--mu-kn",
            "0.86",
            "--attractors",
            "8",
            "--y0",
            str(START_3_2[0]),
            "--v0",
            str(START_3_2[1]),
            "--json",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["starts"] == 8 and data["unsettled"] == []
    attractors = data["attractors"]
    for item in attractors:
        for key in ("label", "n", "p", "kind", "fraction", "state", "multipliers", "starts"):
            assert key in item
    assert {a["label"] for a in attractors} == {"1-1", "3-2"}
    assert sum(a["fraction"] for a in attractors) == pytest.approx(1.0)
    assert list(START_3_2) in next(a for a in attractors if a["label"] == "3-2")["starts"]


@pytest.mark.process
def test_point_attractors_refuses_too_few_starts():
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "campar.cli",
            "point",
            "--omega",
            "3",
            "--attractors",
            "1",
            "--y0",
            "0.5",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert (
        out.returncode == 2
        and "--attractors must be an integer from 2 to 4096, got 1" in out.stderr
    )
