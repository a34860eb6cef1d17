"""Two-parameter curves in the plane of ω and a law parameter (``campar continue --second
phi1:A:B``): the G curve through the ω-branch's G point at the cosine law's own Φ1 = π/3
passes through that point, and a law parameter as --second is validated like the others."""

import json
import math

import pytest

import campar.cli

# The 3-cycle of μkn = 0.91 from ω = 6 has a G point near ω = 5.469 (docs/continuation.md).
BRANCH = ["continue", "--omega", "6:5.3", "--mu-kn", "0.91"]


def test_a_g_curve_in_omega_and_phi1_passes_through_the_omega_branchs_g_point(capsys):
    argv = [*BRANCH, "--curves", "G", "--second", "phi1:1.0:1.1", "--json"]
    assert campar.cli.main(argv) == 0
    result = json.loads(capsys.readouterr().out)
    (g,) = [sp for sp in result["special"] if sp["type"] == "G"]
    assert g["parameters"]["phi1"] == pytest.approx(math.pi / 3, abs=1e-15)
    (curve,) = result["curves"]
    assert (curve["type"], curve["first"], curve["second"]) == ("G", "omega", "phi1")
    # the curve leaves Φ1 = π/3: a curve, not the seed alone
    angles = [pt["phi1"] for pt in curve["points"]]
    assert min(angles) < math.pi / 3 - 0.01 and max(angles) > math.pi / 3 + 0.01
    at = min(curve["points"], key=lambda pt: abs(pt["phi1"] - math.pi / 3))
    assert at["phi1"] == pytest.approx(math.pi / 3, abs=1e-12)
    assert at["omega"] == pytest.approx(g["value"], abs=1e-8)
    assert at["state"] == pytest.approx(g["state"], abs=1e-8)


@pytest.mark.parametrize(
    "second, message",
    [
        ("phi1:1.1:1.0", "a window runs from low to high"),
        ("phi1:1.0:1.0", "the window is empty"),
        ("phi9:1.0:1.1", "'phi9' is not a parameter of the model"),
        ("restitution:0.5:0.9", "restitution belongs to lankarani-nikravesh and flores"),
    ],
)
def test_a_law_parameter_as_second_is_validated_before_computing(second, message, capsys):
    assert campar.cli.main([*BRANCH, "--curves", "G", "--second", second]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_a_curve_holds_one_law_parameter(capsys):
    argv = ["continue", "--omega", "6", "--phi1", "1.0:1.1", "--curves", "G"]
    assert campar.cli.main([*argv, "--second", "n:1.3:1.6"]) == 2
    assert "one law parameter" in capsys.readouterr().err
