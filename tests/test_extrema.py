"""min ε, max ε and max Pn of a cell against an independent SciPy reference, every law.

The reference (campar.bench.scipy_model.extremes) integrates the cell's cycle from its
final state with solve_ivp (DOP853, rtol 1e-12) piece by piece between cam phase
boundaries and contact events, samples each piece's dense output at 2001 points and
refines the extreme samples by a bounded scalar search: no campar code. At the
default tolerances (DOP853, rtol 1e-7) campar must agree to 1e-6 in ε and 1e-5
relative in Pn: the extremes are located on the dense output, not on a model of the
step (a free flight across a cycloidal fall is one long step).
"""

import math

import numpy as np
import pytest

from campar.bench.scipy_model import Model, extremes
from campar.core.cam import PAPER_ANGLES, phase_bounds, phased_cam, tabulated_cam
from campar.core.contact import contact_law
from campar.core.kernel import CONVERGED, OUT_EXTREMA, OUT_STATS, run_chain
from campar.core.model import LAW_CLAMP, PAPER_LAW, Law
from campar.model.cam_table import periodic_spline
from campar.sweep.job import load_job
from campar.sweep.tile import allocate_outputs, cell_settings, solver_options

EPS_TOL = 1e-6
PN_RTOL = 1e-5
ZETA = 0.2
# a harmonic cam, S = (1 − cos θ)/2, as a table of 48 points
TABLE_THETA = np.linspace(0.0, 2.0 * math.pi, 48, endpoint=False)
TABLE_LIFT = 0.5 * (1.0 - np.cos(TABLE_THETA))


def defaults():
    job = load_job("jobs/smoke.yaml")  # the job defaults: DOP853, rtol 1e-7
    settings = cell_settings(job)._replace(transient=CONVERGED, output_bits=OUT_STATS | OUT_EXTREMA)
    return solver_options(job), settings


def run_cells(law, omegas, f0, mu_kn, mu_cn, x0=(0.0, 0.0)):
    """A chain of cells along ``omegas`` from x0; its outputs."""
    solver, settings = defaults()
    n = len(omegas)
    out = allocate_outputs(n, OUT_STATS | OUT_EXTREMA, 0)

    def column(v):
        return np.full(n, float(v))

    run_chain(
        np.asarray(omegas, float),
        column(ZETA),
        column(f0),
        column(mu_kn),
        column(mu_cn),
        law,
        np.array(x0, float),
        solver,
        settings,
        out,
    )
    return out


def check_against_scipy(out, i, model, impact=None):
    assert out.kind[i] == 0 and out.n[i] >= 1, "the check needs a periodic cell"
    n = int(out.n[i])
    eps_min, eps_max, pn_max = extremes(
        model, out.state[i], n, rtol=1e-12, atol=1e-14, impact=impact
    )
    assert abs(out.eps_min[i] - eps_min) <= EPS_TOL, (out.eps_min[i], eps_min)
    assert abs(out.eps_max[i] - eps_max) <= EPS_TOL, (out.eps_max[i], eps_max)
    assert abs(out.pn_max[i] - pn_max) <= PN_RTOL * pn_max, (out.pn_max[i], pn_max)
    return eps_min, eps_max, pn_max


def test_from_rest_paper_law():
    out = run_cells(PAPER_LAW, [3.0], 0.5, 0.8, 0.8)
    check_against_scipy(out, 0, Model(3.0, f0=0.5, mu_kn=0.8, mu_cn=0.8, zeta=ZETA))


def test_a_warm_started_cycle_of_two_revolutions():
    omegas = [3.02, 3.01, 3.0]
    out = run_cells(PAPER_LAW, omegas, 0.5, 0.91, 0.8)
    assert out.n[-1] == 2  # the paper's 2-2 at μkn 0.91, ω 3.0
    check_against_scipy(out, 2, Model(3.0, f0=0.5, mu_kn=0.91, mu_cn=0.8, zeta=ZETA))


def test_near_grazing():
    # the follower never leaves the cam, its gap closing to within 1e-3 of detaching
    out = run_cells(PAPER_LAW, [1.0], 1.0, 0.8, 0.8)
    eps_min, _, _ = check_against_scipy(out, 0, Model(1.0, f0=1.0, mu_kn=0.8, mu_cn=0.8))
    assert 0.0 < eps_min < 1e-3 and out.p[0] == 0


LAWS = {
    # (rise, fall, contact law): every motion law, the table and every contact law
    "cycloidal": ("cycloidal", "cycloidal", "hunt-crossley", 1.5),
    "345-sine-lankarani": ("polynomial-345", "modified-sine", "lankarani-nikravesh", 1.5),
    "trapezoid-cosine-flores": ("modified-trapezoid", "cosine", "flores", 1.5),
    "table-hunt-crossley-n1.2": ("table", None, "hunt-crossley", 1.2),
}


CELLS = [
    pytest.param(name, omega, f0, id=f"{name}-{omega}")
    for name in LAWS
    for omega, f0 in [(2.0, 1.0), (4.0, 0.5)]
    # a restitution law's cell must be a 1-cycle (below): at ω 4 these are 2- and 12-cycles
    if not (LAWS[name][2] != "hunt-crossley" and omega == 4.0)
]


@pytest.mark.slow  # a kernel compile for each combination of laws
@pytest.mark.parametrize("name, omega, f0", CELLS)
def test_every_law_from_rest(name, omega, f0):
    rise, fall, contact, n = LAWS[name]
    if rise == "table":
        knots, coef = periodic_spline(TABLE_THETA, TABLE_LIFT)
        cam = tabulated_cam(knots, coef, phase_bounds(PAPER_ANGLES))
        peer_cam = {"table": (TABLE_THETA, TABLE_LIFT)}
    else:
        cam = phased_cam(rise, fall)
        peer_cam = {"rise": rise, "fall": fall}
    law = Law(np.int64(LAW_CLAMP), cam, contact_law(contact, n=n))
    out = run_cells(law, [omega], f0, 0.8, 0.8)
    model = Model(omega, f0=f0, mu_kn=0.8, mu_cn=0.8, zeta=ZETA, contact=contact, n=n, **peer_cam)
    # a restitution law's state holds the last impact's velocity, which sets the damping
    # of a contact the cycle starts in: the chain's own (law.contact.impact) at its end
    impact = None
    if contact != "hunt-crossley":
        assert out.n[0] == 1  # a 1-cycle: its end state is the chain's end, with that impact
        impact = float(law.contact.impact[0])
    check_against_scipy(out, 0, model, impact)
