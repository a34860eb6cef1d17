"""The separation speed of a map row (campar.sweep.separation): located by bisection on the
chain's states, checked against cells on either side and against the SciPy peer."""

import numpy as np
import pytest
import yaml
from support.cli import call_campar
from support.jobs import plane_job

import campar
from campar.bench.scipy_model import Model, integrate
from campar.sweep.job import Job
from campar.sweep.plan import Tile, chain_parameters
from campar.sweep.separation import OMEGA_TOL
from campar.sweep.tile import allocate_outputs, cell_settings, run_tile, solver_options

ROW = plane_job(
    "row", (3.0, 0.1, 59), ("mu_cn", 0.8, 0.8, 1), outputs=["label", "eps", "pn", "separation"]
)


def one_cell(job, omega, state):
    from campar.core.kernel import run_chain

    par = chain_parameters(job, 0)
    out = allocate_outputs(1, cell_settings(job).output_bits, job.n_sections)
    run_chain(
        np.array([omega]),
        *(par[k][:1] for k in ("zeta", "f0", "mu_kn", "mu_cn")),
        job.law(),
        np.array(state, float),
        solver_options(job),
        cell_settings(job),
        out,
    )
    return out


@pytest.fixture(scope="module")
def row():
    job = Job.from_dict(ROW)
    return job, run_tile(job, Tile(0, 0, 1))


def test_the_separation_speed_lies_between_the_rows_contact_and_detaching_cells(row):
    job, cells = row
    speed = cells["separation_omega"][0]
    assert np.all(cells["separation_omega"][0] == speed[0])  # one value a row
    speed = speed[0]
    omega, p = job.omega, cells["p"][0]
    below, above = omega < speed, omega > speed
    assert np.all(p[below] == 0)  # contact all the way up to it
    assert p[above][np.argmin(omega[above])] > 0  # the next grid cell up detaches
    assert omega[below].max() < speed < omega[above].min()


def test_cells_just_beside_the_separation_speed_detach_above_and_hold_contact_below(row):
    job, cells = row
    speed = cells["separation_omega"][0, 0]
    omega = job.omega
    upper = int(np.flatnonzero(omega > speed)[np.argmin(omega[omega > speed])])
    start = cells["state"][0, upper]  # the chain's state, as the bisection starts
    assert one_cell(job, speed + 2 * OMEGA_TOL, start).p[0] > 0
    assert one_cell(job, speed - 2 * OMEGA_TOL, start).p[0] == 0


def test_the_scipy_peer_sees_detachment_above_and_none_below(row):
    job, cells = row
    speed = cells["separation_omega"][0, 0]
    start = cells["state"][0, 0]
    for omega, detaches in ((speed + 0.02, True), (speed - 0.02, False)):
        state = one_cell(job, omega, start).state[0]  # on the attractor at this speed
        _, events, _ = integrate(Model(omega), state, 4)
        assert any(kind == "detachment" for _, kind in events) == detaches, omega


def test_the_largest_loads_below_it_are_those_just_below_it(row):
    job, cells = row
    speed = cells["separation_omega"][0, 0]
    below = job.omega < speed
    # the bisection's contact cells lie above the grid's: they can only raise the maxima
    assert cells["separation_pn_max"][0, 0] >= cells["pn_max"][0][below].max()
    assert cells["separation_eps_max"][0, 0] >= cells["eps_max"][0][below].max()
    # in contact the loads grow with the speed: the largest is the contact cell next to it
    omega = job.omega
    upper = int(np.flatnonzero(omega > speed)[np.argmin(omega[omega > speed])])
    just_below = one_cell(job, speed - 2 * OMEGA_TOL, cells["state"][0, upper])
    assert cells["separation_pn_max"][0, 0] == pytest.approx(just_below.pn_max[0], rel=1e-4)
    assert cells["separation_eps_max"][0, 0] == pytest.approx(just_below.eps_max[0], rel=1e-4)


def test_a_row_detaching_everywhere_has_no_separation_speed_on_its_grid():
    data = {**ROW, "sweep": {**ROW["sweep"], "omega": {"from": 3.0, "to": 1.5, "points": 7}}}
    job = Job.from_dict(data)
    cells = run_tile(job, Tile(0, 0, 1))
    assert (cells["p"][0] > 0).all()
    assert np.isnan(cells["separation_omega"][0]).all()


def test_campar_open_gives_one_separation_speed_a_row(capsys, tmp_path):
    data = {
        **ROW,
        "sweep": {
            "omega": {"from": 1.2, "to": 0.3, "points": 10},
            "phi1": {"from": 0.9, "to": 1.2, "points": 2},
        },
        "store": str(tmp_path / "s.zarr"),
    }
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(data))
    run = call_campar(capsys, "run", path)
    assert run.returncode == 0, run.stderr
    with campar.open(tmp_path / "s.zarr") as ds:
        assert ds["separation_speed"].dims == ("phi1",)
        assert ds["phi1"].attrs["long_name"] == "cam rise angle"
        speeds = ds["separation_speed"].values
        assert np.all(np.isfinite(speeds)) and np.all((speeds > 0.3) & (speeds < 1.2))
    shown = call_campar(capsys, "separation", tmp_path / "s.zarr")
    assert shown.returncode == 0 and "separation speed" in shown.stdout


def test_a_basin_has_no_separation_output():
    from campar.errors import JobError

    with pytest.raises(JobError, match="separation: a basin job"):
        Job.from_dict(
            {
                "name": "b",
                "sweep": {
                    "y0": {"from": 0, "to": 1, "points": 2},
                    "ydot0": {"from": 0, "to": 1, "points": 2},
                },
                "fixed": {"omega": 3.0},
                "outputs": ["label", "separation"],
            }
        )
