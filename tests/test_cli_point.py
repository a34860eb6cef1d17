"""`campar point`: output formats and clear refusals of bad input."""

import json
import subprocess
import sys

import pytest

CAMPAR = [sys.executable, "-m", "campar.cli"]


def campar(*args):
    return subprocess.run([*CAMPAR, *args], capture_output=True, text=True, timeout=300)


def test_point_json_has_the_documented_keys():
    out = campar("point", "--omega", "3.15", "--mu-kn", "0.91", "--json", "--multipliers",
                 "--lyapunov")  # fmt: skip
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    for key in ("label", "n", "p", "kind", "dc", "eps_min", "eps_max", "pn_max",
                "revolutions", "steps", "multipliers", "lyapunov"):  # fmt: skip
        assert key in data
    assert data["label"] == "2-2" and len(data["multipliers"]) == 2


def test_point_summary_is_human_readable():
    out = campar("point", "--omega", "1.0")
    assert out.returncode == 0
    assert out.stdout.startswith("1-1") and "duty cycle" in out.stdout


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--omega", "0"], "omega must be > 0"),
        (["--omega", "1", "--mu-kn", "1.0"], "mu_kn must be in (0, 1)"),
        (["--omega", "1", "--mu-cn", "-0.1"], "mu_cn must be in (0, 1)"),
        (["--omega", "1", "--zeta", "-1"], "zeta must be ≥ 0"),
        (["--omega", "1", "--f0", "nan"], "f0 must be a finite number"),
        (["--omega", "1", "--rtol", "2"], "rtol"),
        (["--omega", "1", "--revolutions", "0"], "--revolutions"),
    ],
)
def test_bad_input_exits_2_naming_the_parameter(args, needle):
    out = campar("point", *args)
    assert out.returncode == 2
    assert needle in out.stderr
    assert out.stdout == ""
