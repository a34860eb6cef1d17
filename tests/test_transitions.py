"""Typed transitions along a line (``campar.views.transitions``, ``campar line --json``):
the typing rules on synthetic sides, and a period doubling whose multiplier SciPy's
central-difference Jacobian of the section map confirms (``campar.bench.scipy_model``,
an implementation outside campar)."""

import json
from types import SimpleNamespace

import numpy as np
import pytest

from campar.bench.scipy_model import Model, integrate
from campar.cli import main
from campar.views.line import bifurcation_line
from campar.views.plot.bifurcation import plot_line
from campar.views.transitions import (
    NEAR,
    STEPS,
    Side,
    approaching,
    classify_boundary,
    critical_distance,
    find_transitions,
    graze_distance,
)

# -- the rules, on synthetic sides ---------------------------------------------------------


def side(label="1-1", kind="periodic", n=1, p=1, multipliers=(0.3, 0.1), farther=None, **extra):
    return Side(
        index=0,
        omega=1.0,
        label=label,
        kind=kind,
        n=n,
        p=p,
        multipliers=None if multipliers is None else tuple(map(complex, multipliers)),
        farther=None if farther is None else tuple(map(complex, farther)),
        **extra,
    )


def test_distances_to_the_critical_values():
    mult = (complex(-0.97, 0.0), complex(0.2, 0.0))
    assert critical_distance(mult, "-1") == pytest.approx(0.03)
    assert critical_distance(mult, "+1") == pytest.approx(0.8)
    assert critical_distance(mult, "circle") == np.inf  # no complex pair
    pair = (complex(0.3, 0.9), complex(0.3, -0.9))
    assert critical_distance(pair, "circle") == pytest.approx(1 - abs(pair[0]))
    assert critical_distance(None, "-1") == np.inf


def test_an_approach_is_near_or_fast_enough_to_arrive_within_the_boundary():
    assert approaching(NEAR / 2, None, NEAR, 0.2)[0]  # there already
    assert approaching(0.1, 0.2, NEAR, 0.2) == (True, 1.0)  # linear: 1 spacing
    assert not approaching(0.1, 0.12, NEAR, 0.2)[0]  # 5 spacings away at this rate
    assert not approaching(0.1, 0.05, NEAR, 0.2)[0]  # moving away
    assert not approaching(0.3, 0.9, NEAR, 0.2)[0]  # beyond reach
    # a fold's square-root approach with the fold one spacing on: d ∝ √x, x = 1 and 2
    assert approaching(1.0 * 0.1, np.sqrt(2) * 0.1, NEAR, 0.2)[1] == pytest.approx(STEPS)


@pytest.mark.parametrize(
    "before, after, expected",
    [
        # period doubling: 1-1's multiplier → −1, the other side 2-2 (either order)
        (side(multipliers=(-0.99, 0.1)), side("2-2", n=2, p=2, multipliers=(0.95, 0.01)), "PD"),
        (
            side("2-2", n=2, p=2, multipliers=(0.6, 0.01)),
            side(multipliers=(-0.95, 0.1), farther=(-0.9, 0.1)),
            "PD",
        ),
        # Neimark–Sacker: a complex pair → the unit circle, quasi-periodic beyond
        (
            side(multipliers=(0.5 + 0.86j, 0.5 - 0.86j)),
            side("QP", "quasi-periodic", 0, 3, None),
            "NS",
        ),
        # fold: +1, then another cycle
        (
            side("3-2", n=3, p=2, multipliers=(0.88, 0.01), farther=(0.79, 0.01)),
            side(multipliers=(-0.5, -0.2)),
            "SN",
        ),
        # grazing: detachments per revolution change, an extremum of ε → 0
        (side(graze=2e-3, graze_farther=1e-2), side("1-2", p=2, graze=3e-3), "G"),
        # jump: stable on both sides, nothing approaching
        (side(graze=0.3, graze_farther=0.31), side("1-2", p=2, graze=0.3), "jump"),
        (side(multipliers=(-0.99, 0.1)), side("chaos", "chaotic", 0, 40, None), "chaos"),
        (side("QP", "quasi-periodic", 0, 3, None), side(), "unknown"),
        (side(), side("unconverged", "unconverged", 0, 0, None), "unknown"),
    ],
)
def test_boundaries_are_typed_by_what_approaches_its_critical_value(before, after, expected):
    kind, reason, evidence = classify_boundary(before, after)
    assert kind == expected, reason
    if kind in ("PD", "SN", "NS", "G"):
        assert evidence is not None and evidence.type == kind


def test_chaos_names_its_route_and_a_doubled_cycles_plus_one_is_not_a_fold():
    kind, reason, evidence = classify_boundary(
        side(multipliers=(-0.99, 0.1)), side("chaos", "chaotic", 0, 40, None)
    )
    assert "route PD" in reason and evidence.type == "PD"
    kind, reason, _ = classify_boundary(
        side("2-2", n=2, p=2, multipliers=(0.99, 0.01)), side(multipliers=(-0.8, 0.1))
    )
    assert kind == "unknown" and "daughter" in reason


def test_an_even_cycle_is_called_a_fold_only_when_its_points_are_seen_apart():
    fold = dict(label="2-1", n=2, p=1, multipliers=(0.99, 0.01))
    other = side("3-2", n=3, p=2, multipliers=(0.2, 0.1))
    kind, reason, _ = classify_boundary(side(**fold), other)  # σn points not stored (a map)
    assert kind == "unknown" and "pairing unseen" in reason
    apart = side(**fold, half_gap=0.3, half_gap_farther=0.2)  # not pairing up: a fold
    assert classify_boundary(apart, other)[0] == "SN"
    pairing = side(**fold, half_gap=0.1, half_gap_farther=0.2)
    assert "pairing up" in classify_boundary(pairing, other)[1]


def test_graze_distance_refines_the_extremum_nearest_zero():
    t = np.sort(np.r_[np.linspace(0.0, 1.0, 41), 0.413, 0.6071])  # uneven, as at events
    dip = 0.5 * (t - 0.4093) ** 2 + 2e-3  # a contact dip: its minimum 2e-3 between samples
    assert graze_distance(t, dip) == pytest.approx(2e-3, abs=1e-12)
    flight = -((t - 0.6037) ** 2) - 1e-3  # a flight whose top is 1e-3 below the cam
    assert graze_distance(np.r_[t, t + 1.0], np.r_[dip, flight]) == pytest.approx(1e-3)
    assert graze_distance(t, t) is None  # monotone: no extremum


def test_boundaries_of_a_line_without_job_use_its_labels_and_multipliers():
    nan = np.full((2, 2), np.nan)
    mult = [
        [[0.9, 0], [0.01, 0]],
        [[0.97, 0], [0.01, 0]],
        [[-0.96, 0], [0.1, 0]],
        [[-0.9, 0], [0.1, 0]],
        nan,
    ]
    line = SimpleNamespace(
        omega=np.array([2.4, 2.39, 2.38, 2.37, 2.36]),
        labels=["2-2", "2-2", "1-1", "1-1", "QP"],
        kind=np.array([0, 0, 0, 0, 1]),
        n=np.array([2, 2, 1, 1, 0]),
        p=np.array([2, 2, 1, 1, 3]),
        multipliers=np.array(mult),
        sections=np.full((5, 4, 2), np.nan),
    )
    transitions = find_transitions(line)
    assert [(t.before.index, t.after.index) for t in transitions] == [(1, 2), (3, 4)]
    first = transitions[0]
    assert first.type == "PD" and first.evidence.side == "after"
    assert first.before.farther == (0.9 + 0j, 0.01 + 0j)  # the same label's next cell
    assert first.omega == pytest.approx(2.385)
    assert transitions[1].after.multipliers is None


# -- a period doubling of a real line, against SciPy ---------------------------------------


@pytest.fixture(scope="module")
def pd_line():
    """ω 2.5 → 2.2 at μkn = 0.91: a 2-2 cycle halves into 1-1 near ω = 2.365 (ω decreasing),
    i.e. 1-1 period-doubles as ω increases."""
    return bifurcation_line((2.5, 2.2), 100, mu_kn=0.91)


def section_jacobian(model, state, n, h=1e-6):
    """Central-difference Jacobian of the n-revolution section map, SciPy DOP853."""
    jac = np.zeros((2, 2))
    for j in range(2):
        step = np.zeros(2)
        step[j] = h
        plus = integrate(model, state + step, n, rtol=1e-11, atol=1e-13)[0]
        minus = integrate(model, state - step, n, rtol=1e-11, atol=1e-13)[0]
        jac[:, j] = (plus - minus) / (2 * h)
    return jac


def test_a_period_doubling_has_the_multiplier_scipy_finds_near_minus_one(pd_line):
    (pd,) = [t for t in pd_line.transitions if t.type == "PD"]
    assert (pd.before.label, pd.after.label) == ("2-2", "1-1")
    side = pd.after  # the 1-cycle doubles: the evidence is on its side
    assert pd.evidence.side == "after" and pd.evidence.distance < NEAR
    reference = []
    for index in (side.index, side.index + 1):  # the last cell and the next one away
        model = Model(float(pd_line.omega[index]), mu_kn=0.91)
        jac = section_jacobian(model, pd_line.state[index], 1)
        ref = sorted(np.linalg.eigvals(jac), key=abs, reverse=True)
        mine = pd_line.multipliers[index, :, 0] + 1j * pd_line.multipliers[index, :, 1]
        np.testing.assert_allclose(sorted(mine, key=abs, reverse=True), ref, atol=1e-4)
        reference.append(ref[0])
    # SciPy's multiplier itself: real, near −1, and nearer at the cell next to the boundary
    assert abs(reference[0].imag) < 1e-9 and abs(reference[0] + 1) < NEAR
    assert abs(reference[0] + 1) < abs(reference[1] + 1)
    # the doubled cycle on the other side: P² has a multiplier near +1
    assert pd.before.multipliers[0].real > 0.95


def test_a_grazing_has_the_shallow_flight_scipy_finds_on_one_side_only():
    """1-1 → 1-0 near ω = 0.535 (μkn = 0.91): SciPy DOP853 from the last cell's state on
    the 1-1 side sees one detachment with a flight under 1 % of the revolution (a flight of
    depth d lasts ∝ √d), and none from the 1-0 side."""
    line = bifurcation_line((0.6, 0.45), 60, mu_kn=0.91)
    (graze,) = line.transitions
    assert graze.type == "G" and (graze.before.label, graze.after.label) == ("1-1", "1-0")
    assert graze.evidence.distance < 0.01
    flights = []
    for side in (graze.before, graze.after):
        model = Model(side.omega, mu_kn=0.91)
        _, events, _ = integrate(
            model, line.state[side.index], 1, rtol=1e-11, atol=1e-13, max_step=0.05
        )
        flights.append([t for t, kind in events if kind in ("detachment", "impact")])
    (t_off, t_on), none = flights
    assert none == [] and 0 < t_on - t_off < 0.01 * 2 * np.pi / graze.before.omega


def test_the_line_figure_labels_its_transitions(pd_line):
    figure = plot_line(pd_line)
    texts = [t.get_text() for t in figure.axes[0].texts]
    assert texts == ["PD"]


def test_line_json_lists_each_transition_with_its_evidence(tmp_path, capsys):
    argv = [
        "line",
        "--omega",
        "2.2:2.5",
        "--points",
        "100",
        "--mu-kn",
        "0.91",
        "--json",
        "-o",
        str(tmp_path / "line.png"),
    ]
    assert main(argv) == 0
    data = json.loads(capsys.readouterr().out)
    (line,) = data["lines"]
    (pd,) = line["transitions"]
    assert pd["type"] == "PD" and (pd["from"], pd["to"]) == ("2-2", "1-1")
    assert pd["omega_after"] < pd["omega"] < pd["omega_before"]
    re, im = pd["evidence"]["value"]
    assert abs(re + 1) < NEAR and im == 0.0
    assert len(pd["before"]["multipliers"]) == 2 and pd["after"]["multipliers_farther"]
    assert (tmp_path / "line.png").exists()
