"""The root record: it vouches for every variable, commit flag and tile checksum; its loss or
edit, and theirs, is damage that ``verify`` and ``campar.open`` report and a resume repairs;
a store written before it is refused until adopted. Stores of synthetic tiles (``damage``),
their numbers regenerated from their seeds (``fake_tile``) as the reference."""

import json
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest
from support.damage import synthetic_store
from test_store import fake_tile, make_job

import campar
import campar.sweep.store._schema as schema
from campar.cli import main
from campar.errors import StoreDamaged, StoreError, StoreMismatch
from campar.sweep.plan import plan_tiles
from campar.sweep.store import _hdf5, adopt_store, open_store, read_store, verify_store
from campar.sweep.store._metadata import attribute_changes
from campar.sweep.store._root import ZARR_FILE, Root, RootDamaged

MAIN_STORES = Path(__file__).parent / "data" / "main-stores"  # written by campar b09eab1
WRITTEN = (0, 2)  # the tiles those stores (and the stores here) hold, of 3


def written_store(tmp_path: Path, suffix: str) -> tuple[Path, object]:
    path = tmp_path / f"s{suffix}"
    return path, synthetic_store(path, tiles=set(WRITTEN))


def assert_holds(path: Path, tiles) -> None:
    """The store verifies clean, holds exactly ``tiles`` committed, each with the numbers
    ``fake_tile`` makes for it, and campar.open agrees."""
    job = make_job()
    with read_store(path) as reader:
        report = verify_store(reader)
        assert report.clean, report.lines()
        assert np.flatnonzero(report.verified).tolist() == list(tiles)
        for index in tiles:
            tile = plan_tiles(job)[index]
            for name, values in fake_tile(job, tile, index).items():
                assert np.array_equal(reader.read_tile(name, tile), values), (index, name)
    ds = campar.open(path)
    assert np.flatnonzero(ds["done"].values).tolist() == list(tiles)
    assert np.flatnonzero(campar.committed(path)).tolist() == list(tiles)


def resume(path: Path, job=None) -> list[int]:
    with open_store(path, job or make_job()) as store:
        return np.flatnonzero(store.done).tolist()


def main_store_job():
    """The job the stores of b09eab1 were made by: its warm start's order, 2, was the
    default then."""
    return make_job(transient__extrapolate=2)


# -- the record itself -------------------------------------------------------------------


def test_a_record_reads_back_and_its_digest_sees_every_field():
    root = Root(
        3, "0123456789abcdef", {"dc": "aa", "omega": "bb"}, np.array([0, 7, 2**64 - 1], np.uint64)
    )
    back = Root.decode(root.encode())
    assert back.checksums.tolist() == [0, 7, 2**64 - 1] and back.variables == root.variables
    assert back.committed.tolist() == [False, True, True] and back.digest == root.digest
    data = json.loads(root.encode())
    for key, value in [
        ("format", 2),
        ("job_hash", "0123456789abcdee"),
        ("variables", {"dc": "ab", "omega": "bb"}),
        ("checksums", Root(3, "x", {}, np.array([0, 8, 2**64 - 1], np.uint64)).encode()),
        ("tiles", 4),
    ]:
        edited = dict(
            data, **{key: json.loads(value)["checksums"] if key == "checksums" else value}
        )
        with pytest.raises(RootDamaged, match="digest"):
            Root.decode(json.dumps(edited))
    with pytest.raises(RootDamaged, match="newer"):
        Root.decode(json.dumps({**data, "campar_root": 99}))
    for text in ("", "[]", "{", root.encode()[:-5]):
        with pytest.raises(RootDamaged):
            Root.decode(text)


def test_zarr_commits_are_chained_lines_after_the_record_folded_at_close(tmp_path):
    job, path = make_job(), tmp_path / "s.zarr"
    tiles = plan_tiles(job)
    with open_store(path, job) as store:
        for tile in tiles[:2]:
            store.write_tile(tile, fake_tile(job, tile, tile.index))
        text = (path / ZARR_FILE).read_bytes()
        assert text.count(b"\n") == 3  # the record, then a line per commit
        assert campar.committed(path).tolist() == [True, True, False]
        head, first, second, _ = text.split(b"\n")
        assert Root.decode(text).problem is None
        cut = Root.decode(text + b"2 0000000000000abc 12")  # a kill cut the write short
        assert cut.committed.tolist() == [True, True, False] and cut.problem is None
        edited = first.replace(first.split(b" ")[1][:2], b"ff" if first[2:4] != b"ff" else b"ee")
        broken = Root.decode(b"\n".join([head, edited, second, b""]))
        assert broken.committed.tolist() == [False, False, False]
        assert "commit line 1 fails its chain" in broken.problem
    folded = (path / ZARR_FILE).read_bytes()
    assert folded.count(b"\n") == 1 and Root.decode(folded).committed.tolist() == [1, 1, 0]


# -- what the record vouches for: lost or edited, it is damage -------------------------


def set_chunk(path: Path, name: str, index: int, value) -> None:
    """Write one element of a per-tile array through zarr (as a careless hand would)."""
    import zarr

    zarr.open_group(path, mode="r+")[name][index] = value


def edit_group_json(path: Path, edit) -> None:
    document = json.loads((path / "zarr.json").read_text())
    edit(document)
    (path / "zarr.json").write_text(json.dumps(document))


# What only the root record itself can lose (the flags, checksums and metadata under it:
# test_damage's tables, the same readers).
ROOT_DAMAGE = {
    "root record deleted": (lambda p: (p / ZARR_FILE).unlink(), "root record is missing"),
    "root record edited": (
        lambda p: (p / ZARR_FILE).write_text(
            (p / ZARR_FILE).read_text().replace('"tiles": 3', '"tiles": 4')
        ),
        "root record is damaged",
    ),
    "metadata_checksums deleted": (
        lambda p: edit_group_json(p, lambda d: d["attributes"].pop("metadata_checksums")),
        "metadata_checksums (the variables' checksums) cannot be read",
    ),
}


@pytest.mark.parametrize("kind", list(ROOT_DAMAGE))
def test_a_lost_or_edited_root_record_is_found_and_written_anew(tmp_path, kind, capsys):
    path, _ = written_store(tmp_path, ".zarr")
    damage, said = ROOT_DAMAGE[kind]
    damage(path)
    assert main(["verify", str(path)]) == StoreDamaged.exit_code
    out = capsys.readouterr().out
    assert said in out, out
    if "root" in kind:  # nothing vouches for the flags: refused
        with pytest.raises(StoreDamaged, match="root record"):
            campar.open(path)
        with pytest.raises(StoreError, match="root record"):
            campar.committed(path)
    assert resume(path) == list(WRITTEN)  # the record written anew from what verifies
    assert_holds(path, WRITTEN)


def test_a_flag_set_on_a_pending_tile_is_pending_and_cleared(tmp_path, capsys):
    path, _ = written_store(tmp_path, ".zarr")
    set_chunk(path, "done", 1, 1)  # as a kill between a commit's flag and its record leaves
    assert main(["verify", str(path)]) == 0
    assert "which the root record holds pending" in capsys.readouterr().out
    assert campar.open(path)["done"].values.tolist() == [1, 0, 1]
    assert resume(path) == list(WRITTEN)
    with read_store(path) as reader:
        assert verify_store(reader).stray == [] and reader.tile_flags()[0].tolist() == [1, 0, 1]


def test_an_hdf5_record_covers_checkpointed_tiles_and_the_journal_the_rest(tmp_path):
    path, job = written_store(tmp_path, ".h5")
    with h5py.File(path, "r") as f:
        root = _hdf5.file_root(f.attrs)
        done = f["done"][:]
    assert root.committed.tolist() == done.astype(bool).tolist() == [True, False, True]
    with open_store(path, job) as store:  # tile 1 journaled, not checkpointed yet
        store.write_tile(plan_tiles(job)[1], fake_tile(job, plan_tiles(job)[1], 1))
        assert campar.committed(path).tolist() == [True, True, True]
        with read_store(path) as reader:
            assert verify_store(reader).clean and reader.root.committed.tolist() == [1, 0, 1]
    assert_holds(path, [0, 1, 2])


# -- stores written before the record: refused until adopted -----------------------------


@pytest.mark.parametrize("suffix", [".zarr", ".h5"])
def test_a_store_of_the_current_main_is_refused_until_adopted(
    tmp_path, suffix, capsys, monkeypatch
):
    path = tmp_path / f"old{suffix}"
    source = MAIN_STORES / f"written-by-b09eab1{suffix}"
    shutil.copytree(source, path) if source.is_dir() else shutil.copy(source, path)
    for command in (["verify", str(path)], ["status", str(path)]):
        assert main(command) == StoreError.exit_code
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "verify --adopt" in err[0], err
    with pytest.raises(StoreError, match="no root record"):
        campar.open(path)
    with pytest.raises(StoreMismatch, match="an earlier kernel"):  # said from its attributes
        resume(path, main_store_job())
    with monkeypatch.context() as patch:  # were its kernel this campar's: no root record
        patch.setattr(schema, "other_kernel", lambda attrs: None)
        with pytest.raises(StoreError, match="no root record"):
            resume(path, main_store_job())
    assert main(["verify", "--adopt", str(path)]) == 0
    assert "adopted" in capsys.readouterr().out
    assert_holds(path, WRITTEN)
    with pytest.raises(StoreError, match="nothing to adopt"):
        adopt_store(path)
    # adopted, it is read; an earlier kernel computed it (it records none): still not resumed
    with pytest.raises(StoreMismatch, match="an earlier kernel"):
        resume(path, main_store_job())
    assert_holds(path, WRITTEN)


def test_adoption_leaves_damaged_tiles_pending(tmp_path, capsys):
    path = tmp_path / "old.zarr"
    shutil.copytree(MAIN_STORES / "written-by-b09eab1.zarr", path)
    (path / "dc" / "c.2.0").unlink()  # tile 2's dc chunk
    assert main(["verify", "--adopt", str(path)]) == 0
    assert "tile 2" in capsys.readouterr().out
    assert_holds(path, [0])


# -- a rebuilt HDF5 store keeps its attributes' order --------------------------------------


def test_a_repaired_hdf5_store_keeps_its_attributes_in_order(tmp_path):
    path, job = written_store(tmp_path, ".h5")
    with open_store(path, job) as store:
        store.log_run({"outcome": "finished"})  # the run log and history: rewritten
    with h5py.File(path, "r") as f:
        before = list(f.attrs)
    fresh = tmp_path / "fresh.h5"
    _hdf5.build(fresh, job)
    with h5py.File(fresh, "r") as f:  # the order a store of this job is created in
        assert before == list(f.attrs)
    entry = _hdf5.journal_dir(path)
    entry.mkdir(exist_ok=True)
    (entry / "tile-000001.npz").write_bytes(b"not a zip")  # a damaged entry: a rebuild
    assert resume(path) == list(WRITTEN)
    with h5py.File(path, "r") as f:
        assert list(f.attrs) == before


def test_flag_masks_of_a_campar_with_fewer_flags_decode_alike():
    # the stores of b09eab1 hold six flag masks, this campar's flags seven: adopted as they
    # are (test_adoption_leaves_damaged_tiles_pending); masks not among the job's are not
    job = {"flag_masks": [1, 2, 4, 8, 16, 32, 64]}
    assert attribute_changes({"flag_masks": [1, 2, 4, 8, 16, 32]}, job, everything=False) == []
    changed = attribute_changes({"flag_masks": [1, 2, 128]}, job, everything=False)
    assert changed and "flag_masks" in changed[0]
    assert attribute_changes({"flag_masks": [1, 2]}, job, everything=True)  # a checksum's view
