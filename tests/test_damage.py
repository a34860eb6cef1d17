"""The damage suite: a finished store of each layout (Zarr, HDF5) damaged as a careless hand,
a failing disk or another tool would — values edited, chunks swapped or deleted, metadata
deleted, coordinates and decoding attributes edited — and what every reader does with it:
``verify`` exits 65 naming it, ``status`` reports it, ``campar.open`` refuses (a damaged
variable) or reads the damaged tile as not computed with a warning, ``plot`` draws what
verified, and a resume repairs it bit for bit. Never a traceback, never a wrong value.

Stores of synthetic tiles (``fake_tile``): no kernel time."""

import json
import re
import shutil
import warnings

import h5py
import numpy as np
import pytest
import xarray as xr
import zarr
from support.damage import assert_synthetic, finish, synthetic_store
from test_store import fake_tile, make_job

import campar
from campar.cli import main
from campar.errors import StoreDamaged, StoreDamageWarning
from campar.sweep.plan import plan_tiles
from campar.sweep.store import open_store, read_store, verify_store
from campar.sweep.store._h5guard import USERBLOCK, file_state


def _edit_json(path, change):
    data = json.loads(path.read_text())
    change(data)
    path.write_text(json.dumps(data))


def _consolidated(store, name, change):
    _edit_json(store / "zarr.json", lambda d: change(d["consolidated_metadata"]["metadata"][name]))


def _flip(path, at):
    data = bytearray(path.read_bytes())
    data[at % len(data)] ^= 0x10
    path.write_bytes(bytes(data))


def _swap(a, b):
    tmp = a.with_name("swap")
    a.rename(tmp)
    b.rename(a)
    tmp.rename(b)


def _both(store, name, change):
    """An array's metadata changed alike in its own zarr.json and the consolidated copy."""
    _edit_json(store / name / "zarr.json", change)
    _consolidated(store, name, change)


def _big_endian(document):
    document["codecs"][0]["configuration"]["endian"] = "big"


def _chunk_shape(document):
    document["chunk_grid"]["configuration"]["chunk_shape"] = [1, 7]


def _zarr_set(store, name, index, value):
    array = zarr.open_array(store / name, mode="r+")
    array[index] = value


# (case, damage(store), damaged tiles, damaged variable or None). The tile cases keep every
# variable intact; the variable cases every tile.
ZARR_DAMAGE = [
    ("value edited through zarr", lambda s: _zarr_set(s, "dc", (0, 0), 0.125), [0], None),
    ("kind chunks swapped", lambda s: _swap(s / "n" / "c.0.0", s / "n" / "c.1.0"), [0, 1], None),
    ("a chunk deleted", lambda s: (s / "dc" / "c.1.0").unlink(), [1], None),
    ("a chunk's bit flipped", lambda s: _flip(s / "sections" / "c.2.0.0.0", 9), [2], None),
    ("dc/zarr.json deleted", lambda s: (s / "dc" / "zarr.json").unlink(), [], "dc"),
    ("n/zarr.json garbage", lambda s: (s / "n" / "zarr.json").write_text("{x"), [], "n"),
    (
        "scale_factor in the consolidated copy",
        lambda s: _consolidated(s, "dc", lambda m: m["attributes"].update(scale_factor=2.0)),
        [],
        "dc",
    ),
    (
        "add_offset in the array's own document",
        lambda s: zarr.open_array(s / "dc", mode="r+").attrs.update({"add_offset": 1.0}),
        [],
        "dc",
    ),
    (
        "_FillValue changed",
        lambda s: _consolidated(
            s, "dc", lambda m: m["attributes"].update(_FillValue="AAAAAAAA8D8=")
        ),
        [],
        "dc",
    ),
    (
        "units changed",
        lambda s: _consolidated(s, "omega", lambda m: m["attributes"].update(units="rad/s")),
        [],
        "omega",
    ),
    ("omega edited", lambda s: _zarr_set(s, "omega", 0, 5.5), [], "omega"),
    ("zeta edited", lambda s: _zarr_set(s, "zeta", 4, 0.31), [], "zeta"),
    ("a fixed parameter edited", lambda s: _zarr_set(s, "mu_kn", (), 0.5), [], "mu_kn"),
    ("tile_row_start edited", lambda s: _zarr_set(s, "tile_row_start", 1, 3), [], "tile_row_start"),
    ("omega's chunk bit flipped", lambda s: _flip(s / "omega" / "c.0", 3), [], "omega"),
    ("omega's chunk deleted", lambda s: (s / "omega" / "c.0").unlink(), [], "omega"),
    (
        "a global attribute edited",
        lambda s: zarr.open_group(s, mode="r+").attrs.update({"tensile": "allow"}),
        [],
        "(global attributes)",
    ),
    # The commit flags and the tiles' checksums, under the root record (``_root``).
    ("a done chunk deleted", lambda s: (s / "done" / "c.0").unlink(), [0], None),
    ("a done flag set to 0", lambda s: _zarr_set(s, "done", 2, 0), [2], None),
    ("a tile's checksum edited", lambda s: _zarr_set(s, "checksum", 1, 12345), [1], None),
    ("a checksum chunk deleted", lambda s: (s / "checksum" / "c.2").unlink(), [2], None),
    # An array's metadata, in both copies: the tiles are kept, read through the job's.
    ("p's data type", lambda s: _both(s, "p", lambda d: d.update(data_type="uint32")), [], "p"),
    ("p's shape", lambda s: _both(s, "p", lambda d: d.update(shape=[5, 8])), [], "p"),
    ("p's fill value", lambda s: _both(s, "p", lambda d: d.update(fill_value=7)), [], "p"),
    ("p's codecs", lambda s: _both(s, "p", lambda d: d.update(codecs=d["codecs"][:1])), [], "p"),
    ("p's byte order", lambda s: _both(s, "p", _big_endian), [], "p"),
    ("p's chunk shape", lambda s: _both(s, "p", _chunk_shape), [], "p"),
    ("p's Zarr format", lambda s: _both(s, "p", lambda d: d.update(zarr_format=2)), [], "p"),
    (
        "the group's Zarr format",
        lambda s: _edit_json(s / "zarr.json", lambda d: d.update(zarr_format=2)),
        [],
        "(global attributes)",
    ),
    (
        "the checksums attribute deleted, a long_name edited",
        lambda s: (
            _edit_json(s / "zarr.json", lambda d: d["attributes"].pop("metadata_checksums")),
            _consolidated(s, "dc", lambda m: m["attributes"].update(long_name="edited")),
        ),
        [],
        "dc",
    ),
    (
        "the checksums attribute garbage",
        lambda s: zarr.open_group(s, mode="r+").attrs.update({"metadata_checksums": "[1"}),
        [],
        None,
    ),
]
QUICK_ZARR = (
    "value edited through zarr",
    "a done chunk deleted",
    "p's data type",
    "kind chunks swapped",
    "dc/zarr.json deleted",
    "scale_factor in the consolidated copy",
    "omega edited",
)


def _h5_edit(store, change):
    with h5py.File(store, "r+") as f:
        change(f)


def _h5_unsealed(store, change):
    """Rewritten by another tool (no user block: no campar seal), and edited."""
    data = store.read_bytes()[USERBLOCK:]
    store.write_bytes(data)
    _h5_edit(store, change)


def _h5_scale(f):
    f["dc"].attrs["scale_factor"] = 2.0


# HDF5 damage: the file's seal (a digest of every byte) sees it all, and the file is read
# through a rescued copy of what verifies; an unsealed file is checked variable by variable.
HDF5_DAMAGE = [
    (
        "value edited through h5py",
        lambda s: _h5_edit(s, lambda f: f["dc"].__setitem__((0, 0), 0.125)),
        "file",
    ),
    ("scale_factor added", lambda s: _h5_edit(s, _h5_scale), "file"),
    ("omega edited", lambda s: _h5_edit(s, lambda f: f["omega"].__setitem__(0, 5.5)), "file"),
    (
        "_FillValue deleted",
        lambda s: _h5_edit(s, lambda f: f["dc"].attrs.__delitem__("_FillValue")),
        "file",
    ),
    ("a byte flipped near the end", lambda s: _flip(s, -9), "file"),
    ("unsealed, scale_factor added", lambda s: _h5_unsealed(s, _h5_scale), "dc"),
    (
        "unsealed, omega edited",
        lambda s: _h5_unsealed(s, lambda f: f["omega"].__setitem__(0, 5.5)),
        "omega",
    ),
]
QUICK_HDF5 = ("unsealed, scale_factor added",)  # a rescue in a child process takes seconds


def cases(table, quick, full=(pytest.mark.slow,)):
    """The table's cases as parameters, those not in ``quick`` in the full tier only (with
    the ``full`` marks)."""
    return [
        pytest.param(*case[1:], id=case[0], marks=() if case[0] in quick else full)
        for case in table
    ]


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    """pristine(path) -> Job: a finished store of synthetic tiles copied to ``path`` (its
    layout by the suffix), built once a module: each case damages a copy of its own."""
    folder = tmp_path_factory.mktemp("pristine")
    job = make_job()
    stores = {suffix: folder / f"s{suffix}" for suffix in (".zarr", ".h5")}
    for path in stores.values():
        synthetic_store(path, job)

    def copy(path):
        source = stores[path.suffix]
        shutil.copytree(source, path) if source.is_dir() else shutil.copy(source, path)
        return job

    return copy


def _verify_cli(path, capsys) -> str:
    assert main(["verify", str(path)]) == StoreDamaged.exit_code
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return out


def _status_cli(path, capsys) -> str:
    assert main(["status", str(path)]) == 0
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return out


def _plot_cli(path, tmp_path, capsys) -> None:
    figure = tmp_path / "map.png"
    code = main(["plot", str(path), "-o", str(figure)])
    out, err = capsys.readouterr()
    assert code == 0 and figure.stat().st_size > 0, err
    assert "Traceback" not in out + err


def _assert_open_is_the_job(path, job) -> None:
    """campar.open of a repaired store: the job's coordinates, the tiles' exact values."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no damage left to warn about
        ds = campar.open(path)
    np.testing.assert_array_equal(ds["omega"].values, job.first_values)
    np.testing.assert_array_equal(ds[job.second].values, job.second_values)
    for tile in plan_tiles(job):
        expected = fake_tile(job, tile, tile.index)
        for name in ("dc", "n", "sections"):
            assert np.array_equal(ds[name].values[tile.rows], expected[name], equal_nan=True)
    assert "scale_factor" not in ds["dc"].attrs and "add_offset" not in ds["dc"].attrs


@pytest.mark.parametrize("damage,tiles,variable", cases(ZARR_DAMAGE, QUICK_ZARR))
def test_damaged_zarr_store(tmp_path, capsys, pristine, damage, tiles, variable):
    path = tmp_path / "s.zarr"
    job = pristine(path)
    damage(path)

    report_text = _verify_cli(path, capsys)
    with read_store(path) as reader:
        report = verify_store(reader)
    assert sorted(report.damaged) == tiles, report.lines()
    assert list(report.variables) == ([variable] if variable else []), report.lines()
    if variable:
        assert f"variable {variable}:" in report_text
    elif not tiles:  # the checksums themselves unreadable: said, and checked against the job
        assert "cannot be read" in report_text
    assert "damage" in _status_cli(path, capsys)
    _plot_cli(path, tmp_path, capsys)

    if variable:
        with pytest.raises(StoreDamaged, match=re.escape(f"variable {variable}:")):
            campar.open(path)
    elif tiles:
        with pytest.warns(StoreDamageWarning, match="damaged tiles read as not computed"):
            ds = campar.open(path)
        for tile in plan_tiles(job):
            dc = ds["dc"].values[tile.rows]
            if tile.index in tiles:  # not computed: never the damaged numbers
                assert np.isnan(dc).all() and (ds["n"].values[tile.rows] == -1).all()
                assert ds["done"].values[tile.index] == 0
            else:
                assert np.array_equal(dc, fake_tile(job, tile, tile.index)["dc"])

    assert finish(path, job) == tiles  # a resume: variables rewritten, tiles recomputed
    assert_synthetic(path, job)  # verify_store clean, every tile's numbers
    _assert_open_is_the_job(path, job)


# The sealed file's cases whose edit is to a part a rescue does not read but rebuilds from the
# job (a variable's attribute or coordinate values): the seal fails before HDF5 reads a byte
# and every reader reads the rescued copy, the same path as "scale_factor added"'s, which
# test_damaged_hdf5_store takes through every reader; these two, through the seal and the
# repair (test_a_sealed_hdf5_store_edited_where_a_rescue_rebuilds_it).
REBUILT_HDF5 = ("omega edited", "_FillValue deleted")


# A damaged sealed file is rescued by campar's HDF5 guard in a child process.
@pytest.mark.parametrize(
    "damage,variable",
    cases(
        [case for case in HDF5_DAMAGE if case[0] not in REBUILT_HDF5],
        QUICK_HDF5,
        full=(pytest.mark.slow, pytest.mark.process),
    ),
)
def test_damaged_hdf5_store(tmp_path, capsys, pristine, damage, variable):
    path = tmp_path / "s.h5"
    job = pristine(path)
    damage(path)

    report_text = _verify_cli(path, capsys)
    if variable == "file":
        assert "HDF5 file is damaged" in report_text
    else:
        assert f"variable {variable}:" in report_text
    assert "damage" in _status_cli(path, capsys)
    _plot_cli(path, tmp_path, capsys)
    with pytest.raises(StoreDamaged):
        campar.open(path)

    finish(path, job)  # a resume rebuilds the file from what verified, sealed again
    assert_synthetic(path, job)  # verify_store clean, every tile's numbers
    _assert_open_is_the_job(path, job)


@pytest.mark.slow
@pytest.mark.process
@pytest.mark.parametrize(
    "damage", [pytest.param(c[1], id=c[0]) for c in HDF5_DAMAGE if c[0] in REBUILT_HDF5]
)
def test_a_sealed_hdf5_store_edited_where_a_rescue_rebuilds_it(tmp_path, pristine, damage):
    """The seal sees the edit (what verify, status, plot and campar.open report, read from
    ``file_state`` before HDF5 opens the file); a resume rebuilds the file, sealed again."""
    path = tmp_path / "s.h5"
    job = pristine(path)
    damage(path)
    state, _ = file_state(path)
    assert (
        state == "its bytes differ from those campar wrote (the digest in its user block disagrees)"
    )
    finish(path, job)
    assert file_state(path)[0] is None
    assert_synthetic(path, job)  # verify_store clean, every tile's numbers
    _assert_open_is_the_job(path, job)


def test_a_store_run_cannot_repair_is_said_so_by_verify_and_run_alike(tmp_path, capsys, pristine):
    """The group's own zarr.json unreadable: which job the store holds is unknown. verify
    says so (65), a run refuses alike (65), and nothing is deleted."""
    path = tmp_path / "s.zarr"
    job = pristine(path)
    (path / "zarr.json").write_text("{not json")
    assert main(["verify", str(path)]) == StoreDamaged.exit_code
    said = capsys.readouterr()
    assert "cannot tell which job" in said.err and said.err.count("\n") == 1
    with pytest.raises(StoreDamaged, match="cannot tell which job"):
        open_store(path, job)
    assert (path / "dc").is_dir() and (path / "zarr.json").read_text() == "{not json"


def test_campar_open_of_a_zarr_store_edited_after_the_check_still_raises_no_codec_error(
    tmp_path, pristine
):
    """What the issue saw: one bit flipped in omega's chunk made campar.open raise zarr's
    CRC32C ValueError; now it is StoreDamaged naming the variable."""
    path = tmp_path / "s.zarr"
    pristine(path)
    _flip(path / "omega" / "c.0", 3)
    with pytest.raises(StoreDamaged, match="variable omega: values unreadable"):
        campar.open(path)
    shutil.rmtree(path)


def test_raw_xarray_sees_what_campar_open_refuses(tmp_path, pristine):
    """The independent reference: xarray itself, reading the edited consolidated metadata,
    doubles every duty cycle — the silent error campar.open refuses."""
    path = tmp_path / "s.zarr"
    job = pristine(path)
    _consolidated(path, "dc", lambda m: m["attributes"].update(scale_factor=2.0))
    raw = xr.open_zarr(path)
    tile = plan_tiles(job)[0]
    np.testing.assert_allclose(raw["dc"].values[tile.rows], 2 * fake_tile(job, tile, 0)["dc"])
    with pytest.raises(StoreDamaged, match="attribute scale_factor added"):
        campar.open(path)


def test_plot_of_a_basin_store_with_a_flipped_bit_draws_it_and_names_the_tile(
    tmp_path, capsys, caplog
):
    """The issue's basin case: one bit flipped in kind's first chunk made `campar plot` exit 1
    with zarr's CRC traceback. Now the tile is drawn as not computed, said in one line."""
    import campar.sweep.runner as runner
    from campar.sweep.job import Job

    job = Job.from_dict(
        {
            "name": "basin_damage",
            "sweep": {
                "y0": {"from": -0.5, "to": 0.5, "points": 6},
                "ydot0": {"from": -1, "to": 1, "points": 4},
            },
            "fixed": {"omega": 3.0},
            "classify": {"window_revolutions": 16},
            "tiles": {"rows": 2},
        }
    )
    path = tmp_path / "basin.zarr"
    runner.run_job(job, path)
    _flip(path / "kind" / "c.0.0", 17)
    figure = tmp_path / "basin.png"
    assert main(["plot", str(path), "-o", str(figure)]) == 0
    out, err = capsys.readouterr()
    assert figure.stat().st_size > 0 and "Traceback" not in out + err
    assert "1 damaged tiles read as not computed (tile 0: kind unreadable" in caplog.text
