"""The store in the ecosystem's language (CF-1.10, netCDF-4) and ``campar.open``.

Zarr and HDF5 stores of one job open to the same xarray Dataset, with xarray
alone and with ``campar.open``; codes decode with cf_xarray; netCDF tools read
the HDF5 file; stores of format 1 still open, and are never resumed.
"""

import json
import os
import shutil
import subprocess
import warnings

import h5py
import numpy as np
import pytest
import zarr
from support.jobs import reference_arrays
from test_store import fake_tile, make_job, snapshot
from zarr.errors import ZarrUserWarning

import campar
from campar.core.codes import KIND_NAMES, Flag, Kind, Status, cell_label
from campar.errors import StoreError, StoreMismatch
from campar.sweep.arrays import ARRAY_DOCS, TAIL_DIMS
from campar.sweep.job import Job
from campar.sweep.plan import plan_tiles
from campar.sweep.store import FORMAT, _schema, open_store, read_store
from campar.sweep.store._schema import cell_arrays, coordinates, versions
from campar.views.dataset import cell_labels

xr = pytest.importorskip("xarray")
pytest.importorskip("h5netcdf")

ALL_OUTPUTS = ["label", "dc", "eps", "pn", "sections", "multipliers", "lyapunov", "separation"]
CREATED = "2026-01-02T03:04:05+00:00"
RUN = {"start": CREATED, "end": CREATED, "tiles": 2, "ranks": 1, "outcome": "interrupted"}


@pytest.fixture(autouse=True)
def fixed_clock(monkeypatch):
    """Both stores of a comparison created "at the same time" (date_created, history)."""
    monkeypatch.setattr(_schema, "utc_now", lambda: CREATED)


def write_store(path, job: Job, tiles: dict[int, dict], log=True) -> None:
    with open_store(path, job) as store:
        for index, arrays in tiles.items():
            store.write_tile(plan_tiles(job)[index], arrays)
        if log:
            store.log_run(RUN)


def real_tiles(job: Job, indices) -> dict[int, dict]:
    """Tiles of the kernel's own results (so dtypes, NaNs and codes are real ones)."""
    whole = reference_arrays(job)
    return {i: {k: v[plan_tiles(job)[i].rows] for k, v in whole.items()} for i in indices}


@pytest.fixture(scope="module")
def real_job():
    return Job.from_dict(
        {
            "name": "cf_small",
            "sweep": {
                "omega": {"from": 6.0, "to": 1.0, "points": 8},
                "mu_cn": {"from": 0.9, "to": 0.6, "points": 5},
            },
            "classify": {"window_revolutions": 16, "sections": 4},
            "outputs": ALL_OUTPUTS,
            "tiles": {"rows": 2},
            "attractors": {"starts": 2, "cap": 2},  # every array a store can hold
        }
    )


@pytest.fixture
def stores(tmp_path, real_job):
    """A Zarr and an HDF5 store of one job, tiles 0 and 2 of 3 written, one run logged."""
    tiles = real_tiles(real_job, (0, 2))
    paths = tmp_path / "map.zarr", tmp_path / "map.h5"
    for path in paths:
        write_store(path, real_job, tiles)
    return paths


# -- the same Dataset from both backends ----------------------------------------------


def test_xarray_alone_opens_zarr_and_hdf5_stores_identically(stores):
    """Identical but for each store's checksums of its own variables' metadata: a Zarr
    document and an HDF5 dataset's properties are different bytes (``_metadata``); the
    HDF5 file holds its root record as an attribute, a Zarr store as a file of its own."""
    zarr_path, h5_path = stores
    with xr.open_zarr(zarr_path) as a, xr.open_dataset(h5_path, engine="h5netcdf") as b:
        assert json.loads(b.attrs.pop("campar_root").splitlines()[0])["campar_root"] == 1
        sums = [ds.attrs.pop("metadata_checksums") for ds in (a, b)]
        assert sums[0] != sums[1] and json.loads(sums[0]).keys() == json.loads(sums[1]).keys()
        xr.testing.assert_identical(a, b)
        assert a.attrs["runs"] == b.attrs["runs"] and "run interrupted" in a.attrs["history"]


def test_campar_open_gives_the_same_dataset_for_both_backends(stores, real_job):
    zarr_path, h5_path = stores
    with campar.open(zarr_path) as a, campar.open(h5_path) as b:
        xr.testing.assert_identical(a, b)
        for name in ("n", "p", "kind", "status", "flags", "revolutions", "steps"):
            assert a[name].dtype == cell_dtype(real_job, name), name  # codes stay integers
        whole = reference_arrays(real_job)
        rows = plan_tiles(real_job)[0].rows
        np.testing.assert_array_equal(a["kind"].values[rows], whole["kind"][rows])
        np.testing.assert_array_equal(a["sections"].values[rows], whole["sections"][rows])
        assert (a["n"].values[plan_tiles(real_job)[1].rows] == -1).all()  # not computed
        assert a["component"].dtype == b["component"].dtype == np.dtype("<U4")


def cell_dtype(job: Job, name: str) -> np.dtype:
    return next(a.dtype for a in cell_arrays(job) if a.name == name)


def test_campar_open_is_the_lazy_export():
    from campar.views import dataset

    assert campar.open is dataset.open


# -- what the store says about itself -------------------------------------------------


def test_every_variable_is_described_and_every_dimension_labelled(stores, real_job):
    with xr.open_zarr(stores[0]) as ds:
        assert set(ds.dims) <= set(ds.coords)
        for name, var in ds.variables.items():
            assert var.attrs.get("long_name"), name
        for name, (long_name, units, _) in ARRAY_DOCS.items():
            assert ds[name].attrs["long_name"] == long_name
            assert ds[name].attrs.get("units") == units
            assert ds[name].dims[2:] == TAIL_DIMS.get(name, ())
        for name in ("omega", "mu_cn", "f0", "mu_kn", "zeta"):
            assert ds[name].attrs["units"] == "1" and "ωn" in ds.attrs["comment"]
        assert ds["component"].values.tolist() == ["y", "ydot"]
        assert ds["tile_row_start"].values.tolist() == [t.row_start for t in plan_tiles(real_job)]
        assert ds["tile_row_stop"].values.tolist() == [t.row_stop for t in plan_tiles(real_job)]
        attrs = ds.attrs
        assert attrs["Conventions"] == "CF-1.10"
        assert attrs["title"] and attrs["source"].startswith("campar ")
        assert attrs["history"].splitlines()[0] == f"{CREATED} campar {campar.__version__}: " + (
            "created for job cf_small"
        )
        assert (attrs["tensile"], attrs["chain_start"], attrs["sweep_direction"]) == (
            "clamp",
            "rest",
            "down",
        )
        assert attrs["campar_version"] == campar.__version__ and attrs["campar_store"] == FORMAT
        assert json.loads(attrs["job"]) == real_job.to_dict()
        assert json.loads(attrs["versions"]) == versions()


def test_code_meanings_come_from_the_codes_module(stores):
    with campar.open(stores[1]) as ds:
        kind, status, flags = ds["kind"].attrs, ds["status"].attrs, ds["flags"].attrs
    assert kind["flag_values"].tolist() == [k.value for k in Kind]
    assert kind["flag_values"].dtype == np.int8  # CF: the variable's type
    assert kind["flag_meanings"].split() == [KIND_NAMES[k].replace(" ", "_") for k in Kind]
    assert status["flag_values"].tolist() == [s.value for s in Status]
    assert status["flag_meanings"].split() == [s.name.lower() for s in Status]
    assert flags["flag_masks"].tolist() == [f.value for f in Flag if f.value]
    assert flags["flag_meanings"].split() == [f.name.lower() for f in Flag if f.value]


def test_cf_xarray_decodes_kinds_and_flag_bits(stores):
    pytest.importorskip("cf_xarray")
    with campar.open(stores[0]) as ds:
        computed = ds["kind"] >= 0
        chaotic = ds["kind"].cf == "chaotic"
        assert (chaotic == (ds["kind"] == Kind.CHAOTIC)).all()
        bits = ds["flags"].where(computed, 0).cf.flags
        same = bits["newton"] == ((ds["flags"] & Flag.NEWTON) != 0)
        assert same.where(computed, True).all()
        assert set(bits) == {f.name.lower() for f in Flag if f.value}
        assert int((ds["status"].cf == "ok").sum()) == int(computed.sum())


def netcdf_dump() -> str | None:
    """The path of netCDF's ``ncdump``; as root with apt-get, netcdf-bin is installed first
    (Debian's package of the netCDF C tools: the reader every netCDF program shares)."""
    if shutil.which("ncdump") is None and os.geteuid() == 0 and shutil.which("apt-get"):
        env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
        for command in (
            ["apt-get", "install", "-y", "-q", "netcdf-bin"],
            ["apt-get", "update", "-q"],
            ["apt-get", "install", "-y", "-q", "netcdf-bin"],
        ):
            done = subprocess.run(command, capture_output=True, env=env, timeout=900)
            if done.returncode == 0 and shutil.which("ncdump"):
                break
    return shutil.which("ncdump")


@pytest.mark.process
def test_netcdf_tools_read_the_hdf5_store(stores):
    ncdump = netcdf_dump()
    if ncdump is None:
        why = "ncdump (netcdf-bin) is not installed, and could not be (root and apt-get needed)"
        if os.environ.get("CI") == "true":
            pytest.fail(why)
        pytest.skip(why)
    out = subprocess.run([ncdump, "-h", str(stores[1])], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    header = out.stdout
    assert "mu_cn = 5 ;" in header and "component = 2 ;" in header and "tile = 3 ;" in header
    assert "double state(mu_cn, omega, component) ;" in header
    assert 'kind:flag_meanings = "periodic quasi-periodic chaotic' in header
    assert ':Conventions = "CF-1.10" ;' in header
    data = subprocess.run([ncdump, "-v", "component", str(stores[1])], capture_output=True)
    assert b'component = "y", "ydot" ;' in data.stdout


# -- n-p labels -----------------------------------------------------------------------


def test_cell_labels_are_cell_label_of_every_cell():
    rng = np.random.default_rng(1)
    kind = rng.integers(-1, 6, size=(40, 30)).astype(np.int8)  # -1 not computed, 5 unknown
    n, p = rng.integers(0, 5, size=(2, 40, 30)).astype(np.int32)
    p[::3] += 6  # chattering ones
    got = cell_labels(kind, n, p, chatter_p=7)
    for k, a, b, label in zip(kind.flat, n.flat, p.flat, got.flat, strict=True):
        if k == -1:
            assert label == ""
        elif k == 5:
            assert label == "kind 5"
        else:
            assert label == cell_label(int(k), int(a), int(b), 7)
    assert cell_labels(np.array([np.nan, 0.0]), [1, 2], [1, 8]).tolist() == ["", "2-8~"]


def test_the_label_variable_uses_the_jobs_chatter_p(tmp_path):
    job = make_job(classify__chatter_p=3)
    tile = plan_tiles(job)[0]
    arrays = fake_tile(job, tile, 0)
    arrays["kind"][:] = Kind.PERIODIC
    arrays["n"][:], arrays["p"][:] = 2, 3
    write_store(tmp_path / "c.zarr", job, {0: arrays})
    with campar.open(tmp_path / "c.zarr") as ds:
        labels = ds["label"].values
    assert (labels[tile.rows] == "2-3~").all() and (labels[tile.row_stop :] == "").all()


# -- a run in progress ----------------------------------------------------------------


def test_campar_open_shows_tiles_an_hdf5_run_has_only_journaled(tmp_path):
    job, path = make_job(), tmp_path / "live.h5"
    tiles = plan_tiles(job)
    arrays = fake_tile(job, tiles[1], 1)
    with open_store(path, job) as store:
        store.write_tile(tiles[1], arrays)  # in the journal, not in the file yet
        with campar.open(path) as ds:
            assert ds["done"].values.tolist() == [0, 1, 0]
            np.testing.assert_array_equal(ds["sections"].values[tiles[1].rows], arrays["sections"])
            np.testing.assert_array_equal(ds["n"].values[tiles[1].rows], arrays["n"])
            assert (ds["n"].values[tiles[0].rows] == -1).all()
    with campar.open(path) as after:  # checkpointed at close: the same Dataset
        xr.testing.assert_identical(ds, after)


# -- older formats ----------------------------------------------------------------------

# Format 1, as campar wrote it before the CF metadata (commit e28cf64; checked once
# against that commit's own stores, which campar.open reads to the same Dataset as
# these): the tail dimension "var", done as bool, Zarr attributes nested, no
# attributes on arrays, HDF5 dimension scales only on omega and the second axis.
FORMAT1_TAIL = {"state": ("var",), "sections": ("section_point", "var")}


def write_format1(path, job: Job, tiles: dict[int, dict], runs: list[dict]) -> None:
    attrs = {
        "campar_store": 1,
        "job": job.to_dict(),
        "job_hash": job.digest(),
        "versions": versions(),
        "runs": runs,
    }
    h5 = path.suffix == ".h5"
    f = h5py.File(path, "w") if h5 else zarr.create_group(path, zarr_format=3)
    for key, value in attrs.items():
        f.attrs[key] = json.dumps(value) if h5 and key in ("job", "versions", "runs") else value
    for name, values in coordinates(job).items():
        if h5:
            f.create_dataset(name, data=values).make_scale(name)
        else:
            f.create_array(name, data=values, dimension_names=[name], fill_value=np.nan)
    done = np.zeros(len(plan_tiles(job)), bool)
    for a in cell_arrays(job):
        data = np.full(a.shape, a.fill, a.dtype)
        for index, arrays in tiles.items():
            data[plan_tiles(job)[index].rows] = arrays[a.name]
            done[index] = True
        dims = (*a.dims[:2], *FORMAT1_TAIL.get(a.name, a.dims[2:]))
        if h5:
            d = f.create_dataset(
                a.name, data=data, chunks=a.chunks, fillvalue=a.fill, compression="gzip"
            )
            for axis, dim in enumerate(dims):
                d.dims[axis].label = dim
                if dim in f:
                    d.dims[axis].attach_scale(f[dim])
        else:
            f.create_array(
                a.name, data=data, chunks=a.chunks, fill_value=a.fill, dimension_names=list(dims)
            )
    if h5:
        f.create_dataset("done", data=done, chunks=(1,)).dims[0].label = "tile"
        f.close()
    else:
        f.create_array("done", data=done, chunks=(1,), dimension_names=["tile"], compressors=None)
        with warnings.catch_warnings():  # consolidated metadata is not in the v3 spec
            warnings.simplefilter("ignore", ZarrUserWarning)
            zarr.consolidate_metadata(path)


@pytest.mark.parametrize("suffix", [".zarr", ".h5"])
def test_a_format1_store_opens_as_the_current_format_would(tmp_path, real_job, suffix):
    tiles = real_tiles(real_job, (1,))
    old, new = tmp_path / f"old{suffix}", tmp_path / f"new{suffix}"
    write_format1(old, real_job, tiles, [RUN])
    write_store(new, real_job, tiles)
    with read_store(old) as reader:  # campar status, plot: as before
        assert reader.format == 1 and reader.done.tolist() == [False, True, False]
    with campar.open(old) as a, campar.open(new) as b:
        assert a.attrs.pop("campar_store") == 1 and b.attrs.pop("campar_store") == FORMAT
        assert not a["checksum"].values.any()  # format 1 had no checksums
        xr.testing.assert_identical(a.drop_vars("checksum"), b.drop_vars("checksum"))


@pytest.mark.parametrize("suffix", [".zarr", ".h5"])
def test_a_format1_store_is_not_resumed_and_not_touched(tmp_path, suffix):
    job, path = make_job(), tmp_path / f"old{suffix}"
    write_format1(path, job, {0: fake_tile(job, plan_tiles(job)[0], 0)}, [])
    before = snapshot(path)
    expected = f"store format 1; this campar writes format {FORMAT}"
    with pytest.raises(StoreMismatch, match=expected) as e:
        open_store(path, job)
    assert "another --store path" in str(e.value) and "--overwrite" in str(e.value)
    assert snapshot(path) == before


def test_a_store_of_a_newer_format_is_refused_by_readers(tmp_path):
    job, path = make_job(), tmp_path / "future.zarr"
    write_store(path, job, {}, log=False)
    zarr.open_group(path, mode="r+").attrs["campar_store"] = 99
    for opener in (read_store, campar.open):
        with pytest.raises(StoreError, match="format 99.*newer campar"):
            opener(path)
