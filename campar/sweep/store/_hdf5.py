"""HDF5 backend (a path ending .h5 or .hdf5): one file with the Zarr store's names.

HDF5 from PyPI is serial and not crash-safe: a process killed while the
library updates a file can leave it unreadable, finished tiles and all. So a
run never modifies the store file in place:

1. a finished tile goes to the journal first, ``<store>.journal/tile-000012.npz``
   with its arrays and their checksum, written aside and renamed, so an entry
   is whole or absent — this is the tile's commit;
2. at a checkpoint (every ``CHECKPOINT_TILES`` tiles or ``CHECKPOINT_SECONDS``,
   and at close) the file is copied, the journal applied to the copy (arrays,
   checksum, then ``done``), the copy flushed, fsynced and renamed over the
   store, and only then are the applied entries deleted. A checkpoint first
   reserves the disk space the copy may need (``_h5guard.reserve``), and
   removes the copy if anything fails: a full disk leaves the store and the
   journal as they were, and HDF5 never writes into a full disk.

Every file written is sealed (``_h5guard``): its user block holds a digest of
the file and the job's hash, checked before HDF5 reads the file; a file that
fails the check is read only by a child process (``rescue``). An entry that
cannot be read or fails its checksum (``_journal``) is never applied: it is set
aside as ``tile-000012.npz.damaged-<time>`` and its tile recomputed. A store
whose verification finds damage is rebuilt: a new file built aside from the
job, every tile that verified copied into it, renamed over the store —
whatever was damaged, data or the file's own structure, is left behind. A
store file HDF5 cannot read at all, whose seal names the job being resumed, is
kept aside as ``<store>.damaged-<time>`` and the map computed again.

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
import errno
import logging
import os
import re
import shutil
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np

from ...errors import StoreDamaged, StoreError
from ..job import Job
from ..plan import Tile, plan_tiles
from ._base import Store, StoreReader, tile_values
from ._h5guard import (
    FOREIGN,
    open_checked,
    release,
    rescue,
    rescue_attrs,
    reserve,
    seal,
    sealed_job,
    zeroed_start,
)
from ._h5layout import build, describe_file, file_root, fresh_variables
from ._integrity import Verification, describe_exception
from ._journal import (  # noqa: F401 (re-exported: the backend's journal)
    ENTRY,
    ENTRY_TMP,
    damaged_name,
    journal_dir,
    journal_entries,
    load_entry,
    read_entry,
    set_aside,
    verified_entry,
    write_entry,
)
from ._lock import StoreLock
from ._metadata import CHECKSUMS_ATTR, VOLATILE_ATTRS
from ._root import HDF5_ATTR
from ._schema import (
    FORMAT,
    decode_attrs,
    run_attrs,
)

log = logging.getLogger("campar.sweep.store")

CHECKPOINT_TILES = 64
CHECKPOINT_SECONDS = 60.0
ROOM_MARGIN = 1 << 16  # bytes a checkpoint wants free beyond its copy and 10 % (HDF5 metadata)


def read_attrs(path: Path) -> dict | None:
    """Attributes of the campar store at ``path``, None if it is none; StoreDamaged for a
    damaged one whose attributes cannot be read (read in a child process: ``_h5guard``)."""
    if not path.is_file():
        return None
    try:
        f, state = open_checked(path)
        if f is None and state == FOREIGN:
            if zeroed_start(path):
                raise StoreDamaged(
                    f"{path} begins with zeroed bytes where an HDF5 file has its signature: a "
                    "damaged store? campar cannot tell which job it holds, and never deletes "
                    "it: move it away and run again"
                )
            return None
        if f is None:
            attrs = _rescued_attrs(path, state)
        else:
            with f:
                attrs = decode_attrs(f.attrs)
    except PermissionError:
        raise
    except (OSError, ValueError, KeyError, RuntimeError) as exc:  # an unsealed file
        raise StoreDamaged(
            f"{path} is an HDF5 file that cannot be opened ({describe_exception(exc)}); "
            "campar never deletes it: move it away and run again"
        ) from None
    return attrs if "job_hash" in attrs else None


def _rescued_attrs(path: Path, state: str) -> dict:
    rescued = rescue_attrs(path)
    if rescued.attrs is None:
        sealed = sealed_job(path)
        error = StoreDamaged(
            f"{path} is damaged ({state}) and {rescued.failure}; "
            + (
                f"its seal says it holds job {sealed}: `campar run` of that job keeps it aside "
                "and computes the map again"
                if sealed
                else "campar cannot tell which job it holds, and never deletes it: move it away "
                "and run again"
            )
        )
        error.sealed_job = sealed
        raise error
    return rescued.attrs


def set_store_aside(path: Path) -> Path:
    """Keep a store file HDF5 cannot read (and its journal) under a name campar ignores."""
    aside = damaged_name(path)
    os.replace(path, aside)
    if journal_dir(path).is_dir():
        os.replace(journal_dir(path), aside.with_name(f"{aside.name}.journal"))
    return aside


def create(path: Path, job: Job) -> None:
    """Write the whole empty store aside, then rename it to ``path`` (nothing is left of a
    creation that fails)."""
    shutil.rmtree(journal_dir(path), ignore_errors=True)  # entries of an older store
    tmp = path.with_name(f"{path.name}.creating-{os.getpid()}")
    try:
        build(tmp, job)
        seal(tmp, job.digest())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def remove(path: Path) -> None:
    path.unlink()
    shutil.rmtree(journal_dir(path), ignore_errors=True)


def clean_leftovers(path: Path, job: Job) -> list[Path]:
    """Delete a killed checkpoint's copy and half-written entries (the journal's whole entries
    are applied when the store opens, damaged ones kept aside)."""
    removed = [p for p in path.parent.glob(f"{glob_escape(path.name)}.checkpoint-*")]
    journal = journal_dir(path)
    if journal.is_dir():
        removed += [p for p in journal.iterdir() if ENTRY_TMP.match(p.name)]
    for p in removed:
        p.unlink(missing_ok=True)
    return removed


def repair(path: Path, job: Job, report: Verification) -> None:
    """Rebuild the store from the tiles that verified (file and journal): a new file built
    aside, the old one's attributes and those tiles copied in, then renamed over it."""
    keep = np.flatnonzero(report.verified).tolist()
    with _replacement(path, job) as tmp:
        build(tmp, job)
        with open(tmp, "ab") as fh:
            reserve(fh, _room(path, journal_entries(path).values()), tmp)
        with Hdf5Reader(path, None, path, adopting=True) as old, h5py.File(tmp, "r+") as new:
            for key, value in old._file.attrs.items():  # date created, history, run log
                if key in VOLATILE_ATTRS and key not in (CHECKSUMS_ATTR, HDF5_ATTR):
                    set_in_place(new.attrs, key, value)  # the rest: the job's
            sums = report.sums if report.sums is not None else old.tile_checksums()[0]
            for index in keep:
                tile = old._tiles[index]
                for name in old.names:
                    new[name][tile.region] = old.read_tile(name, tile)
                new["checksum"][index] = sums[index]
                new["done"][index] = 1
            root = file_root(new.attrs).with_sums(np.where(report.verified, sums, 0))
            new.attrs.modify(HDF5_ATTR, root.encode())
    for index, entry in journal_entries(path).items():
        if index in report.damaged:
            set_aside(entry, report.damaged[index])
        else:
            entry.unlink(missing_ok=True)  # in the new file now


def set_in_place(attrs, key: str, value) -> None:
    """Set an attribute where it is in the file's order of attributes (``attrs[key] = …``
    deletes it and adds it last), or add it last if the file has none of that name."""
    if key in attrs:
        attrs.modify(key, value)
    else:
        attrs[key] = value


def committed_now(path: Path) -> np.ndarray:
    """Per tile, committed now: in the file's root record or in the journal
    (``committed_tiles``). The journal is listed first: an entry a checkpoint folds into the
    file meanwhile is then in the file."""
    journaled = list(journal_entries(path))
    f, state = open_checked(path)
    if f is None:
        raise StoreDamaged(f"{path} is damaged ({state}): `campar verify` says more")
    with f:
        root = file_root(f.attrs)
    if root is None:
        raise StoreError(f"{path} has no root record (see `campar verify --adopt`)")
    committed = root.committed.copy()
    committed[[i for i in journaled if i < committed.size]] = True
    return committed


def glob_escape(name: str) -> str:
    return re.sub(r"([\[\]*?])", r"[\1]", name)


# -- checkpoints -----------------------------------------------------------------


@contextlib.contextmanager
def _replacement(path: Path, job: Job):
    """A new version of the store file, written at the temporary path this yields: released,
    sealed and renamed over ``path`` when the block succeeds, removed when it fails."""
    tmp = path.with_name(f"{path.name}.checkpoint-{os.getpid()}")
    try:
        yield tmp
        release(tmp)
        seal(tmp, job.digest())  # digest and fsync
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def apply_journal(path: Path, job: Job, runs: list[dict] | None = None) -> list[int]:
    """Checkpoint: fold the journal (and a new run log) into the store file atomically.
    Returns the tiles whose entries were damaged (set aside: no longer committed)."""
    entries = journal_entries(path)
    if not entries and runs is None:
        return []
    tiles = plan_tiles(job)
    applied, damaged = [], []
    with _replacement(path, job) as tmp:
        _copy_with_room(path, tmp, _room(path, entries.values()))
        with h5py.File(tmp, "r+") as f:
            for index, entry in entries.items():
                arrays, problem = read_entry(entry, job, index)
                if problem:
                    set_aside(entry, problem)
                    damaged.append(index)
                elif arrays is not None:
                    f["checksum"][index] = arrays.pop("checksum")
                    for name, values in arrays.items():
                        f[name][tiles[index].region] = values
                    applied.append(entry)
            for entry in applied:  # the flags, then the root record
                f["done"][int(ENTRY.match(entry.name).group(1))] = 1
            root = file_root(f.attrs)
            sums = root.checksums.copy()
            for entry in applied:
                index = int(ENTRY.match(entry.name).group(1))
                sums[index] = f["checksum"][index]
            f.attrs.modify(HDF5_ATTR, root.with_sums(sums).encode())
            if runs is not None:
                for key, value in run_attrs(job, decode_attrs(f.attrs), runs).items():
                    set_in_place(f.attrs, key, value)
    for entry in applied:
        entry.unlink(missing_ok=True)
    return damaged


def _room(path: Path, entries) -> int:
    """Bytes a checkpoint's copy may take: the file, its journal entries (uncompressed: more
    than their chunks will take) and a margin for HDF5's own metadata."""
    size = path.stat().st_size
    return int(1.1 * size) + sum(e.stat().st_size for e in entries) + ROOM_MARGIN


def _copy_with_room(path: Path, tmp: Path, needed: int) -> None:
    """Copy the store file to ``tmp`` with ``needed`` bytes of disk reserved for it: a full
    disk is an OSError here, never a failed write inside HDF5 (which crashes it)."""
    free = shutil.disk_usage(path.parent).free
    if free < needed:
        raise OSError(
            errno.ENOSPC,
            f"No space left on device: a checkpoint needs {needed / 1e6:.1f} MB beside the "
            f"store, {free / 1e6:.1f} MB are free",
            str(path.parent),
        )
    with open(path, "rb") as src, open(tmp, "wb") as dst:
        reserve(dst, needed, tmp)
        shutil.copyfileobj(src, dst, 1 << 20)


class Hdf5Store(Store):
    def __init__(self, path: Path, job: Job, lock: StoreLock, done: np.ndarray, real: Path):
        apply_journal(real, job)  # what an earlier run committed (verified by open_store)
        with h5py.File(real, "r") as f:
            runs = decode_attrs(f.attrs)["runs"]
        super().__init__(path, job, lock, runs, real)
        self._done = np.array(done, bool)
        self._journaled = 0
        self._runs_dirty = False
        self._last_checkpoint = time.monotonic()

    @property
    def done(self) -> np.ndarray:
        return self._done.copy()

    def _write_tile(self, tile: Tile, arrays: dict[str, np.ndarray], checksum: int) -> None:
        write_entry(self.real, tile.index, arrays, checksum)
        self._done[tile.index] = True
        self._journaled += 1
        due = time.monotonic() - self._last_checkpoint >= CHECKPOINT_SECONDS
        if self._journaled >= CHECKPOINT_TILES or due:
            self.checkpoint()

    def _write_runs(self, runs: list[dict]) -> None:
        self._runs_dirty = True
        self.checkpoint()

    def checkpoint(self) -> None:
        damaged = apply_journal(self.real, self.job, self._runs if self._runs_dirty else None)
        self._done[damaged] = False  # damaged on disk since this run wrote them
        self._journaled = 0
        self._runs_dirty = False
        self._last_checkpoint = time.monotonic()

    def _close(self) -> None:
        if self._journaled or self._runs_dirty:
            self.checkpoint()
        with contextlib.suppress(OSError):  # only if empty
            journal_dir(self.real).rmdir()


class Hdf5Reader(StoreReader):
    def __init__(self, path: Path, attrs: dict | None, real: Path, *, adopting: bool = False):
        del attrs  # re-read below, after the journal: the file may have been replaced since
        # Journal first, file second: an entry a checkpoint removes meanwhile is then in the file.
        raw = {}
        for index, entry in journal_entries(real).items():
            try:
                raw[index] = (entry, load_entry(entry))
            except Exception as exc:
                raw[index] = (entry, exc)
        self._rescue_dir, self._file_problems = None, []
        try:
            self._file = self._open(path, real)
        except OSError as exc:
            read_attrs(real)  # StoreDamaged if it is a damaged HDF5 file
            raise StoreDamaged(f"{path} cannot be opened ({describe_exception(exc)})") from None
        try:
            super().__init__(path, decode_attrs(self._file.attrs), real, adopting=adopting)
            self._check_layout()
            self._take_root(lambda: file_root(self._file.attrs))
        except BaseException:
            self.close()
            raise
        self._tiles = plan_tiles(self.job)
        if self.format == FORMAT and self._rescue_dir is None and self._sealed is False:
            self._file_problems.append(
                "the file carries no campar digest (rewritten by another tool?): only its "
                "tiles' checksums vouch for it; `campar run` seals it again"
            )
        self._journal, self._sums, self._journal_problems = {}, {}, {}
        for index, (entry, loaded) in raw.items():
            self._take_entry(index, entry, loaded)

    def _take_entry(self, index: int, entry: Path, loaded) -> None:
        if isinstance(loaded, Exception):
            why = f"journal entry {entry.name} unreadable ({describe_exception(loaded)})"
            self._journal_problems[index] = why
            return
        if loaded is None:
            return  # folded into the file by a checkpoint meanwhile
        if (self.format or 0) < 3:
            self._journal[index] = loaded
            return
        arrays, why = verified_entry(entry, self.job, index, loaded)
        if why:
            self._journal_problems[index] = why
        else:
            self._sums[index] = arrays.pop("checksum")
            self._journal[index] = arrays

    def _open(self, path: Path, real: Path) -> h5py.File:
        """The store file once it passed its check; else a copy of what can be rescued from it
        (``_h5guard``), with the tiles lost in the rescue counted as damaged."""
        f, state = open_checked(real)
        self._sealed = state is None
        if f is not None:
            return f
        self._rescue_dir = Path(tempfile.mkdtemp(prefix="campar-rescue-"))
        copy = self._rescue_dir / real.name
        rescued = rescue(real, copy)
        if not rescued.finished:
            shutil.rmtree(self._rescue_dir, ignore_errors=True)
            self._rescue_dir = None
            raise StoreDamaged(
                f"{path} is damaged ({state}) and {rescued.failure or 'cannot be read'}: "
                "no tile of it can be trusted; move it away and run again"
            )
        self._damage = f"the HDF5 file is damaged ({state})"
        self._file_problems.append(
            f"{self._damage}: tiles read from a rescued copy of those that verify"
        )
        self._rescued_damage = rescued.damaged
        return h5py.File(copy, "r")

    @property
    def journaled(self) -> dict[int, dict[str, np.ndarray]]:
        return dict(self._journal)

    def _outside_root(self) -> dict[int, int]:
        return {index: int(self._sums.get(index, 0)) for index in self._journal}

    @property
    def journal_problems(self) -> dict[int, str]:
        """Tiles whose journal entry is damaged, or lost in rescuing a damaged file."""
        return {**getattr(self, "_rescued_damage", {}), **self._journal_problems}

    def metadata_problems(self) -> list[str]:
        return list(self._file_problems)

    @property
    def file_damage(self) -> str | None:
        return getattr(self, "_damage", None)

    def _shapes(self) -> dict[str, tuple]:
        return {
            name: tuple(v.shape) for name, v in self._file.items() if isinstance(v, h5py.Dataset)
        }

    def _describe(self, arrays) -> dict:
        return describe_file(self._file, arrays)

    def _fresh(self, arrays) -> dict:
        return fresh_variables(self.job, arrays)

    def _tile_values(self, name: str) -> tuple[np.ndarray, dict[int, str]]:
        data = self._file[name]
        values, problems = tile_values(data.__getitem__, len(self._tiles), data.dtype, name)
        for index in self._journal:
            values[index] = self._sums.get(index, 0) if name == "checksum" else 1
            problems.pop(index, None)
        return values, problems

    def _read_rows(self, name: str, rows: slice, layer: int | None) -> np.ndarray:
        data = self._file[name][self.selection(rows, layer)]
        first, stop, _ = rows.indices(self.job.shape[0])
        for index, arrays in self._journal.items():
            tile = self._tiles[index]
            lo, hi = max(tile.row_start, first), min(tile.row_stop, stop)
            if lo >= hi or (layer is not None and tile.layer != layer):
                continue
            # of a both store read whole (layer None): the tile's own direction
            into = data if layer is not None or tile.layer is None else data[tile.layer]
            into[lo - first : hi - first] = arrays[name][lo - tile.row_start : hi - tile.row_start]
        return data

    def close(self) -> None:
        if getattr(self, "_file", None) is not None:
            self._file.close()
        if self._rescue_dir is not None:
            shutil.rmtree(self._rescue_dir, ignore_errors=True)
