"""A law parameter of the model as the continuation parameter: the cam's phase angles,
the contact's exponent and restitution, continued by the same section map as ω."""

import math

import numpy as np
import pytest

import campar.cli
from campar.continuation.orbit import find_cycle, solve_cycle
from campar.model import Model
from campar.views.continuation import continue_from_cell

OMEGA = 3.0  # a stable 1-1 cycle of the cosine law at the paper's base values


def test_phi1_continued_through_pi_over_3_meets_the_omega_branch():
    """At Φ1 = π/3 the cosine cam is the paper's: the Φ1-branch's cycle there equals the
    ω-branch's cycle at the same parameters to 1e-10."""
    by_omega = continue_from_cell("omega", (OMEGA, OMEGA - 0.1), {"omega": OMEGA})
    by_phi1 = continue_from_cell("phi1", (math.pi / 3, 1.2), {"omega": OMEGA})
    assert by_phi1.start.parameters["phi1"] == math.pi / 3
    a, b = np.array(by_omega.start.sections), np.array(by_phi1.start.sections)
    assert a.shape == b.shape and np.max(np.abs(a - b)) < 1e-10
    # through π/3: a branch from 0.9 to 1.2 passes it, and each of its points is the cycle
    # Newton's method finds at that angle with a cam built afresh (the model's phi1)
    through = continue_from_cell("phi1", (0.9, 1.2), {"omega": OMEGA}).root
    assert through.values.min() < math.pi / 3 < through.values.max()
    k = int(np.argmin(np.abs(through.values - math.pi / 3)))
    angle = float(through.values[k])
    model = Model.build(omega=OMEGA, phi1=angle, phi4=math.pi - angle)
    fresh = find_cycle(through.n, through.states[k], model=model, omega=OMEGA)
    assert np.max(np.abs(np.array(fresh.state) - through.states[k])) < 1e-10


# Spans the branch leaves in a few dozen points: below restitution 0.74 (ω = 2, Flores)
# its steps shrink to 1e-4, and a span to 0.6 ends at max_points (5000 points, 80 000 shots).
@pytest.mark.parametrize(
    "parameter, span, omega, law",
    [("n", (1.5, 1.3), OMEGA, {}), ("restitution", (0.8, 0.77), 2.0, {"law": "flores"})],
)
def test_contact_parameters_continue_and_agree_with_a_fresh_model(parameter, span, omega, law):
    model = Model.build(omega=omega, **law)
    result = continue_from_cell(parameter, span, {"omega": omega}, model=model)
    branch = result.root
    assert len(branch.values) > 3 and min(span) <= branch.values[-1] <= max(span) + 1e-9
    k = len(branch.values) // 2
    fresh_model = model.replace(**{parameter: float(branch.values[k])})
    fresh = solve_cycle(branch.n, branch.states[k], {"omega": omega}, model=fresh_model)
    # a swept exponent compiles the general power: the fresh model's specialised one
    # agrees to the integrator's accuracy
    assert np.max(np.abs(np.array(fresh.state) - branch.states[k])) < 1e-8


def test_continue_takes_a_law_parameters_range_on_the_command_line(capsys):
    argv = ["continue", "--omega", str(OMEGA), "--phi1", "1.0:1.1", "--json"]
    assert campar.cli.main(argv) == 0
    import json

    data = json.loads(capsys.readouterr().out)
    assert data["start"]["parameters"]["phi1"] == 1.0
