"""Basins of attraction (a job sweeping y0, ydot0: ``campar.sweep.basin``, ``campar.views.basins``).

Checked against independent evidence: the bistable cell (ω = 5.8, μkn = 0.86) has the
1-1 and 3-2 attractors, and the SciPy model started from a start of each basin ends on
that basin's cycle; a monostable cell's basin is one attractor with fraction 1; every
cell is the record ``find_attractors`` makes of its start, grouped alike; the grouping
equals the record-by-record rule; resume, rank count and the two backends give the same
store; bad jobs are refused with a message naming the key.
"""

import numpy as np
import pytest
import xarray as xr
from support.cli import call_campar
from support.jobs import computed_store, merge, resume_after_interrupt
from support.processes import assert_mpirun_store_equals
from support.stores import assert_same_store, stored

import campar
import campar.sweep.runner as runner
from campar.bench.scipy_model import Model
from campar.bench.scipy_peer import scipy_cell
from campar.core.codes import Kind
from campar.errors import JobError
from campar.sweep.census import group_cells, record_points, same_record
from campar.sweep.job import Job
from campar.views.attractors import CHAOS_AFTER, CLOUD_POINTS, find_attractors
from campar.views.plot import PlotError, plot_store
from campar.views.point import simulate_point

# 7 × 6 starts over the box of jobs/basin_bistable.yaml at its cell; one row of starts a tile.
BASIN = {
    "name": "basin",
    "sweep": {
        "y0": {"from": -1.0, "to": 3.0, "points": 7},
        "ydot0": {"from": -8.7, "to": 8.7, "points": 6},
    },
    "fixed": {"omega": 5.8, "mu_kn": 0.86},
    "tiles": {"rows": 2},
}
MONOSTABLE = merge(BASIN, {"fixed": {"omega": 5.8, "mu_kn": 0.82}})


# Session-wide: the test under mpirun that compares with it runs apart from the module's
# others (with the exclusive tests, tests/support/tiers.py), and would build it again.
@pytest.fixture(scope="session")
def basin(tmp_path_factory):
    """The BASIN store (Zarr) and its job."""
    return computed_store(tmp_path_factory, BASIN)


def starts_of(job: Job) -> np.ndarray:
    """(cells, 2) the start of every cell, in the store's (ydot0, y0) order, flattened."""
    v, y = np.meshgrid(job.second_values, job.first_values, indexing="ij")
    return np.stack([y.ravel(), v.ravel()], axis=1)


def test_the_bistable_basin_holds_1_1_and_3_2_and_scipy_ends_on_each_cycle(basin):
    path, job = basin
    with campar.open(path) as ds:
        labels = ds["attractor_label"].values.tolist()
        assert sorted(labels) == ["1-1", "3-2"]
        assert ds["attractor_fraction"].sum() == pytest.approx(1.0)
        assert (ds["basin"].values >= 1).all()  # every start settled
        model = Model(5.8, mu_kn=0.86)
        tol = 1e-4  # SciPy (rtol 1e-10) against campar (rtol 1e-7) on a stable cycle
        for rank in ds["attractor"].values:
            start = starts_of(job)[np.flatnonzero(ds["basin"].values.ravel() == rank)[0]]
            peer = scipy_cell(model, start, 60, 6, rtol=1e-10)
            a = ds.sel(attractor=rank)
            assert peer.label == str(a["attractor_label"].values)
            cycle = a["attractor_sections"].values[: int(a["attractor_n"])]
            scipy_cycle = peer.sections[-int(a["attractor_n"]) :]
            assert same_record(Kind.PERIODIC, cycle, Kind.PERIODIC, scipy_cycle, tol)


def test_a_monostable_basin_is_one_attractor_with_fraction_one(tmp_path):
    runner.run_job(Job.from_dict(MONOSTABLE), tmp_path / "mono.zarr")
    with campar.open(tmp_path / "mono.zarr") as ds:
        assert ds["attractor_label"].values.tolist() == ["1-1"]
        assert ds["attractor_fraction"].values.tolist() == [1.0]
        assert (ds["basin"].values == 1).all()


def test_every_cell_is_the_find_attractors_record_of_its_start_and_grouped_alike(basin):
    path, job = basin
    starts = starts_of(job)
    census = find_attractors(5.8, starts=starts, mu_kn=0.86)
    with campar.open(path) as ds:
        # the same attractors, ranked alike, and every start in the same one
        assert ds["attractor_label"].values.tolist() == [a.label for a in census.attractors]
        assert ds["attractor_fraction"].values == pytest.approx(
            [a.fraction for a in census.attractors]
        )
        assert (ds["basin"].values.ravel() == census.basin + 1).all()
        # bit for bit, the record of `campar point --attractors` (a cell of each attractor)
        sections = ds["sections"].values.reshape(len(starts), *ds["sections"].shape[2:])
        for rank in ds["attractor"].values:
            i = int(np.flatnonzero(ds["basin"].values.ravel() == rank)[-1])
            point = simulate_point(
                5.8,
                y0=float(starts[i, 0]),
                v0=float(starts[i, 1]),
                mu_kn=0.86,
                multipliers=True,
                sections=CLOUD_POINTS,
                chaos_after=CHAOS_AFTER,
            )
            assert (point.n, point.p) == (
                int(ds["n"].values.ravel()[i]),
                int(ds["p"].values.ravel()[i]),
            )
            kind = int(ds["kind"].values.ravel()[i])
            assert np.array_equal(
                record_points(kind, point.n, sections[i]), point.sections[: point.n]
            )
            assert np.array_equal(ds["state"].values.reshape(-1, 2)[i], point.state)


def reference_grouping(kinds, points, tol):
    """The census's rule record by record (each record against every group's first member),
    as ``group_records`` computed it before ``group_cells``: the oracle of the fast path."""
    members = []
    for i, (kind, pts) in enumerate(zip(kinds, points, strict=True)):
        if kind not in (Kind.PERIODIC, Kind.QUASIPERIODIC, Kind.CHAOTIC):
            continue
        for group in members:
            if same_record(kinds[group[0]], points[group[0]], kind, pts, tol):
                group.append(i)
                break
        else:
            members.append([i])
    return sorted(members, key=lambda g: (-len(g), g[0]))


def test_group_cells_is_the_record_by_record_rule_on_random_records():
    rng = np.random.default_rng(7)
    cycles = [rng.normal(size=(n, 2)) for n in (1, 2, 2, 3, 4)]
    cloud = rng.normal(size=(64, 2))
    kinds, ns, sections = [], [], np.full((400, 64, 2), np.nan)
    for i in range(400):
        pick = rng.integers(0, 8)
        if pick < 5:  # a cycle, shifted cyclically, with noise below or above the tolerance
            n = len(cycles[pick])
            noise = rng.choice([1e-7, 1e-3])
            sections[i, :n] = np.roll(cycles[pick], rng.integers(0, n), axis=0) + noise
            kinds.append(int(Kind.PERIODIC))
            ns.append(n)
        elif pick == 5:  # a sample of one chaotic cloud
            sections[i] = cloud[rng.permutation(64)] + rng.normal(scale=1e-3, size=(64, 2))
            kinds.append(int(Kind.CHAOTIC))
            ns.append(0)
        else:
            kinds.append(int(Kind.UNCONVERGED))
            ns.append(0)
    points = [record_points(k, n, s) for k, n, s in zip(kinds, ns, sections, strict=True)]
    groups, found = group_cells(kinds, ns, sections, 1e-5)
    assert [g.tolist() for g in groups] == reference_grouping(kinds, points, 1e-5)
    assert len(groups) > 6  # the noisy records above tolerance are attractors of their own
    assert (found[np.array(kinds) == Kind.UNCONVERGED] == -1).all()


@pytest.mark.parametrize("suffix", [".zarr", pytest.param(".h5", marks=pytest.mark.slow)])
def test_an_interrupted_basin_resumes_bitwise_and_both_backends_open_alike(
    basin, tmp_path, monkeypatch, suffix
):
    whole, job = basin
    path = tmp_path / f"resumed{suffix}"
    resume_after_interrupt(monkeypatch, job, path, 0)
    assert_same_store(stored(path), stored(whole))
    with campar.open(path) as a, campar.open(whole) as b:
        xr.testing.assert_identical(a.drop_attrs(), b.drop_attrs())


@pytest.mark.slow  # the basin fixture's serial reference, then mpirun
@pytest.mark.process
@pytest.mark.mpi
def test_a_basin_under_mpirun_equals_the_serial_one(basin, tmp_path):
    whole, _ = basin
    assert_mpirun_store_equals(BASIN, tmp_path, whole)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"fixed": {"omega": None}}, "fixes omega"),
        ({"chains": {"start": "continue"}}, "chains: a basin job's cells each start"),
        ({"initial": {"y": 0.5}}, "leave initial out"),
        ({"attractors": {"starts": 4}}, "leave attractors out"),
        ({"classify": {"sections": 4}}, "sections must be ≥ n_max"),
        ({"sweep": {"ydot0": {"from": 1, "to": 1, "points": 3}}}, "identical cells"),
    ],
)
def test_a_bad_basin_job_is_refused_naming_the_key(change, message):
    data = merge(BASIN, change)
    data["fixed"] = {k: v for k, v in data["fixed"].items() if v is not None}
    with pytest.raises(JobError, match=message):
        Job.from_dict(data)


def test_the_basin_figure_and_its_refusals(capsys, basin, tmp_path):
    path, _ = basin
    out = plot_store(path, output=tmp_path / "basin.png")
    assert out.stat().st_size > 10_000
    with pytest.raises(PlotError, match="basin store: it draws --what basin"):
        plot_store(path, "dc", output=tmp_path / "dc.png")
    result = call_campar(capsys, "plot", path, "--bifurcations", "-o", tmp_path / "b.png")
    assert result.returncode != 0 and "basin store" in result.stderr
    status = call_campar(capsys, "status", path)
    assert "6 ydot0 × 7 y0" in status.stdout
