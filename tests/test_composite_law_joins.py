"""The joins of a composite cam law's pieces are breakpoints of the revolution
(campar.core.cam.next_join): a step across one, where the cam's fourth derivative jumps,
passes the embedded error estimate with an error far above the tolerance. Checked on the
join times themselves and, for the modified trapezoid, against the independent SciPy
model: the chain's revolutions repeat its cycle to the integrator's accuracy, and a chain
through a region that read as 3-3, 4-4 and 5-5 is 1-1 throughout, as SciPy's cycle is."""

import math

import numpy as np
import pytest

from campar import simulate_point
from campar.bench import scipy_shooting
from campar.core import cam as C
from campar.core.jit import through_numba
from campar.model.compute import run_cells
from campar.model.model import Model
from campar.views.dataset import cell_labels

ANGLES = (1.1, 1.9, 0.9, 2 * math.pi - 3.9)
JOINS = {"modified-trapezoid": (0.125, 0.375, 0.625, 0.875), "modified-sine": (0.125, 0.875)}
TRAPEZOID = {"rise": "modified-trapezoid", "fall": "modified-trapezoid"}
# A cell of jobs/design_f0_modified-trapezoid.yaml (ω, f0) where the chain's revolutions,
# stepping across the joins, scattered by 8e-6 about the cycle
CELL = {"omega": 2.144322, "f0": 0.955426}


def join_times(law_name, phase, omega):
    """Every time next_join gives in ``phase`` of a cam of this law on rise and fall, from
    the phase's start on."""
    cam = C.phased_cam(law_name, law_name, ANGLES)
    bounds = C.phase_bounds(ANGLES)
    next_join = through_numba(C.next_join)
    t, times = bounds[phase] / omega, []
    while (t := next_join(cam, phase, t, omega)) < bounds[phase + 1] / omega:
        times.append(t)
    return times, bounds


@pytest.mark.parametrize("law", C.MOTION_LAWS)
@pytest.mark.parametrize("phase", [0, 1, 2, 3])
def test_the_revolution_stops_on_each_join_of_a_composite_law_and_nowhere_else(law, phase):
    omega = 1.7
    times, bounds = join_times(law, phase, omega)
    fractions = JOINS.get(law, ()) if phase in (0, 2) else ()
    width = ANGLES[phase]
    expected = [(bounds[phase] + u * width) / omega for u in fractions]
    np.testing.assert_allclose(times, expected, rtol=1e-12, atol=0)


def scipy_one_cycle(parameters: dict, x):
    """SciPy's 1-cycle near x and its multipliers (campar.bench.scipy_shooting)."""
    cycle, jacobian = scipy_shooting.fixed_point(parameters, x, 1)
    return cycle, scipy_shooting.multipliers(jacobian)


@pytest.mark.slow
def test_a_modified_trapezoid_cycle_repeats_to_the_integrators_accuracy():
    cell = simulate_point(**CELL, **TRAPEZOID)
    cycle, multipliers = scipy_one_cycle({**CELL, **TRAPEZOID}, cell.state)
    assert max(abs(multipliers)) < 0.5  # a strongly attracting 1-cycle
    assert cell.label == "1-1" and cell.revolutions <= 12
    assert np.abs(np.array(cell.state) - cycle).max() < 5e-8
    # the paper's recipe from the cycle itself: one plain revolution, then a read window
    window = simulate_point(
        {
            **CELL,
            "model": {"cam": TRAPEZOID},
            "transient": {"mode": "fixed", "max_revolutions": 1},
            "classify": {"sections": 32},
        },
        state=tuple(cycle),
    )
    # the window's 32 section points repeat within the classifier's 1e-6 (they scattered by
    # 8e-6 with steps across the joins: no period up to 32 then)
    assert window.label == "1-1"
    assert np.abs(np.array(window.sections) - cycle).max() < 5e-8


@pytest.mark.slow
def test_a_modified_trapezoid_chain_is_one_one_where_scipy_has_a_stable_one_cycle():
    model = Model.build({"omega": 2.3, "f0": CELL["f0"], "model": {"cam": TRAPEZOID}})
    omega = np.linspace(2.3, 2.0, 121)
    out = run_cells(model, omega=omega, outputs=("label",))
    assert set(cell_labels(out.kind, out.n, out.p)) == {"1-1"}
    for i in (0, 60, 120):
        parameters = {"omega": float(omega[i]), "f0": CELL["f0"], **TRAPEZOID}
        cycle, multipliers = scipy_one_cycle(parameters, out.state[i])
        assert max(abs(multipliers)) < 1.0
        assert np.abs(out.state[i] - cycle).max() < 5e-7
