"""Curves at map scale (campar curves): seeds from a map's typed edges, tasks run by the
runner serially and under mpirun, stored and read back; the curves against the map they
were seeded from and against the cycles themselves."""

import json
import subprocess

import numpy as np
import pytest
from support.cli import call_campar
from support.jobs import plane_job
from support.processes import CAMPAR, MPIRUN, subprocess_env
from support.stores import stored

from campar.continuation.orbit import find_cycle
from campar.errors import JobError
from campar.sweep.job import Job
from campar.sweep.runner import run_job
from campar.views.boundaries import store_boundaries
from campar.views.dataset import open as open_store
from campar.views.map_curves import agreement, curves_job, read_curves, store_seeds

# the 2-2 tongue of the (ω, μkn) plane, coarse: its lower part, where the 1-1 cycle
# doubles at both ends
TONGUE = plane_job(
    "tongue",
    (4.2, 2.2, 28),
    ("mu_kn", 0.93, 0.85, 10),
    chains={"start": "continue"},
    outputs=["label", "dc", "eps", "pn", "multipliers"],
    tiles={"rows": 2},
)


# Session-wide: the test under mpirun that compares with it runs apart from the module's
# others (with the exclusive tests, tests/support/tiers.py), and would build it again.
@pytest.fixture(scope="session")
def tongue(tmp_path_factory):
    """The map, and its curves computed serially by the command."""
    where = tmp_path_factory.mktemp("tongue")
    path = where / "tongue.zarr"
    run_job(Job.from_dict(TONGUE), path)
    out = call_campar(None, "curves", path, "--types", "PD", "--points", "200")
    assert out.returncode == 0, out.stderr
    return path


def test_seeds_are_the_maps_pd_edges_grouped_by_curve(tongue):
    tasks = store_seeds(tongue, ("PD",))
    edges = store_boundaries(tongue, shoot=True).of_type("PD")  # as campar curves types them
    assert sum(task[0].cells for task in tasks) == len(edges) > 10
    assert {task[0].n for task in tasks} == {1}  # the 1-1 cycle doubles at every PD edge
    assert all(seed.type == "PD" and seed.axis in ("omega", "mu_kn") for t in tasks for seed in t)


def test_the_pd_curves_are_made_of_pd_points(tongue):
    """The window cuts the tongue's PD curve above its bottom (μkn ≈ 0.843): two curves of
    1-cycles, the tongue's two sides. At points along each the 1-cycle, solved for afresh
    by Newton at the point's parameters, has the multiplier −1 to 1e-7."""
    pd = sorted(
        (c for c in read_curves(tongue) if c.type == "PD" and c.n == 1),
        key=lambda c: c.values[:, 0].mean(),
    )
    assert len(pd) == 2 and all(len(c.values) > 20 for c in pd)
    assert pd[0].values[:, 0].max() < 2.5 < 2.7 < pd[1].values[:, 0].min()
    for curve in pd:
        for k in np.linspace(0, len(curve.values) - 1, 3).astype(int):
            omega, mu_kn = curve.values[k]
            orbit = find_cycle(1, curve.states[k], omega=omega, mu_kn=mu_kn)
            assert abs(orbit.multipliers[0] + 1.0) < 1e-7, (omega, mu_kn, orbit.multipliers)


def test_the_maps_pd_edges_lie_on_the_curve(tongue):
    """Every PD-typed edge of the map within a cell of the continued PD curve; of the
    curve's stretch inside the periodic map, most beside PD edges. On this coarse grid
    (Δω = 0.074) the map types some of the tongue's edges jump or unknown — its cells do
    not see the multiplier reach −1 — which the curve shows to be PD (the full plane's
    shares: campar bench continuation, benchmarks/RESULTS.md)."""
    found = store_boundaries(tongue)
    with open_store(tongue) as ds:
        grid = {
            "omega": ds["omega"].values,
            "second": ds["mu_kn"].values,
            "kind": ds["kind"].values,
            "n": ds["n"].values,
        }
    a = agreement(found, read_curves(tongue), grid, "PD")
    assert a.edges_near >= 0.95, a
    assert a.length_near >= 0.75, a


def test_the_curves_store_is_verified_and_resumes_to_the_same_bytes(capsys, tongue):
    curves = tongue.with_name("tongue-curves.zarr")
    assert call_campar(capsys, "verify", curves).returncode == 0
    status = call_campar(capsys, "status", curves)
    assert "PD of 1-cycles" in status.stdout
    before = stored(curves)
    again = call_campar(capsys, "curves", tongue, "--types", "PD", "--points", "200", "--json")
    assert again.returncode == 0, again.stderr
    assert json.loads(again.stdout)["curves"][0]["type"] == "PD"
    after = stored(curves)
    assert all(np.array_equal(before[k], after[k], equal_nan=True) for k in before)
    # another map's seeds make another job: its store is refused, nothing overwritten
    other = call_campar(
        capsys, "curves", tongue, "--types", "PD", "--points", "100", "--store", curves
    )
    assert other.returncode == 3 and "different job" in other.stderr, other.stderr
    assert all(np.array_equal(before[k], stored(curves)[k], equal_nan=True) for k in before)


@pytest.mark.mpi
@pytest.mark.skipif(not MPIRUN.exists(), reason=f"no mpirun at {MPIRUN}")
@pytest.mark.process
@pytest.mark.timeout(900)  # 200-point curves on two ranks, each started cold
def test_curves_under_mpirun_equal_the_serial_ones(tongue, tmp_path):
    out = subprocess.run(
        [
            str(MPIRUN),
            "-n",
            "2",
            *CAMPAR,
            "curves",
            str(tongue),
            "--types",
            "PD",
            "--points",
            "200",
            "--store",
            str(tmp_path / "mpi.zarr"),
        ],
        capture_output=True,
        text=True,
        timeout=900,
        env=subprocess_env(),
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.count("tasks") == 1  # rank 0 reports
    serial, parallel = stored(tongue.with_name("tongue-curves.zarr")), stored(tmp_path / "mpi.zarr")
    for name in serial:
        assert np.array_equal(serial[name], parallel[name], equal_nan=True), name


def test_bad_curves_requests_are_one_line(capsys, tongue, tmp_path):
    data = curves_job(tongue, ("PD",), points=50, store=tmp_path / "c.zarr").to_dict()
    data.pop("curves")
    with pytest.raises(JobError, match="is a curves job"):
        Job.from_dict(data)
    for argv, message in (
        (["--types", "XX"], "--types"),
        (["--points", "1"], "--points"),
    ):
        out = call_campar(capsys, "curves", tongue, *argv)
        assert out.returncode == 2 and message in out.stderr, out.stderr
        assert len(out.stderr.strip().splitlines()) == 1
    basin = {
        "name": "basin",
        "sweep": {
            "y0": {"from": -1, "to": 1, "points": 3},
            "ydot0": {"from": -1, "to": 1, "points": 2},
        },
        "fixed": {"omega": 3.0},
    }
    run_job(Job.from_dict(basin), tmp_path / "basin.zarr")
    out = call_campar(capsys, "curves", tmp_path / "basin.zarr")
    assert out.returncode == 2 and "basin store" in out.stderr
