"""Integrity: every committed tile carries a checksum; verify finds damage, status reports it,
a resume recomputes it. Stores of synthetic tiles (no kernel time) on both backends."""

import json
import os
from pathlib import Path

import numpy as np
import pytest
import zarr
from support.cli import call_campar
from support.damage import assert_synthetic, damage_file, finish, synthetic_store, zarr_chunks
from support.jobs import assert_same_map
from test_store import fake_tile, make_job

import campar
import campar.sweep.runner as runner
from campar.errors import StoreDamaged, StoreError
from campar.sweep.arrays import array_names
from campar.sweep.plan import plan_tiles
from campar.sweep.progress import summarize, verify_report
from campar.sweep.store import _hdf5 as h5
from campar.sweep.store import open_store, read_store, tile_checksum, verify_store
from campar.sweep.store._h5guard import USERBLOCK, file_state


def test_a_checksum_sees_every_byte_name_dtype_and_shape():
    job = make_job()
    tile = plan_tiles(job)[0]
    arrays, names = fake_tile(job, tile, 0), array_names(job)
    reference = tile_checksum(arrays, names)
    assert reference == tile_checksum({k: v.copy() for k, v in arrays.items()}, names)
    assert 0 < reference < 2**64
    flipped = {**arrays, "dc": arrays["dc"].copy()}
    flipped["dc"].reshape(-1).view(np.uint8)[5] ^= 1
    assert tile_checksum(flipped, names) != reference
    retyped = {**arrays, "n": arrays["n"].astype(np.int64)}
    assert tile_checksum(retyped, names) != reference
    reshaped = {**arrays, "dc": arrays["dc"].reshape(-1)}
    assert tile_checksum(reshaped, names) != reference
    assert tile_checksum(arrays, names[::-1]) != reference  # order matters: the store's


@pytest.fixture(params=[".zarr", ".h5"])
def store(request, tmp_path):
    path = tmp_path / f"s{request.param}"
    return path, synthetic_store(path)


def test_a_whole_store_verifies(store):
    path, job = store
    with read_store(path) as reader:
        report = verify_store(reader)
    assert report.clean and report.checksums and report.committed == [0, 1, 2]
    text, intact = verify_report(path)
    assert intact and "3 committed tiles (checksums)" in text and "all intact" in text


@pytest.mark.parametrize("how", ["delete", "truncate", "flip"])
def test_a_damaged_zarr_chunk_is_found_reported_and_recomputed(tmp_path, how):
    path = tmp_path / "s.zarr"
    job = synthetic_store(path)
    rng = np.random.default_rng(len(how))
    n_chunk = [f for f in zarr_chunks(path, job, 1) if f.parent.name == "n"][0]
    damage_file(n_chunk, how, rng)
    with read_store(path) as reader:
        report = verify_store(reader)
        counts = summarize(reader)
    assert list(report.damaged) == [1], report.lines()
    if how == "delete":
        assert "only fill values in n" in report.damaged[1]
    assert counts["tiles"] == (2, 3) and list(counts["damaged"]) == [1]
    with open_store(path, job) as resumed:  # the damaged tile is pending again, its cells fill
        assert resumed.done.tolist() == [True, False, True]
    with read_store(path) as reader:
        assert (reader.read_rows("n", plan_tiles(job)[1].rows) == -1).all()
        assert verify_store(reader).clean  # nothing left that claims to be done and is not
    assert finish(path, job) == [1]
    assert_synthetic(path, job)


def test_a_damaged_done_flag_or_checksum_makes_the_tile_pending(tmp_path):
    path = tmp_path / "s.zarr"
    job = synthetic_store(path)
    (path / "done" / "c.0").write_bytes(b"")  # truncated: the flag cannot be read
    zarr.open_group(path, mode="r+")["done"][2] = 7  # neither 0 nor 1 (a valid chunk)
    (path / "checksum" / "c.1").write_bytes(b"\0" * 3)
    with read_store(path) as reader:
        report = verify_store(reader)
        assert not reader.done[0] and not reader.done[2]
    assert sorted(report.damaged) == [0, 1, 2]
    assert "done unreadable" in report.damaged[0] and "holds 7" in report.damaged[2]
    assert finish(path, job) == [0, 1, 2]
    assert_synthetic(path, job)


def test_a_pending_tile_with_stray_chunks_is_not_damage(tmp_path):
    """A kill between a tile's arrays and its flag: pending, not damaged."""
    path = tmp_path / "s.zarr"
    job = synthetic_store(path, tiles={0})
    group = zarr.open_group(path, mode="r+")
    group["n"][plan_tiles(job)[1].rows] = 5  # arrays written, no checksum, no flag
    with read_store(path) as reader:
        report = verify_store(reader)
    assert report.clean and report.committed == [0]
    with open_store(path, job):  # a resume clears them: outside done tiles, only the fill
        pass
    with read_store(path) as reader:
        assert (reader.read_rows("n", plan_tiles(job)[1].rows) == -1).all()


@pytest.mark.process  # campar's HDF5 guard reads a damaged file in a child
def test_hdf5_damage_anywhere_in_the_file_is_seen_before_hdf5_reads_it(tmp_path):
    path = tmp_path / "s.h5"
    job = synthetic_store(path)
    assert file_state(path)[0] is None
    size = path.stat().st_size
    with open(path, "r+b") as fh:  # a bit deep in the file, a byte HDF5 may never read
        fh.seek(size - 7)
        byte = fh.read(1)
        fh.seek(size - 7)
        fh.write(bytes([byte[0] ^ 4]))
    assert "differ" in file_state(path)[0]
    with read_store(path) as reader:  # read through a rescued copy
        report = verify_store(reader)
    assert any("HDF5 file is damaged" in p for p in report.problems)
    assert not report.clean
    with pytest.raises(StoreDamaged, match="HDF5 file is damaged"):
        campar.open(path)  # xarray would hand the damaged file to HDF5 itself
    finish(path, job)  # a resume rebuilds the file from the tiles that verified
    assert file_state(path)[0] is None
    assert_synthetic(path, job)


@pytest.mark.slow  # two rescues in child processes, ~3 s
@pytest.mark.process
def test_hdf5_zeroed_user_block_and_zeroed_start_are_named(tmp_path):
    path = tmp_path / "s.h5"
    job = synthetic_store(path)
    with open(path, "r+b") as fh:
        fh.write(bytes(USERBLOCK))
    assert "user block" in file_state(path)[0]
    finish(path, job)
    assert_synthetic(path, job)
    with open(path, "r+b") as fh:
        fh.write(bytes(4096))  # the HDF5 signature gone too
    with pytest.raises(StoreDamaged, match="zeroed bytes.*never deletes"):
        read_store(path)
    with pytest.raises(StoreDamaged):
        open_store(path, job)
    assert path.exists()  # never deleted


@pytest.mark.process  # campar's HDF5 guard reads a damaged file in a child
def test_a_truncated_hdf5_store_is_called_damaged_not_foreign(tmp_path):
    path = tmp_path / "s.h5"
    synthetic_store(path)
    with open(path, "r+b") as fh:
        fh.truncate(path.stat().st_size // 2)
    with pytest.raises(StoreDamaged, match="damaged"):
        read_store(path)


@pytest.mark.parametrize("how", ["truncate", "flip", "garbage"])
def test_a_damaged_journal_entry_is_set_aside_and_its_tile_recomputed(tmp_path, how):
    path = tmp_path / "s.h5"
    job = make_job()
    h5.CHECKPOINT_TILES, saved = 1000, h5.CHECKPOINT_TILES
    try:
        store = open_store(path, job)
        for tile in plan_tiles(job):
            store.write_tile(tile, fake_tile(job, tile, tile.index))
        store._lock.release()  # as a killed writer leaves it: journal only, no checkpoint
    finally:
        h5.CHECKPOINT_TILES = saved
    entry = h5.journal_entries(path)[1]
    if how == "garbage":
        entry.write_bytes(os.urandom(200))
    else:
        damage_file(entry, how, np.random.default_rng(3))
    with read_store(path) as reader:
        report = verify_store(reader)
    assert list(report.damaged) == [1] and "journal entry tile-000001.npz" in report.damaged[1]
    assert finish(path, job) == [1]
    aside = [p.name for p in h5.journal_dir(path).iterdir()]
    assert len(aside) == 1 and aside[0].startswith("tile-000001.npz.damaged-")
    assert_synthetic(path, job)


def test_metadata_that_disagrees_with_the_arrays_is_reported_not_an_index_error(capsys, tmp_path):
    path = tmp_path / "s.zarr"
    synthetic_store(path)
    group = zarr.open_group(path, mode="r+")
    stored = json.loads(group.attrs["job"])
    stored["sweep"]["zeta"]["points"] = 9  # the hash no longer matches, the arrays neither
    group.attrs["job"] = json.dumps(stored)
    with pytest.raises(StoreDamaged, match="disagrees with itself.*hash.*array n has shape"):
        read_store(path)
    status = call_campar(capsys, "status", path)
    assert status.returncode == StoreDamaged.exit_code, status.stderr
    assert "Traceback" not in status.stderr and len(status.stderr.splitlines()) == 1


def test_status_reports_damage_and_verify_lists_it_then_run_repairs(capsys, write_job, caplog):
    """The issue's recipe: chunks deleted from a finished store (the CLI reads it)."""
    _, job = write_job(tiles={"rows": 2})
    runner.run_job(job)
    path = Path(job.store)
    for name, index in (("n", 1), ("dc", 2)):
        (path / name / f"c.{index}.0").unlink()  # rm S.zarr/n/c.1.0 …
    status = call_campar(capsys, "status", path)
    assert status.returncode == 0, status.stderr
    assert "tiles   1/3 done, 2 damaged (tiles 1, 2" in status.stdout
    verify = call_campar(capsys, "verify", path)
    assert verify.returncode == StoreDamaged.exit_code
    assert "tile 1: checksum mismatch" in verify.stdout and "tile 2: checksum" in verify.stdout
    assert runner.run_job(job).outcome == "complete"
    assert "tile 1 is damaged" in caplog.text and "computed again" in caplog.text
    with read_store(path) as reader:
        assert_same_map(reader, job)
        assert verify_store(reader).clean


def test_stores_of_older_formats_are_checked_for_readability(tmp_path):
    path = tmp_path / "s.zarr"
    synthetic_store(path)
    group = zarr.open_group(path, mode="r+")
    group.attrs["campar_store"] = 2
    with read_store(path) as reader:
        report = verify_store(reader)
    assert report.clean and not report.checksums
    group["kind"][0:1] = -1  # a committed tile holding uncomputed cells
    with read_store(path) as reader:
        assert "never written in kind" in verify_store(reader).damaged[0]
    with pytest.raises(StoreError, match="format 2"):
        open_store(path, make_job())
