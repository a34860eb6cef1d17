"""Both sweep directions (``chains.direction: both``) and the hysteresis between them.

A ``both`` store must hold, bit for bit, what the down job and the up job it
combines compute separately, whatever the backend, interruptions or rank count;
it opens with a ``direction`` dimension and a ``hysteresis`` map decided by the
cycles themselves. The physical check is a line through a bistable region
(μkn = 0.86 around ω = 5.8, where `campar point` finds 1-1 from rest and 3-2
from another start), cross-checked with the independent SciPy model.
"""

import os
import signal

import numpy as np
import pytest
import xarray as xr
from support.cli import call_campar
from support.jobs import SMALL_JOB, merge
from support.processes import MPIRUN, assert_mpirun_store_equals
from support.stores import assert_same_store, stored

import campar
import campar.sweep.runner as runner
from campar.bench.scipy_model import Model
from campar.bench.scipy_peer import scipy_cell
from campar.core.codes import Kind, Status
from campar.errors import Interrupted, JobError, StoreMismatch
from campar.sweep.job import Job
from campar.sweep.plan import plan_tiles
from campar.sweep.progress import summarize
from campar.sweep.store import read_store
from campar.sweep.tile import run_tile
from campar.views.cycles import hysteresis_cells, same_cycles
from campar.views.dataset import cycle_tolerance, hysteresis
from campar.views.plot import PlotError, plot_store
from campar.views.point import simulate_point

# 6 × 24 cells a direction, 16-revolution read windows; two chains a tile.
GRID = merge(
    SMALL_JOB,
    {
        "sweep": {"omega": {"from": 6.0, "to": 1.0, "points": 24}},
        "tiles": {"rows": 2},
        "outputs": ["label", "dc", "sections"],
    },
)


def job_of(direction: str, **extra) -> Job:
    return Job.from_dict(
        merge(GRID, {"name": direction, "chains": {"direction": direction}, **extra})
    )


# -- the job and its tiles ----------------------------------------------------------


def test_a_both_job_stores_sections_and_refuses_bad_directions():
    job = Job.from_dict(merge(SMALL_JOB, {"chains": {"direction": "both"}}))
    assert job.wants("sections") and job.directions == ("down", "up")
    assert job.one_direction("up").chains.direction == "up"
    assert job.one_direction("up").to_dict()["outputs"] == job.to_dict()["outputs"]
    with pytest.raises(
        JobError,
        match=r"^job: chains.direction: Input should be 'down', 'up' or "
        "'both', got 'sideways'$",
    ):
        Job.from_dict(merge(SMALL_JOB, {"chains": {"direction": "sideways"}}))
    with pytest.raises(JobError, match="sections must be ≥ n_max or unset, got 8"):
        Job.from_dict(
            merge(SMALL_JOB, {"chains": {"direction": "both"}, "classify": {"sections": 8}})
        )
    # One-direction jobs are as before: no sections unless asked, no direction axis.
    assert not Job.from_dict(SMALL_JOB).wants("sections")


def test_tiles_of_a_both_job_run_every_row_range_down_then_up():
    tiles = plan_tiles(job_of("both"))
    assert [t.direction for t in tiles] == ["down"] * 3 + ["up"] * 3
    assert [t.index for t in tiles] == list(range(6))
    assert [(t.row_start, t.row_stop) for t in tiles[:3]] == [(0, 2), (2, 4), (4, 6)]
    assert [(t.row_start, t.row_stop) for t in tiles[3:]] == [(0, 2), (2, 4), (4, 6)]
    assert tiles[4].region == (1, slice(2, 4))
    assert [t.direction for t in plan_tiles(job_of("up"))] == [None] * 3  # as before


# -- the store: bitwise the two one-direction jobs, on both backends ----------------------


@pytest.mark.parametrize("suffix", [".zarr", pytest.param(".h5", marks=pytest.mark.slow)])
def test_a_both_store_is_the_down_and_the_up_store_bit_for_bit(capsys, tmp_path, suffix):
    paths = {d: tmp_path / f"{d}{suffix}" for d in ("both", "down", "up")}
    for direction, path in paths.items():
        assert runner.run_job(job_of(direction), path).outcome == "complete"
    both, down, up = (stored(paths[d]) for d in ("both", "down", "up"))
    for name in down:
        if name in ("checksum", "done"):  # per tile: the down tiles, then the up tiles
            expected = np.concatenate([down[name], up[name]])
        else:
            expected = np.stack([down[name], up[name]])
        assert both[name].dtype == expected.dtype, name
        assert np.array_equal(both[name], expected, equal_nan=True), name
    assert not np.array_equal(down["n"], up["n"])  # the directions do differ here

    ds = campar.open(paths["both"])
    assert ds["n"].dims == ("direction", "mu_cn", "omega")
    assert ds["label"].dims == ("direction", "mu_cn", "omega")
    assert ds["sections"].dims == ("direction", "mu_cn", "omega", "section_point", "component")
    assert ds["direction"].values.tolist() == ["down", "up"]
    assert ds["tile_direction"].values.tolist() == ["down"] * 3 + ["up"] * 3
    assert ds["hysteresis"].dims == ("mu_cn", "omega") and ds["hysteresis"].dtype == bool
    assert "never NaN" in ds["hysteresis"].attrs["comment"]
    assert ds.attrs["sweep_direction"] == "both"
    np.testing.assert_array_equal(ds["n"].sel(direction="up").values, up["n"])
    # the hysteresis map from the two one-direction stores' own arrays
    sides = [{k: s[k] for k in ("kind", "status", "n", "sections")} for s in (down, up)]
    expected = hysteresis_cells(*sides, cycle_tolerance(job_of("both")))
    np.testing.assert_array_equal(ds["hysteresis"].values, expected)
    assert expected.any() and not expected.all()

    raw = (
        xr.open_zarr(paths["both"])
        if suffix == ".zarr"
        else xr.open_dataset(paths["both"], engine="h5netcdf")
    )
    with raw:
        assert raw["kind"].dims == ("direction", "mu_cn", "omega")
        assert raw["direction"].values.tolist() == ["down", "up"]
        assert raw["direction"].attrs["long_name"] == "sweep direction of the chains"
        np.testing.assert_array_equal(hysteresis(raw).values, expected)  # from the raw store
    # one-direction stores keep their layout: no direction, no hysteresis
    single = campar.open(paths["down"])
    assert single["n"].dims == ("mu_cn", "omega")
    assert "direction" not in single.dims and "hysteresis" not in single

    with read_store(paths["both"]) as reader:
        status = summarize(reader)
    assert status["tiles"] == (6, 6) and status["cells"] == (288, 288)
    result = call_campar(capsys, "status", paths["both"])
    assert "tiles   6/6 done" in result.stdout and "each chain down and up" in result.stdout
    # labels per direction, each counting its own cells (from the down and up stores)
    assert list(status["labels"]) == ["down", "up"]
    for way in ("down", "up"):
        with read_store(paths[way]) as reader:
            assert status["labels"][way] == summarize(reader)["labels"][None]
        assert f"labels  ({way}) " in result.stdout
    assert call_campar(capsys, "verify", paths["both"]).returncode == 0


def test_a_both_store_refuses_the_one_direction_job_and_the_other_way(tmp_path):
    path = tmp_path / "both.zarr"
    runner.run_job(job_of("both"), path)
    with pytest.raises(StoreMismatch, match='chains.direction: "both" in the store, "down"'):
        runner.run_job(job_of("down"), path)
    runner.run_job(job_of("down"), tmp_path / "down.zarr")
    with pytest.raises(StoreMismatch, match="chains.direction"):
        runner.run_job(job_of("both"), tmp_path / "down.zarr")


# -- resume and rank count ------------------------------------------------------------------


def interrupt_at(monkeypatch, index: int) -> None:
    """SIGTERM this process while run_tile computes tile ``index``."""

    def tile_with_signal(job, tile):
        if tile.index == index:
            os.kill(os.getpid(), signal.SIGTERM)
        return run_tile(job, tile)

    monkeypatch.setattr(runner, "run_tile", tile_with_signal)


@pytest.mark.parametrize("suffix", [".zarr", ".h5"])
def test_a_both_run_interrupted_in_the_up_tiles_resumes_bitwise(tmp_path, monkeypatch, suffix):
    job = job_of("both", tiles={"rows": 1})  # 12 tiles: 6 down, 6 up
    whole = tmp_path / f"whole{suffix}"
    runner.run_job(job, whole)
    path = tmp_path / f"resumed{suffix}"
    interrupt_at(monkeypatch, 8)  # the third up tile
    with pytest.raises(Interrupted):
        runner.run_job(job, path)
    with read_store(path) as reader:
        done = reader.done
    assert done[:9].all() and not done.all()  # every down tile, some up ones: both layers
    monkeypatch.setattr(runner, "run_tile", run_tile)
    assert runner.run_job(job, path).outcome == "complete"
    assert_same_store(stored(path), stored(whole))


def damage_chunk(path, tile) -> None:
    """Spoil the chunk of array ``n`` that holds ``tile`` (of a both store: its direction's)."""
    if path.suffix == ".zarr":
        import zarr

        array = zarr.open_array(path / "n", mode="r")
        (
            path / "n" / array.metadata.encode_chunk_key((tile.layer, tile.row_start // 2, 0))
        ).unlink()
        return
    import h5py

    with h5py.File(path, "r") as f:  # where HDF5 keeps the chunk: flip a byte of it
        info = f["n"].id.get_chunk_info_by_coord((tile.layer, tile.row_start, 0))
    with open(path, "r+b") as fh:
        fh.seek(info.byte_offset + info.size // 2)
        byte = fh.read(1)
        fh.seek(info.byte_offset + info.size // 2)
        fh.write(bytes([byte[0] ^ 0xFF]))


# a damaged HDF5 file is read through campar's guard, a child process (_h5guard)
@pytest.mark.parametrize("suffix", [".zarr", pytest.param(".h5", marks=pytest.mark.process)])
def test_a_damaged_up_tile_is_found_and_recomputed_alone(capsys, tmp_path, suffix):
    job = job_of("both")
    path = tmp_path / f"both{suffix}"
    runner.run_job(job, path)
    before = stored(path)
    tile = plan_tiles(job)[4]  # rows 2–3, up
    damage_chunk(path, tile)
    result = call_campar(capsys, "verify", path)
    assert result.returncode == 65 and "tile 4:" in result.stdout, result.stdout
    assert "tile 1:" not in result.stdout  # the same rows down are intact
    summary = runner.run_job(job, path)
    assert summary.entry["tiles"] == 1  # tile 4 alone
    assert_same_store(stored(path), before)


def test_journaled_tiles_of_both_directions_read_in_place_before_a_checkpoint(tmp_path):
    from campar.sweep.store import open_store

    job = job_of("both")
    whole = tmp_path / "whole.h5"
    runner.run_job(job, whole)
    expected = stored(whole)
    path = tmp_path / "journal.h5"
    tiles = plan_tiles(job)
    with open_store(path, job) as store:
        for tile in (tiles[1], tiles[4], tiles[5]):  # committed to the journal only
            store.write_tile(tile, run_tile(job, tile))
        with read_store(path) as reader:
            assert reader.journaled.keys() == {1, 4, 5}
            n = reader.read("n")
        ds = campar.open(path)
    rows = slice(2, 4)
    np.testing.assert_array_equal(n[0, rows], expected["n"][0, rows])
    np.testing.assert_array_equal(n[1, 2:], expected["n"][1, 2:])
    assert (n[0, 4:] == -1).all() and (n[1, :2] == -1).all()  # not computed
    np.testing.assert_array_equal(ds["n"].values, n)


@pytest.mark.slow
@pytest.mark.mpi
@pytest.mark.skipif(not MPIRUN.exists(), reason=f"no mpirun at {MPIRUN}")
@pytest.mark.process
def test_a_both_map_under_mpirun_equals_the_serial_one(tmp_path):
    # Zarr, whose workers write their tiles of either direction themselves. An HDF5 store's
    # master writes every tile through the store's write_tile, a serial run's own path (the
    # both layout on HDF5: test_a_both_store_is_the_down_and_the_up_store_bit_for_bit), from
    # arrays that cross the wire as a one-direction tile's do (test_mpi's HDF5 map).
    data = merge(GRID, {"name": "mpi", "chains": {"direction": "both", "start": "continue"}})
    serial = tmp_path / "serial.zarr"
    runner.run_job(Job.from_dict(data), serial)
    assert_mpirun_store_equals(data, tmp_path, serial)


# -- the hysteresis rule on constructed cycles ---------------------------------------------

TOL = 1e-5
CYCLE = np.array([[0.1, -1.0], [0.4, 2.0], [-0.3, 0.5]])  # a 3-cycle's σn points


def cell(points, n=None, kind=Kind.PERIODIC, status=Status.OK, size=8) -> dict:
    """One cell's arrays as a store holds them: σn points NaN-padded to ``size``."""
    sections = np.full((1, size, 2), np.nan)
    sections[0, : len(points)] = points
    n = len(points) if n is None else n
    return {
        "kind": np.array([kind], np.int8),
        "status": np.array([status], np.int8),
        "n": np.array([n], np.int32),
        "sections": sections,
    }


def hysteretic(a: dict, b: dict) -> bool:
    return bool(hysteresis_cells(a, b, TOL)[0])


def test_a_cyclic_shift_of_one_cycle_is_no_hysteresis():
    for shift in range(3):
        assert not hysteretic(cell(CYCLE), cell(np.roll(CYCLE, shift, axis=0)))
    noise = 0.4 * TOL * np.array([[1, -1], [-1, 1], [1, 1]])
    assert not hysteretic(cell(CYCLE), cell(np.roll(CYCLE, 1, axis=0) + noise))
    # a 2-cycle whose points coincide (within the tolerance) is the 1-cycle it repeats
    point = CYCLE[:1]
    assert not hysteretic(cell(point), cell(np.vstack([point, point + 0.5 * TOL])))


def test_a_different_cycle_is_hysteresis():
    assert hysteretic(cell(CYCLE), cell(CYCLE + 3 * TOL))  # just beyond the tolerance
    assert hysteretic(cell(CYCLE), cell(CYCLE[::-1]))  # same points, other order
    assert hysteretic(cell(CYCLE), cell(CYCLE[:1]))  # a 1-cycle at one of its points
    assert hysteretic(cell(CYCLE[:2]), cell(CYCLE[:1]))


def test_cells_not_periodic_both_ways_are_never_hysteretic():
    other = cell(CYCLE[:1] + 1.0)
    for kind in (Kind.QUASIPERIODIC, Kind.CHAOTIC, Kind.UNCONVERGED, Kind.FAILED, -1):
        assert not hysteretic(cell(CYCLE, n=0, kind=kind), other)
        assert not hysteretic(other, cell(CYCLE, n=0, kind=kind))
    assert not hysteretic(cell(CYCLE, status=Status.STEP_LIMIT), other)
    assert not hysteretic(cell(np.full((3, 2), np.nan)), other)  # cycle not recorded
    assert not hysteretic(cell(CYCLE, n=9), other)  # longer than the points stored


def test_same_cycles_compares_every_cell_with_its_own_pair():
    a = np.stack([cell(CYCLE)["sections"][0], cell(CYCLE[:2])["sections"][0]])
    b = np.stack([cell(np.roll(CYCLE, 2, axis=0))["sections"][0], cell(CYCLE[1:])["sections"][0]])
    np.testing.assert_array_equal(same_cycles([3, 2], a, [3, 2], b, TOL), [True, False])


def test_the_tolerance_is_the_cycles_own_accuracy():
    job = job_of("both")
    assert cycle_tolerance(job) == pytest.approx(1e-5)  # 5 × 2 × window_tol 1e-6
    loose = job_of("both", integrator={"rtol": 1e-5})
    assert cycle_tolerance(loose) == pytest.approx(5e-5)


# -- figures -------------------------------------------------------------------------------


def test_plot_draws_hysteresis_and_either_direction(capsys, tmp_path):
    both, down = tmp_path / "both.zarr", tmp_path / "down.zarr"
    runner.run_job(job_of("both"), both)
    runner.run_job(job_of("down"), down)
    for what, direction in (("hysteresis", None), ("labels", "up"), ("dc", None)):
        out = plot_store(both, what, tmp_path / f"{what}.png", direction=direction)
        assert out.stat().st_size > 1000
    with pytest.raises(PlotError, match="needs a store of a chains.direction: both job"):
        plot_store(down, "hysteresis", tmp_path / "x.png")
    with pytest.raises(PlotError, match="ran down only; it has no up map"):
        plot_store(down, "labels", tmp_path / "x.png", direction="up")
    result = call_campar(capsys, "plot", both, "--what", "hysteresis", "-o", tmp_path / "h.png")
    assert result.returncode == 0 and (tmp_path / "h.png").exists(), result.stderr


# -- physics: a bistable region, cross-checked with SciPy -------------------------------------

# `campar point --omega 5.8 --mu-kn 0.86` reaches 1-1 from rest and 3-2 from
# (y, ẏ) = (−0.35507, −2.29022). A corner of the μkn plane through that cell, by the
# paper's 2-D continuation: down carries the 3-cycles of the plane's corner (6.0, 0.96)
# into it, up arrives on the 1-1 of low ω.
BISTABLE = {
    "name": "bistable",
    "sweep": {
        "omega": {"from": 6.0, "to": 5.0, "points": 11},
        "mu_kn": {"from": 0.96, "to": 0.86, "points": 6},
    },
    "chains": {"direction": "both", "start": "continue"},
    "tiles": {"rows": 2},
}
OTHER_START = {"y0": -0.35507, "v0": -2.29022}


@pytest.fixture(scope="module")
def bistable(tmp_path_factory):
    path = tmp_path_factory.mktemp("bistable") / "bistable.zarr"
    runner.run_job(Job.from_dict(BISTABLE), path)
    return campar.open(path).load()


def test_the_known_bistable_cell_is_hysteretic_with_campar_point_s_two_cycles(bistable):
    cell = bistable.sel(omega=5.8, mu_kn=0.86, method="nearest")
    assert (float(cell["omega"]), float(cell["mu_kn"])) == pytest.approx((5.8, 0.86))
    assert cell["label"].values.tolist() == ["3-2", "1-1"]  # down, up
    assert bool(cell["hysteresis"])
    tol = cycle_tolerance(Job.from_dict(BISTABLE))
    for direction, start in (("down", OTHER_START), ("up", {})):
        alone = simulate_point(5.8, mu_kn=0.86, **start)  # one cell, its own start
        side = cell.sel(direction=direction)
        n = int(side["n"])
        assert alone.n == n
        assert same_cycles([n], alone.sections[None, :n], [n], side["sections"].values[None], tol)
    h = bistable["hysteresis"].values
    assert 0.3 < h.mean() < 1  # a band, not the whole corner
    assert not h[:, -3:].any()  # at ω ≤ 5.2 both directions are on 1-1


@pytest.mark.slow
def test_each_direction_s_cycle_of_the_hysteretic_cells_is_an_attractor_by_scipy(bistable):
    """From each direction's stored state, the SciPy model (rtol 1e-10, none of campar's
    numerics) settles on that direction's cycle again, with its n-p, and the two differ."""
    row = bistable.sel(mu_kn=0.86, method="nearest")
    cells = np.flatnonzero(row["hysteresis"].values)
    assert len(cells) >= 5
    for i in cells:
        omega = float(row["omega"][i])
        cycles = {}
        for direction in ("down", "up"):
            d = row.sel(direction=direction)
            n = int(d["n"][i])
            peer = scipy_cell(
                Model(omega, mu_kn=float(row["mu_kn"])),
                d["state"].values[i],
                40,
                2 * n + 4,
                rtol=1e-10,
            )
            assert peer.label == f"{n}-{int(d['p'][i])}", (omega, direction)
            cycle = peer.sections[-n:]
            assert same_cycles([n], cycle[None], [n], d["sections"].values[i][None, :n], 1e-5)[0]
            cycles[direction] = cycle
        size = max(len(c) for c in cycles.values())  # σn points NaN-padded alike
        a, b = (np.vstack([c, np.full((size - len(c), 2), np.nan)])[None] for c in cycles.values())
        assert not same_cycles([len(cycles["down"])], a, [len(cycles["up"])], b, 1e-3)[0], omega
