"""A tabulated cam's rough knots are breakpoints of the revolution (campar.core.cam.
rough_knots): its cubic spline's third derivative jumps at every knot, and steps across
the knots of a coarse table left each revolution's map off by a noise that read 1-cycles
as 2-2 … 12-12. Checked on the knots chosen and, for tables of the modified trapezoid and
the cycloidal law at 720 points, against SciPy's cycles of the built-in laws they sample
(the spline's own cycle lies within ~1e-7 of them)."""

import math

import numpy as np
import pytest

from campar.bench import scipy_shooting
from campar.core import cam as C
from campar.core import model as M
from campar.core.jit import through_numba
from campar.model.cam_table import parse_table
from campar.model.compute import run_cells
from campar.model.model import Model
from campar.views.dataset import cell_labels

BOUNDS = C.phase_bounds(C.PAPER_ANGLES)
# the chain of tests/test_composite_law_joins.py: SciPy's stable 1-cycles all along
F0 = 0.955426
OMEGA = np.linspace(2.3, 2.0, 121)


def law_table(law: str, points: int) -> str:
    """The built-in law ``law`` on rise and fall, sampled at ``points`` equal steps."""
    cam = C.phased_cam(law, law)
    lift = through_numba(M.cam)
    rows = []
    for theta in np.arange(points) * 2 * math.pi / points:
        phase = int(np.searchsorted(BOUNDS, theta, side="right")) - 1
        rows.append(f"{float(theta)!r},{float(lift(theta, phase, cam)[0])!r}")
    return "theta,S\n" + "\n".join(rows) + "\n"


def table_cam(law: str, points: int, joins: str = "smooth") -> C.TabulatedCam:
    table = parse_table(law_table(law, points))
    return C.tabulated_cam(*table.spline(joins, BOUNDS), BOUNDS)


def test_the_rough_knots_of_a_coarse_table_lie_where_its_law_bends():
    cam = table_cam("modified-trapezoid", 720)
    breaks = cam.breaks[:-1]
    assert cam.breaks[-1] == math.inf and np.all(np.diff(breaks) > 0)
    assert set(breaks) <= set(cam.knots[:-1]) and not set(breaks) & set(BOUNDS)
    # the trapezoid's acceleration bends on its sine ramps (u in [0, 1/8], [3/8, 5/8],
    # [7/8, 1] of rise and fall) and is straight on its plateaus and dwells: the spline's
    # kinks there are its ringing, which decays within a few knots of a ramp
    width = C.PAPER_ANGLES[0]
    ramps = [(0.0, 0.125), (0.375, 0.625), (0.875, 1.0)]
    near = 6 * 2 * math.pi / 720
    for start in (BOUNDS[0], BOUNDS[2]):
        inside = breaks[(breaks > start) & (breaks < start + width)]
        for lo, hi in ramps:
            on_ramp = (inside > start + lo * width) & (inside < start + hi * width)
            assert on_ramp.sum() >= 0.8 * (hi - lo) * 120  # most of the ramp's knots
    for b in breaks:
        offsets = [b - start for start in (BOUNDS[0], BOUNDS[2])]
        assert any(lo * width - near <= x <= hi * width + near for x in offsets for lo, hi in ramps)


def test_a_dense_table_has_no_rough_knot():
    # the cosine law's acceleration jumps at the phase boundaries: one spline a phase
    assert len(table_cam("cosine", 36000, "phases").breaks) == 1  # inf alone
    assert len(table_cam("modified-trapezoid", 36000).breaks) == 1


def test_the_revolution_stops_on_each_rough_knot_of_its_phase_and_nowhere_else():
    cam = table_cam("cycloidal", 720)
    next_join = through_numba(C.next_join)
    omega = 1.7
    for phase in range(4):
        t, times = BOUNDS[phase] / omega, []
        while (t := next_join(cam, phase, t, omega)) < BOUNDS[phase + 1] / omega:
            times.append(t)
        breaks = cam.breaks[(cam.breaks > BOUNDS[phase]) & (cam.breaks < BOUNDS[phase + 1])]
        np.testing.assert_allclose(times, breaks / omega, rtol=1e-15, atol=0)
        assert (len(times) > 0) == (phase in (0, 2))


@pytest.mark.slow
@pytest.mark.parametrize("law", ["modified-trapezoid", "cycloidal"])
def test_a_coarse_tables_chain_has_the_built_in_laws_cycles(law, tmp_path):
    path = tmp_path / f"{law}.csv"
    path.write_text(law_table(law, 720))
    cam = {"table": str(path), "table_joins": "smooth"}
    model = Model.build({"omega": 2.3, "f0": F0, "model": {"cam": cam}})
    out = run_cells(model, omega=OMEGA, outputs=("label",))
    # stepping across the knots: 67 of 121 cells 1-1 (trapezoid), 46 (cycloidal)
    assert set(cell_labels(out.kind, out.n, out.p)) == {"1-1"}
    assert out.revolutions.mean() < 3  # (stepping across: 25 and 28)
    for i in (0, 60, 120):
        parameters = {"omega": float(OMEGA[i]), "f0": F0, "rise": law, "fall": law}
        cycle, jacobian = scipy_shooting.fixed_point(parameters, out.state[i], 1)
        assert max(abs(scipy_shooting.multipliers(jacobian))) < 1.0
        assert np.abs(out.state[i] - cycle).max() < 2e-7
