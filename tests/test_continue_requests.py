"""`campar continue` does what it is asked or says why not: ranges refused before any work,
the start cycle named first, what was asked for and not found said on stderr and in the
JSON, each curve reported once."""

import json
from dataclasses import replace

import numpy as np
import pytest

import campar.views.continuation as continuation
from campar.cli import main
from campar.continuation.curves import BifurcationCurve
from campar.continuation.special import SpecialPoint


def no_work(*args, **kwargs):
    raise AssertionError("the request was not refused before the start cell was simulated")


@pytest.mark.parametrize(
    "argv, said",
    [
        (["--second", "mu_kn:0.5:1.5"], ("--second mu_kn:0.5:1.5:", "mu_kn", "1.5")),
        (["--second", "mu_kn:nan:0.95"], ("--second mu_kn:nan:0.95:", "finite", "nan")),
        (["--second", "mu_kn:0.9:0.9"], ("the window is empty",)),
        (["--second", "foo:1:2"], ("'foo' is not a parameter of the model",)),
        (["--second", "mu_kn:0.95:0.84"], ("from low to high: mu_kn:0.84:0.95",)),
        (["--second", "omega:3:4"], ("must differ from the branch's, omega",)),
        (["--second", "mu_cn:0.7:inf"], ("--second mu_cn:0.7:inf:", "finite", "inf")),
        (["--second", "f0:-1:0.5"], ("--second f0:-1:0.5:", "f0", "-1")),
    ],
)
def test_a_bad_second_window_is_refused_in_one_line_before_any_work(
    argv, said, capsys, monkeypatch
):
    monkeypatch.setattr(continuation, "simulate_point", no_work)
    code = main(["continue", "--omega", "4:3", "--mu-kn", "0.91", "--curves", "PD", *argv])
    err = capsys.readouterr().err
    assert code == 2 and all(part in err for part in said), err
    assert len(err.strip().splitlines()) == 1


@pytest.mark.parametrize(
    "argv, said",
    [
        (["--omega", "nan:3"], ("omega", "finite", "nan")),
        (["--omega", "4:-1"], ("omega", "-1")),
        (["--omega", "4", "--mu-kn", "0.5:1.5"], ("mu_kn", "1.5")),
        (["--omega", "4:4"], ("the range of omega is empty",)),
        (["--omega", "4:3", "--mu-cn", "1.2"], ("mu_cn", "1.2")),
        (["--omega", "4:3", "--second", "mu_kn:0.8:0.9"], ("give their types (--curves",)),
    ],
)
def test_a_bad_range_is_refused_in_one_line_before_any_work(argv, said, capsys, monkeypatch):
    monkeypatch.setattr(continuation, "simulate_point", no_work)
    code = main(["continue", *argv])
    err = capsys.readouterr().err
    assert code == 2 and all(part in err for part in said), err
    assert len(err.strip().splitlines()) == 1


def test_python_gets_the_same_refusal():
    from campar.errors import JobError

    with pytest.raises(JobError, match="the window is empty"):
        continuation.continue_from_cell(
            "omega",
            (4.0, 3.0),
            {"mu_kn": 0.91},
            curve_types=("PD",),
            second="mu_kn",
            second_window=(0.9, 0.9),
        )


def test_a_curve_type_not_found_is_said_on_stderr_and_in_the_json(capsys, tmp_path):
    """From rest at ω = 6 the cell is 3-1; its branch down to 5 has a grazing and a fold
    but no PD point (test_branches checks both against SciPy): no PD curve can exist."""
    figure = tmp_path / "b.png"
    argv = ["continue", "--omega", "6:5", "--mu-kn", "0.91", "--curves", "PD"]
    argv += ["--second", "mu_kn:0.9:0.92", "--switch", "1", "--json", "-o", str(figure)]
    assert main(argv) == 0
    out, err = capsys.readouterr()
    data = json.loads(out)
    assert data["start"]["label"] == "3-1" and data["start_cell"] == "3-1"
    assert "reaches" in data["start_chosen"]
    assert [sp["type"] for sp in data["special"]] == ["G", "SN"]
    assert data["curves"] == []
    said = [line.removeprefix("campar continue: ") for line in err.strip().splitlines()]
    assert said[:2] == data["missing"]
    assert data["missing"][0].startswith("no switch: no PD point on the 3-1 cycle's branch")
    assert data["missing"][1].startswith("no PD curve: no PD point on the branches")
    assert said[2] == f"{tmp_path / 'b-curves.png'} not written: no curve found"
    assert figure.exists() and not (tmp_path / "b-curves.png").exists()


def test_the_start_cycle_chosen_is_the_first_line(capsys):
    assert main(["continue", "--omega", "4:3.9", "--mu-kn", "0.91", "--cycle", "1"]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert first.startswith("start: 1-1 cycle (stable) at omega=4,")
    assert first.endswith("--cycle 1, from the simulated cell (2-1)")


def special(value: float, second: float, state=(0.5, -0.7)) -> SpecialPoint:
    return SpecialPoint(
        type="PD",
        parameter="omega",
        value=value,
        state=state,
        n=1,
        multipliers=(-1.0, -0.1),
        labels=("1-1", "1-1"),
        stable=(True, False),
        accuracy=1e-12,
        parameters={"omega": value, "zeta": 0.2, "f0": 0.5, "mu_kn": second, "mu_cn": 0.8},
    )


def u_shaped_curve() -> BifurcationCurve:
    """A PD curve through (3, 0.9) and (5, 0.9), bending up to μkn = 0.95 between."""
    t = np.linspace(0.0, np.pi, 201)
    values = np.column_stack([4.0 - np.cos(t), 0.9 + 0.05 * np.sin(t)])
    states = np.column_stack([0.5 + 0.01 * t, -0.7 + 0.0 * t])
    return BifurcationCurve(
        type="PD",
        n=1,
        first="omega",
        second="mu_kn",
        parameters={},
        model={},
        values=values,
        states=states,
        multipliers=np.full((201, 2), -1.0 + 0j),
        p=np.ones(201, int),
        end="left the window",
    )


def test_a_special_point_on_a_curve_already_continued_starts_none():
    curve, window = u_shaped_curve(), ((2.0, 6.0), (0.84, 0.95))
    far_end = special(5.0, 0.9, state=(0.5 + 0.01 * np.pi, -0.7))
    assert continuation.on_a_curve(far_end, [curve], window)
    # off the curve: in the plane, in the cycle's state, in type or in period
    assert not continuation.on_a_curve(special(4.0, 0.9, far_end.state), [curve], window)
    assert not continuation.on_a_curve(special(5.0, 0.9, (0.2, -0.7)), [curve], window)
    assert not continuation.on_a_curve(replace(far_end, type="SN"), [curve], window)
    curve.n = 2
    assert not continuation.on_a_curve(far_end, [curve], window)


@pytest.mark.slow
def test_a_curve_through_both_pd_points_of_a_branch_is_reported_once(capsys):
    """Over ω 6 → 2 the 1-cycles have two PD points on one PD curve of the (ω, μkn)
    window: one curve, passing through both (each a PD point by SciPy's shooting)."""
    from campar.bench import scipy_shooting

    argv = ["continue", "--omega", "6:2", "--mu-kn", "0.91", "--cycle", "1", "--curves", "PD"]
    assert main([*argv, "--second", "mu_kn:0.84:0.95", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    pds = [sp for sp in data["special"] if sp["type"] == "PD"]
    assert len(pds) == 2 and len(data["curves"]) == 1 and data["missing"] == []
    values = np.array([[pt["omega"], pt["mu_kn"]] for pt in data["curves"][0]["points"]])
    for sp in pds:
        value, _ = scipy_shooting.bifurcation_point(
            "PD", {"omega": sp["value"], "mu_kn": 0.91}, "omega", sp["state"], 1
        )
        scaled = (values - [value, 0.91]) / [4.0, 0.11]  # the window's sides
        assert np.linalg.norm(scaled, axis=1).min() <= 0.02  # within a curve step


def test_the_branch_length_is_bounded_before_any_work(capsys, monkeypatch):
    monkeypatch.setattr(continuation, "simulate_point", no_work)
    assert main(["continue", "--omega", "4:3", "--max-points", "1000000000"]) == 2
    assert "--max-points must be from 2 to 100000" in capsys.readouterr().err
