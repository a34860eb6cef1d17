"""A map's census of coexisting attractors (job key ``attractors``, ``campar.sweep.multistable``).

Every cell of such a map also runs K starts and its chain's end state through the kernel
and stores how many distinct attractors they reached, with the first ones' n, p, kind and
basin fraction. Checked against the known bistable cell (ω = 5.8, μkn = 0.86: 1-1 from
rest, 3-2 from another start, both confirmed by the independent SciPy model), a
monostable cell, ``find_attractors`` at the same cells, resume, MPI, both directions and
``campar.open``; a job without the key keeps its hash and its store's layout.
"""

from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from support.cli import call_campar
from support.jobs import computed_store, merge, resume_after_interrupt
from support.processes import MPIRUN, assert_mpirun_store_equals
from support.stores import assert_same_store, stored

import campar
import campar.sweep.runner as runner
from campar.bench.scipy_model import Model
from campar.bench.scipy_peer import scipy_cell
from campar.core.codes import Kind
from campar.errors import JobError
from campar.sweep.arrays import CENSUS_ARRAYS, array_names
from campar.sweep.census import group_records
from campar.sweep.job import Job, load_job
from campar.sweep.overrides import with_settings
from campar.sweep.plan import plan_tiles
from campar.sweep.store import store_arrays
from campar.sweep.tile import run_tile
from campar.views.attractors import find_attractors
from campar.views.plot import PlotError, plot_store

JOBS = Path(__file__).resolve().parents[1] / "jobs"
K, CAP = 8, 3
START_3_2 = (-0.35507, -2.29022)  # the start of the 3-2 cycle at the bistable cell
# 3 × 3 cells, one chain a tile: μkn 0.86 (bistable at ω = 5.8), 0.84, 0.82 (monostable).
GRID = {
    "name": "census",
    "sweep": {
        "omega": {"from": 5.9, "to": 5.7, "points": 3},
        "mu_kn": {"from": 0.86, "to": 0.82, "points": 3},
    },
    "tiles": {"rows": 1},
    "attractors": {"starts": K, "cap": CAP},
}
BISTABLE, MONOSTABLE = (0, 1), (2, 1)  # (row, column): (0.86, 5.8) and (0.82, 5.8)


# Session-wide: the test under mpirun that compares with it runs apart from the module's
# others (with the exclusive tests, tests/support/tiers.py), and would build it again.
@pytest.fixture(scope="session")
def census(tmp_path_factory):
    """The GRID map's store (Zarr) and its job."""
    return computed_store(tmp_path_factory, GRID)


def cell_census(path, row: int, col: int) -> dict:
    with campar.open(path) as ds:
        cell = ds.isel(mu_kn=row, omega=col)
        return {
            "n_attractors": int(cell.n_attractors),
            "unsettled": int(cell.unsettled_starts),
            "labels": [str(s) for s in cell.attractor_label.values],
            "fractions": cell.attractor_fraction.values,
            "omega": float(cell.omega),
            "mu_kn": float(cell.mu_kn),
        }


# -- the job key --------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ({"starts": 1}, "attractors.starts: Input should be greater than or equal to 2, got 1"),
        ({"cap": 2}, "attractors.starts: required key is missing"),
        ({"starts": 8, "cap": 0}, "attractors.cap: Input should be greater than or equal to 1"),
        ({"starts": 8, "basins": 1}, "attractors.basins: unknown key; allowed here: starts, cap"),
        (8, "attractors: must be a mapping of keys"),
    ],
)
def test_a_bad_attractors_key_is_one_line_naming_it(value, message):
    with pytest.raises(JobError) as err:
        Job.from_dict({**GRID, "attractors": value})
    assert message in str(err.value) and "\n" not in str(err.value)


def test_without_the_key_a_job_keeps_its_hash_and_its_store_layout():
    # jobs/smoke.yaml's hash before the key existed (campar d3f773f, whose warm start's
    # order was 2 by default): a job without the key hashes as it did then.
    smoke = with_settings(load_job(JOBS / "smoke.yaml"), {"transient.extrapolate": 2})
    assert smoke.digest() == SMOKE_HASH
    plain = Job.from_dict({k: v for k, v in GRID.items() if k != "attractors"})
    assert plain.attractors is None and "attractors" not in plain.to_dict()
    assert Job.from_dict(plain.to_dict()) == plain
    assert not set(CENSUS_ARRAYS) & set(array_names(plain))
    assert not any("attractor" in a.dims for a in store_arrays(plain))
    with_key = Job.from_dict(GRID)
    assert with_key.digest() != plain.digest()
    assert array_names(with_key) == [*array_names(plain), *CENSUS_ARRAYS]


SMOKE_HASH = "05ce13c35225c203"


def test_grouping_ranks_by_the_counted_starts_and_a_record_beyond_them_counts_nothing():
    one, other = np.array([[0.1, 0.2]]), np.array([[0.5, -0.3]])
    periodic, unconverged = int(Kind.PERIODIC), int(Kind.UNCONVERGED)
    kinds = [periodic, unconverged, periodic, periodic, periodic]
    points = [other, np.zeros((0, 2)), one, one + 1e-7, other + 1e-7]
    # records 0–3 are the starts; record 4 (the chain's) joins "other" but is not counted
    groups, basin = group_records(kinds, points, 1e-5, counted=4)
    assert groups == [[2, 3], [0, 4]]  # 2 starts before 1; ties would go by first member
    assert basin.tolist() == [1, -1, 0, 0, 1]
    groups, _ = group_records([periodic, periodic], [one, other], 1e-5, counted=1)
    assert groups == [[0], [1]]  # reached by the chain alone: ranked last


# -- the census of real cells ------------------------------------------------------------


def test_the_bistable_cell_shows_1_1_and_3_2_which_scipy_confirms(census):
    path, _ = census
    cell = cell_census(path, *BISTABLE)
    assert (cell["omega"], cell["mu_kn"]) == pytest.approx((5.8, 0.86))
    assert cell["n_attractors"] >= 2
    assert {"1-1", "3-2"} <= set(cell["labels"])
    # the independent model (SciPy DOP853, rtol 1e-10) from rest and from the start
    model = Model(cell["omega"], mu_kn=cell["mu_kn"])
    peers = [scipy_cell(model, x0, 60, 6, rtol=1e-10) for x0 in ((0.0, 0.0), START_3_2)]
    assert [p.label for p in peers] == ["1-1", "3-2"]


def test_a_monostable_cell_has_one_attractor_with_fraction_one(census):
    path, _ = census
    cell = cell_census(path, *MONOSTABLE)
    assert cell["n_attractors"] == 1 and cell["unsettled"] == 0
    assert cell["labels"] == ["1-1", "", ""]
    assert cell["fractions"][0] == 1.0 and np.isnan(cell["fractions"][1:]).all()


@pytest.mark.parametrize("where", [BISTABLE, MONOSTABLE, (1, 0)])
def test_each_cell_is_find_attractors_there_with_the_same_starts(census, where):
    """Same labels, same fractions, same order; the chain's end state may only add an
    attractor no start reached (fraction 0, last)."""
    path, _ = census
    cell = cell_census(path, *where)
    point = find_attractors(cell["omega"], count=K, mu_kn=cell["mu_kn"])
    labels = [a.label for a in point.attractors]
    fractions = [a.fraction for a in point.attractors]
    extra = cell["n_attractors"] - len(labels)
    assert extra in (0, 1)
    assert cell["labels"][: min(len(labels), CAP)] == labels[:CAP]
    assert list(cell["fractions"][: min(len(labels), CAP)]) == fractions[:CAP]
    if extra and len(labels) < CAP:
        assert cell["fractions"][len(labels)] == 0.0
    assert cell["unsettled"] == len(point.unsettled)
    assert sum(fractions) + cell["unsettled"] / K == pytest.approx(1.0)


def test_the_census_leaves_the_chain_s_own_arrays_as_they_were(census):
    _, job = census
    plain = Job.from_dict({k: v for k, v in GRID.items() if k != "attractors"})
    for tile in plan_tiles(job)[:2]:
        with_census, without = run_tile(job, tile), run_tile(plain, tile)
        for name, values in without.items():
            assert np.array_equal(with_census[name], values, equal_nan=True), name


def test_campar_open_offers_the_census_with_cf_attributes(census, tmp_path):
    path, job = census
    h5 = tmp_path / "census.h5"
    runner.run_job(job, h5)
    assert_same_store(
        {k: v for k, v in stored(h5).items()}, {k: v for k, v in stored(path).items()}
    )
    with campar.open(path) as ds, campar.open(h5) as other:
        assert list(ds["attractor"].values) == [1, 2, 3]
        assert ds["attractor_kind"].dims == ("mu_kn", "omega", "attractor")
        assert ds["n_attractors"].dims == ("mu_kn", "omega")
        assert ds["n_attractors"].dtype == np.int16
        kind = ds["attractor_kind"]
        assert "periodic" in kind.attrs["flag_meanings"]
        assert kind.attrs["long_name"] == "kind of the attractor"
        assert ds["attractor_fraction"].attrs["units"] == "1"
        for name in (*CENSUS_ARRAYS, "attractor_label"):
            assert "long_name" in ds[name].attrs, name
            np.testing.assert_array_equal(ds[name].values, other[name].values)
        # a label where an attractor is stored, "" beyond
        has = ds["attractor_kind"].values >= 0
        assert (ds["attractor_label"].values[has] != "").all()
        assert (ds["attractor_label"].values[~has] == "").all()
        assert ((ds["attractor_kind"].values == Kind.PERIODIC) == (ds["attractor_n"] > 0)).all()
        stored_count = np.minimum(ds["n_attractors"].values, 3)
        assert (has.sum(axis=-1) == stored_count).all()


def test_plot_multistability_draws_the_counts_and_refuses_a_store_without(capsys, census, tmp_path):
    path, _ = census
    out = plot_store(path, "multistability", tmp_path / "m.png")
    assert out.stat().st_size > 0
    plain = Job.from_dict({**{k: v for k, v in GRID.items() if k != "attractors"}})
    runner.run_job(plain, tmp_path / "plain.zarr")
    with pytest.raises(PlotError, match="holds no n_attractors.*attractors key"):
        plot_store(tmp_path / "plain.zarr", "multistability", tmp_path / "p.png")
    result = call_campar(capsys, "plot", path, "--what", "multistability", "-o", tmp_path / "c.png")
    assert result.returncode == 0, result.stderr


def test_status_and_the_set_map_count_each_set_of_coexisting_attractors(census, tmp_path):
    """The sets campar status lists and the set map's legend, against the attractor labels
    campar.open gives each cell (xarray's path through the store, sorted here)."""
    from campar.sweep.progress import describe
    from campar.sweep.store import read_store

    path, _ = census
    expected = Counter()
    with campar.open(path) as ds:
        for labels, count in zip(
            ds.attractor_label.values.reshape(-1, CAP),
            ds.n_attractors.values.reshape(-1),
            strict=True,
        ):
            if count >= 2:
                more = {"…"} if count > CAP else set()
                expected[frozenset({str(x) for x in labels if x} | more)] += 1
    assert expected[frozenset({"1-1", "3-2"})] >= 1  # the bistable cell's pair
    with read_store(path) as reader:
        (line,) = [x for x in describe(reader).splitlines() if x.startswith("sets")]
    listed = line.removeprefix("sets    ").split("  (cells where")[0].split(", ")
    shown = {frozenset(name.split(" + ")): int(c) for name, c in (x.rsplit(" ", 1) for x in listed)}
    assert shown == dict(expected)
    out = plot_store(path, "attractor_sets", tmp_path / "sets.png")
    assert out.stat().st_size > 0


def test_the_set_map_ignores_the_order_of_the_slots_and_marks_sets_beyond_the_cap():
    from campar.sweep.attractor_sets import attractor_sets
    from campar.views.plot import plot_map

    job = Job.from_dict(merge(GRID, {"sweep": {"mu_kn": {"points": 2}}}))
    kind = np.array(
        [[[0, 0, -1], [0, 0, -1], [0, -1, -1]], [[0, 0, 0], [0, 1, -1], [0, 0, 0]]], np.int8
    )
    n = np.array([[[1, 3, -1], [3, 1, -1], [1, -1, -1]], [[1, 3, 2], [1, 0, -1], [1, 3, 2]]])
    p = np.array([[[1, 2, -1], [2, 1, -1], [1, -1, -1]], [[1, 2, 2], [1, 0, -1], [1, 2, 2]]])
    count = np.array([[2, 2, 1], [3, 2, 5]], np.int16)
    codes, names = attractor_sets(kind, n, p, count)
    assert [names[c] for c in codes.reshape(-1)] == [
        "1-1 + 3-2",
        "1-1 + 3-2",
        "1-1",
        "1-1 + 2-2 + 3-2",
        "1-1 + QP",
        "1-1 + 2-2 + 3-2 + …",
    ]
    arrays = {"n_attractors": count, "attractor_kind": kind, "attractor_n": n, "attractor_p": p}
    figure = plot_map(job, arrays, "attractor_sets")
    entries = [t.get_text() for t in figure.axes[0].get_legend().get_texts()]
    assert entries[:2] == ["1 attractor (1)", "1-1 + 3-2 (2)"]  # the most frequent set first
    assert sorted(entries[2:]) == ["1-1 + 2-2 + 3-2 (1)", "1-1 + 2-2 + 3-2 + … (1)", "1-1 + QP (1)"]


def test_the_map_s_categories_are_1_2_3_4_or_more_and_not_computed():
    from campar.views.plot import plot_map

    job = Job.from_dict(merge(GRID, {"sweep": {"mu_kn": {"points": 2}}}))
    counts = np.array([[1, 1, 2], [3, 7, -1]], np.int16)  # -1: a tile not computed
    figure = plot_map(job, {"n_attractors": counts}, "multistability")
    entries = [t.get_text() for t in figure.axes[0].get_legend().get_texts()]
    assert entries == [
        "1 attractor (2)",
        "2 attractors (1)",
        "3 attractors (1)",
        "4 or more (1)",
        "not computed (1)",
    ]


# -- resume, ranks, directions ---------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".zarr", ".h5"])
def test_an_interrupted_census_map_resumes_bitwise(census, tmp_path, monkeypatch, suffix):
    whole, job = census
    path = tmp_path / f"resumed{suffix}"
    resume_after_interrupt(monkeypatch, job, path, 0)
    assert_same_store(stored(path), stored(whole))


def test_a_both_direction_map_has_a_census_per_direction_equal_to_each_one(tmp_path):
    data = merge(GRID, {"chains": {"direction": "both"}})
    both = Job.from_dict(data)
    runner.run_job(both, tmp_path / "both.zarr")
    with campar.open(tmp_path / "both.zarr") as ds:
        assert ds["n_attractors"].dims == ("direction", "mu_kn", "omega")
        assert ds["attractor_label"].dims == ("direction", "mu_kn", "omega", "attractor")
        for layer, direction in enumerate(("down", "up")):
            one = Job.from_dict(merge(data, {"chains": {"direction": direction}}))
            tiles = [run_tile(one, tile) for tile in plan_tiles(one)]
            for name in CENSUS_ARRAYS:
                expected = np.concatenate([t[name] for t in tiles])
                np.testing.assert_array_equal(ds[name].values[layer], expected)


@pytest.mark.slow
@pytest.mark.mpi
@pytest.mark.skipif(not MPIRUN.exists(), reason=f"no mpirun at {MPIRUN}")
@pytest.mark.process
def test_a_census_map_under_mpirun_equals_the_serial_one(census, tmp_path):
    serial, _ = census
    assert_mpirun_store_equals(GRID, tmp_path, serial)


def test_the_example_job_is_valid_and_asks_for_a_census():
    job = load_job(JOBS / "mu_kn_multistability.yaml")
    assert job.attractors is not None and job.attractors.starts >= 2
    omega, mu_kn = job.omega, job.second_values
    assert np.isclose(omega, 5.8).any() and np.isclose(mu_kn, 0.86).any()
