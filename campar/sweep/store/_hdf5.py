"""HDF5 backend (a path ending .h5 or .hdf5): one file with the Zarr store's names.

HDF5 from PyPI is serial and not crash-safe: a process killed while the
library updates a file can leave it unreadable, finished tiles and all. So a
run never modifies the store file in place:

1. a finished tile goes to the journal first, ``<store>.journal/tile-000012.npz``,
   written aside and renamed, so an entry is whole or absent — this is the
   tile's commit;
2. at a checkpoint (every ``CHECKPOINT_TILES`` tiles or ``CHECKPOINT_SECONDS``,
   and at close) the file is copied, the journal applied to the copy (arrays,
   then ``done``), the copy flushed, fsynced and renamed over the store, and
   only then are the applied entries deleted.

A kill at any point leaves the last checkpoint plus whole journal entries;
the next ``open_store`` replays them, and readers overlay them, so
``campar status`` counts every finished tile even during a run. Replaying is
idempotent (an entry holds the same numbers as the file), so a kill between
the rename and the deletions loses nothing either.

The file is a netCDF-4 file (what netCDF-C and h5netcdf read): every coordinate
of a dimension is an HDF5 dimension scale named after it (with
``_Netcdf4Dimid``, its order), every axis of every other variable has its scale
attached, ``_FillValue`` is an attribute of the variable's type equal to the
HDF5 fill value, and creation order is tracked so tools list variables in the
Zarr store's order. Checkpoints only write into existing datasets and
attributes, which keeps that structure.
"""

import contextlib
import os
import re
import shutil
import time
from pathlib import Path

import h5py
import numpy as np

from ..job import Job
from ..plan import Tile, plan_tiles
from ._base import Store, StoreReader
from ._lock import StoreLock
from ._schema import ArraySchema, decode_attrs, initial_attrs, run_attrs, store_arrays

CHECKPOINT_TILES = 64
CHECKPOINT_SECONDS = 60.0
ENTRY = re.compile(r"^tile-(\d+)\.npz$")


def journal_dir(path: Path) -> Path:
    return path.with_name(path.name + ".journal")


def read_attrs(path: Path) -> dict | None:
    if not path.is_file():
        return None
    try:
        with h5py.File(path, "r") as f:
            attrs = decode_attrs(f.attrs)
    except (OSError, ValueError):
        return None
    return attrs if "job_hash" in attrs else None


def write_attrs(node, attrs: dict, dtype: np.dtype | None = None) -> None:
    """HDF5 attributes: text as UTF-8 strings, numbers typed as netCDF wants them."""
    for key, value in attrs.items():
        if key == "_FillValue" or isinstance(value, np.ndarray):
            value = np.asarray(value, dtype)  # CF: the variable's own type
        elif isinstance(value, bool | int):
            value = np.int32(value)
        node.attrs[key] = value


def create(path: Path, job: Job) -> None:
    """Write the whole empty store aside, then rename it to ``path``."""
    shutil.rmtree(journal_dir(path), ignore_errors=True)  # entries of an older store
    tmp = path.with_name(f"{path.name}.creating-{os.getpid()}")
    arrays = store_arrays(job)
    with h5py.File(tmp, "w", track_order=True) as f:
        write_attrs(f, initial_attrs(job))
        dims = [a.name for a in arrays if a.is_dimension]
        for a in arrays:
            data = _create_dataset(f, a)
            if a.is_dimension:
                data.make_scale(a.name)
                data.attrs["_Netcdf4Dimid"] = np.int32(dims.index(a.name))
            else:
                for axis, dim in enumerate(a.dims):
                    data.dims[axis].attach_scale(f[dim])
            write_attrs(data, a.attrs, a.dtype)
    _fsync(tmp)
    os.replace(tmp, path)


def _create_dataset(f: h5py.File, a: ArraySchema) -> h5py.Dataset:
    if a.dtype.kind == "U":
        return f.create_dataset(
            a.name, data=a.values.astype(object), dtype=h5py.string_dtype(), track_order=True
        )
    if a.values is not None:
        return f.create_dataset(a.name, data=a.values, dtype=a.dtype, track_order=True)
    return f.create_dataset(
        a.name, shape=a.shape, dtype=a.dtype, chunks=a.chunks, fillvalue=a.fill,
        compression=None if a.name == "done" else "gzip", track_order=True,
    )  # fmt: skip


def remove(path: Path) -> None:
    path.unlink()
    shutil.rmtree(journal_dir(path), ignore_errors=True)


def clean_leftovers(path: Path, job: Job) -> list[Path]:
    """Delete a killed checkpoint's copy and half-written entries, then replay the journal."""
    removed = [p for p in path.parent.glob(f"{glob_escape(path.name)}.checkpoint-*")]
    journal = journal_dir(path)
    if journal.is_dir():
        removed += [p for p in journal.iterdir() if not ENTRY.match(p.name)]
    for p in removed:
        p.unlink(missing_ok=True)
    apply_journal(path, job)
    return removed


def glob_escape(name: str) -> str:
    return re.sub(r"([\[\]*?])", r"[\1]", name)


# -- the journal -----------------------------------------------------------------


def journal_entries(path: Path) -> dict[int, Path]:
    journal = journal_dir(path)
    if not journal.is_dir():
        return {}
    found = {}
    for p in journal.iterdir():
        match = ENTRY.match(p.name)
        if match:
            found[int(match.group(1))] = p
    return dict(sorted(found.items()))


def write_entry(path: Path, index: int, arrays: dict[str, np.ndarray]) -> None:
    journal = journal_dir(path)
    journal.mkdir(exist_ok=True)
    final = journal / f"tile-{index:06d}.npz"
    tmp = journal / f".{final.name}.{os.getpid()}.tmp"
    with open(tmp, "wb") as fh:
        np.savez(fh, **arrays)
    os.replace(tmp, final)


def load_entry(entry: Path) -> dict[str, np.ndarray] | None:
    """A journal entry's arrays, or None if a checkpoint removed it meanwhile."""
    try:
        with np.load(entry) as data:
            return {name: data[name] for name in data.files}
    except FileNotFoundError:
        return None


def apply_journal(path: Path, job: Job, runs: list[dict] | None = None) -> int:
    """Checkpoint: fold the journal (and a new run log) into the store file atomically."""
    entries = journal_entries(path)
    if not entries and runs is None:
        return 0
    tiles = plan_tiles(job)
    tmp = path.with_name(f"{path.name}.checkpoint-{os.getpid()}")
    shutil.copyfile(path, tmp)
    with h5py.File(tmp, "r+") as f:
        for index, entry in entries.items():
            for name, values in load_entry(entry).items():
                f[name][tiles[index].rows] = values
        for index in entries:
            f["done"][index] = 1
        if runs is not None:
            write_attrs(f, run_attrs(job, decode_attrs(f.attrs), runs))
    _fsync(tmp)
    os.replace(tmp, path)
    for entry in entries.values():
        entry.unlink(missing_ok=True)
    return len(entries)


def _fsync(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


class Hdf5Store(Store):
    def __init__(self, path: Path, job: Job, lock: StoreLock):
        with h5py.File(path, "r") as f:
            runs = decode_attrs(f.attrs)["runs"]
            self._done = f["done"][:].astype(bool)
        super().__init__(path, job, lock, runs)  # the journal is empty: clean_leftovers replayed it
        self._journaled = 0
        self._runs_dirty = False
        self._last_checkpoint = time.monotonic()

    @property
    def done(self) -> np.ndarray:
        return self._done.copy()

    def _write_tile(self, tile: Tile, arrays: dict[str, np.ndarray]) -> None:
        write_entry(self.path, tile.index, arrays)
        self._done[tile.index] = True
        self._journaled += 1
        due = time.monotonic() - self._last_checkpoint >= CHECKPOINT_SECONDS
        if self._journaled >= CHECKPOINT_TILES or due:
            self.checkpoint()

    def _write_runs(self, runs: list[dict]) -> None:
        self._runs_dirty = True
        self.checkpoint()

    def checkpoint(self) -> None:
        apply_journal(self.path, self.job, self._runs if self._runs_dirty else None)
        self._journaled = 0
        self._runs_dirty = False
        self._last_checkpoint = time.monotonic()

    def _close(self) -> None:
        if self._journaled or self._runs_dirty:
            self.checkpoint()
        with contextlib.suppress(OSError):  # only if empty
            journal_dir(self.path).rmdir()


class Hdf5Reader(StoreReader):
    def __init__(self, path: Path, attrs: dict):
        del attrs  # re-read below, after the journal: the file may have been replaced since
        # Journal first, file second: an entry a checkpoint removes meanwhile is then in the file.
        entries = {i: load_entry(e) for i, e in journal_entries(path).items()}
        self._journal = {i: arrays for i, arrays in entries.items() if arrays is not None}
        self._file = h5py.File(path, "r")
        super().__init__(path, decode_attrs(self._file.attrs))
        self._tiles = plan_tiles(self.job)

    @property
    def journaled(self) -> dict[int, dict[str, np.ndarray]]:
        return dict(self._journal)

    def _done(self) -> np.ndarray:
        done = self._file["done"][:].astype(bool)  # int8 from format 2 on
        done[list(self._journal)] = True
        return done

    def _read(self, name: str) -> np.ndarray:
        data = self._file[name][:]
        for index, arrays in self._journal.items():
            data[self._tiles[index].rows] = arrays[name]
        return data

    def close(self) -> None:
        self._file.close()
