"""One interface everywhere: every key of the model is a flag of each command that computes
cells (point, line, continue), generated from one schema (campar.model.FIELDS,
campar/cli/options.py), and a line's flags reach the kernel (checked against the
independent SciPy model)."""

import argparse
import json

import numpy as np
import pytest

from campar.bench.scipy_model import Model, duty_cycle, integrate
from campar.cli import build_parser, main
from campar.cli.options import FIELD_DEST
from campar.model import FIELDS

CELL_COMMANDS = ("point", "line", "continue")


def subparser(command: str) -> argparse.ArgumentParser:
    parser = build_parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return sub.choices[command]


def option(parser: argparse.ArgumentParser, flag: str) -> argparse.Action:
    found = [a for a in parser._actions if flag in a.option_strings]
    assert found, f"{parser.prog} has no {flag}"
    return found[0]


@pytest.mark.parametrize("command", CELL_COMMANDS)
@pytest.mark.parametrize("key", sorted(FIELDS))
def test_every_model_key_is_a_flag_with_the_jobs_choices(command, key):
    field = FIELDS[key]
    action = option(subparser(command), field.flag)
    if field.choices:
        assert action.metavar == "|".join(field.choices)
    assert key in action.help and str(field.default) in action.help


@pytest.mark.parametrize("command", CELL_COMMANDS)
def test_the_commands_share_one_definition_of_the_model_flags(command):
    """Same flags, same help text: a flag means the same in every command."""
    mine = {a.dest: (a.option_strings, a.help) for a in subparser(command)._actions}
    point = {a.dest: (a.option_strings, a.help) for a in subparser("point")._actions}
    for field in FIELDS.values():
        dest = FIELD_DEST + field.key
        assert mine[dest] == point[dest], field.key
    assert mine["set"] == point["set"] and mine["job"] == point["job"]


def test_a_lines_model_flags_reach_the_kernel(tmp_path):
    """`campar line --cam-velocity literal --duty-cycle force`: its first cell (ω = 2 from
    rest, μcn = 0.9, the clamp active in contact) is a cycle of SciPy's *literal* model, and
    its duty cycle is SciPy's count of the time without force, not the separated time."""
    npz, png = tmp_path / "line.npz", tmp_path / "line.png"
    code = main(
        [
            "line",
            "--omega",
            "2:1.99",
            "--points",
            "2",
            "--mu-cn",
            "0.9",
            "--cam-velocity",
            "literal",
            "--duty-cycle",
            "force",
            "--npz",
            str(npz),
            "-o",
            str(png),
        ]
    )
    assert code == 0
    arrays = np.load(npz)
    assert str(arrays["cam_velocity"]) == "literal" and str(arrays["duty_cycle"]) == "force"
    n, state, dc = int(arrays["n"][0]), arrays["state"][0], float(arrays["dc"][0])
    assert n >= 1  # periodic
    literal = Model(2.0, mu_cn=0.9, cam_velocity="literal")
    back, _, _ = integrate(literal, state, n)
    assert np.max(np.abs(back - state)) < 1e-5  # a fixed point of the literal n-map
    chain_back, _, _ = integrate(Model(2.0, mu_cn=0.9), state, n)
    assert np.max(np.abs(chain_back - state)) > 1e-3  # and not of the chain rule's
    assert dc == pytest.approx(duty_cycle(literal, state, n, by="force"), abs=1e-5)
    assert dc > duty_cycle(literal, state, n, by="separation") + 0.01


def test_line_json_names_the_model_options(tmp_path, capsys):
    code = main(
        [
            "line",
            "--omega",
            "2:1.99",
            "--points",
            "2",
            "--duty-cycle",
            "force",
            "-o",
            str(tmp_path / "l.png"),
            "--json",
        ]
    )
    assert code == 0
    (line,) = json.loads(capsys.readouterr().out)["lines"]
    assert line["parameters"]["duty_cycle"] == "force"
    assert line["parameters"]["cam_velocity"] == "chain"
    assert line["parameters"]["tensile"] == "clamp"
