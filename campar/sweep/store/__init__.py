"""Result stores: Zarr v3 (default) or HDF5 (a path ending .h5/.hdf5), one interface.

A run opens its store with ``open_store(path, job)``: it takes the store's
lock, creates the store or checks that it holds the same job (resume), cleans
what a killed writer left, and returns a ``Store`` whose ``done`` says which
tiles remain. Views open any store read-only with ``read_store(path)``.

Layout (both backends, same names): coordinates ``omega`` and the second
parameter (e.g. ``mu_cn``); per-cell arrays over (second, omega[, tail]) named
as in ``campar.sweep.arrays``; ``done`` per tile; attributes ``job`` (normalised),
``job_hash``, ``versions``, ``runs`` (the run log), ``campar_store`` (format).

From format 2 on the store speaks CF-1.10 (``_cf``): every variable has its
long name, units and meaning, codes their flag values and meanings, every
dimension is a coordinate (``component`` y/ydot, ``tile`` with its row range),
and the HDF5 file is a netCDF-4 file, so ``xarray.open_zarr`` and
``xarray.open_dataset(path, engine="h5netcdf")`` give the same Dataset
(``campar.open``). Format 1 stores are still read; only the current format resumes.

From format 3 on every committed tile carries a checksum (``_integrity``), and
every variable — coordinates, array metadata, the attributes that say how values
decode — one of its own (``_metadata``): ``verify_store`` reads every committed
tile back and checks every variable, reporting the damaged ones, and
``open_store`` does so before a resume, rewrites the damaged variables from the
job, makes the damaged tiles pending again (logging which and why) and so
recomputes them. A store reached through
symbolic links is used at its real path: the lock, the files and every atomic
replace act there, and the links stay. A failed read or write of the store
(full disk, permissions) raises StoreIOError (exit 74) naming the path and the
cause, and leaves no temporary file behind.
"""

import glob
import logging
import os
import re
import shutil
import time
from pathlib import Path

import numpy as np

from ...errors import StoreDamaged, StoreError, io_error
from ..job import Job
from ..plan import plan_tiles
from ._base import Store, StoreReader
from ._integrity import Verification, check_tiles, tile_checksum, verify_store
from ._lock import StoreLock, holder_alive, lock_path
from ._metadata import CHECKSUMS_ATTR
from ._root import HDF5_ATTR, MARK_ATTR, RootDamaged
from ._schema import (
    FORMAT,
    ArraySchema,
    cell_arrays,
    check_readable,
    check_same_job,
    check_tile_arrays,
    fill_value,
    job_differences,
    other_kernel,
    store_arrays,
    stored_kernel,
    tile_shape,
    upgraded_attrs,
)

ROOT_ATTRS = (HDF5_ATTR, MARK_ATTR)  # attributes of the root record's (``_root``)

__all__ = [
    "CHECKSUMS_ATTR",
    "ROOT_ATTRS",
    "FORMAT",
    "ArraySchema",
    "Store",
    "StoreReader",
    "TileWriter",
    "takes_direct_writes",
    "Verification",
    "adopt_store",
    "backend_name",
    "cell_arrays",
    "committed_tiles",
    "is_store",
    "stored_job",
    "fill_value",
    "job_differences",
    "lock_path",
    "open_store",
    "other_kernel",
    "read_store",
    "store_arrays",
    "stored_kernel",
    "tile_checksum",
    "tile_shape",
    "upgraded_attrs",
    "verify_store",
    "check_tiles",
]

log = logging.getLogger("campar.sweep.store")

HDF5_SUFFIXES = (".h5", ".hdf5")
_STORES: dict = {}  # backend module → its Store class
_READERS: dict = {}  # backend module → its StoreReader class


def backend_name(path: str | Path) -> str:
    return "hdf5" if Path(path).suffix.lower() in HDF5_SUFFIXES else "zarr"


def _backend(path: Path):
    """The backend module of the store at ``path``, imported when a store of its kind is
    first met: a run of a Zarr store never loads h5py, nor one of an HDF5 file zarr (each
    a good part of a process's start-up, benchmarks/RESULTS.md)."""
    if backend_name(path) == "hdf5":
        from . import _hdf5 as module

        store, reader = module.Hdf5Store, module.Hdf5Reader
    else:
        from . import _zarr as module

        store, reader = module.ZarrStore, module.ZarrReader
    _STORES[module], _READERS[module] = store, reader
    return module


def real_path(path: Path) -> Path:
    """The store's own path: every symbolic link (of the store or its folders) resolved."""
    return Path(os.path.realpath(path))


def open_store(path: str | Path, job: Job, *, overwrite: bool = False) -> Store:
    """Open the store of a run: create it, or resume it if it holds the same job.

    Raises StoreLocked if another live run holds it (through whatever alias),
    StoreMismatch if it holds a different job or was computed by another kernel
    version (untouched, unless ``overwrite`` replaces it), StoreError if ``path``
    is something other than a campar store (never replaced), StoreDamaged if its
    metadata is, StoreIOError if the system refuses a read or write. Committed
    tiles are verified first; the damaged ones are made pending (``Store.done`` is
    unset for them).
    """
    path = Path(path)
    backend, real = _backend(path), real_path(path)
    lock = StoreLock.acquire(real)
    try:
        if real.is_file() and real.stat().st_nlink > 1:
            raise StoreError(
                f"{path} has {real.stat().st_nlink} names (hard links): a store is locked by "
                "its name, so a run through another name would write it too; remove the other "
                "links (find -samefile) and run again"
            )
        _remove_aside(real)
        attrs = _read_attrs_for(path, real, backend, job)
        if attrs is None and real.exists() and not _empty_dir(real):
            raise StoreError(
                f"{path} exists and is not a campar store; choose another --store path "
                "(campar never deletes what it did not write)"
            )
        if attrs is not None and not overwrite:
            check_same_job(path, attrs, job)
        if attrs is None and real.exists():
            real.rmdir()  # an empty directory
        elif attrs is not None and overwrite:
            backend.remove(real)  # the target: a link to it stays, and finds the new store
        if not real.exists():
            backend.create(real, job)
            done = np.zeros(len(plan_tiles(job)), bool)
        else:
            backend.clean_leftovers(real, job)
            done = _verify_for_resume(path, real, backend, attrs, job)
        if done is None:  # kept aside, beyond repair: the map starts again
            backend.create(real, job)
            done = np.zeros(len(plan_tiles(job)), bool)
        return _STORES[backend](path, job, lock, done, real)
    except OSError as exc:
        lock.release()
        raise io_error(f"cannot open the store {path}", exc) from None
    except BaseException:
        lock.release()
        raise


def _read_attrs_for(path: Path, real: Path, backend, job: Job) -> dict | None:
    """The store's attributes; None after keeping aside an HDF5 file of this very job (its
    seal says so) that HDF5 cannot read: a new store replaces it, the old one is kept."""
    try:
        return backend.read_attrs(real)
    except StoreDamaged as exc:
        if getattr(exc, "sealed_job", None) != job.digest():
            raise
        aside = backend.set_store_aside(real)
        log.warning("%s; kept as %s, the map is computed again", exc, aside.name)
        return None


def _verify_for_resume(path: Path, real: Path, backend, attrs: dict, job: Job):
    """Verify every committed tile; repair the damaged ones (pending again) and log why.
    None if the store of this job is beyond reading (HDF5) and was kept aside."""
    start = time.monotonic()
    try:
        with _READERS[backend](path, attrs, real) as reader:
            report = verify_store(reader)
        if not report.tiles_checked:  # damaged metadata of tile arrays: rewritten first
            for name, why in report.variables.items():
                log.warning(
                    "%s: variable %s is damaged (%s): rewritten from the job", path, name, why
                )
            backend.repair(real, job, report)
            with _READERS[backend](path, backend.read_attrs(real), real) as reader:
                report = verify_store(reader)
    except StoreDamaged as exc:
        if not hasattr(backend, "set_store_aside"):
            raise StoreDamaged(f"{exc}; --overwrite recomputes the store") from None
        aside = backend.set_store_aside(real)  # its attributes named this job: ours
        log.warning("%s; kept as %s, the map is computed again", exc, aside.name)
        return None
    for problem in report.problems:
        log.warning("%s: %s", path, problem)
    for name, why in report.variables.items():
        log.warning("%s: variable %s is damaged (%s): rewritten from the job", path, name, why)
    for index, why in sorted(report.damaged.items()):
        log.warning("%s: tile %d is damaged (%s): computed again", path, index, why)
    if not report.clean or not report.metadata_checksums or report.stray or report.root is None:
        backend.repair(real, job, report)
    if report.committed:
        log.info(
            "%s: %d committed tiles verified in %.1f s, %d damaged",
            path,
            len(report.committed),
            time.monotonic() - start,
            len(report.damaged),
        )
    return report.verified


def adopt_store(path: str | Path) -> Verification:
    """Adopt a store written before root records (``_root``): under its lock, check every
    variable against the stored job and every committed tile against its checksum, rewrite
    the variables from the job, leave the damaged tiles pending, and write the root record of
    the tiles that verified. Returns the check; StoreError if the store has a root record
    already, StoreLocked if a run holds it."""
    path = Path(path)
    backend, real = _backend(path), real_path(path)
    if not real.exists():
        raise StoreError(f"no store at {path}")
    lock = StoreLock.acquire(real)
    try:
        attrs = backend.read_attrs(real)
        if attrs is None:
            raise StoreError(f"{path} is not a campar {backend_name(path)} store")
        check_readable(path, attrs)
        if attrs.get("campar_store") != FORMAT:
            raise StoreError(
                f"{path} has store format {attrs.get('campar_store')!r}: it is read as it is "
                f"(readability checks only); only format {FORMAT} stores are adopted"
            )
        backend.clean_leftovers(real, None)
        with _READERS[backend](path, attrs, real, adopting=True) as reader:
            if reader.root is not None:
                raise StoreError(f"{path} has a sound root record: nothing to adopt")
            job = reader.job
            report = verify_store(reader)
        report.adopting = True
        backend.repair(real, job, report)
        return report
    except OSError as exc:
        raise io_error(f"cannot adopt the store {path}", exc) from None
    finally:
        lock.release()


def takes_direct_writes(path: str | Path) -> bool:
    """Whether the store at ``path`` (by its backend) lets workers write their own tiles
    (``Store.direct_writes``), known from its name before it is opened and before its
    backend is imported: a Zarr store does. Under MPI rank 0 decides a job's tile rows
    with it, and the workers wait for that before they load the kernel."""
    return backend_name(path) == "zarr"


class TileWriter:
    """Writes its own tiles' arrays into a store that allows it (``Store.direct_writes``):
    a worker rank's side of a run whose master only commits (``Store.commit_tiles``).
    ``real``: the store's real path (``Store.real``), as the master opened it."""

    def __init__(self, real: str | Path, job: Job):
        self.path, self.job = Path(real), job
        self.tiles = plan_tiles(job)
        self._cell_arrays = cell_arrays(job)
        self._names = [a.name for a in self._cell_arrays]
        try:
            from ._zarr import ZarrTileArrays  # only a Zarr store takes a worker's writes

            self._arrays = ZarrTileArrays(self.path, job)
        except OSError as exc:
            raise io_error(f"cannot open the store {self.path} to write tiles", exc) from None

    def write_tile(self, tile, arrays: dict[str, np.ndarray]) -> int:
        """Write a tile's arrays (as ``run_tile`` returns them); returns the checksum its
        commit records. StoreIOError (exit 74) when the write fails."""
        if tile != self.tiles[tile.index]:
            raise ValueError(f"{tile} is not tile {tile.index} of job {self.job.name}")
        check_tile_arrays(self.job, tile, arrays, self._cell_arrays)
        try:
            self._arrays.write(tile, arrays)
        except OSError as exc:
            what = f"cannot write tile {tile.index} to the store {self.path}"
            raise io_error(what, exc) from None
        return tile_checksum(arrays, self._names)


def read_store(path: str | Path) -> StoreReader:
    """Open a store read-only (no lock; safe while a run writes it). StoreDamaged if its
    metadata cannot be read or disagrees with itself; StoreIOError if the system refuses."""
    path = Path(path)
    real = real_path(path)
    if not real.exists():  # said before the backend is imported (a run asks, to resume)
        raise StoreError(f"no store at {path}")
    backend = _backend(path)
    try:
        attrs = backend.read_attrs(real)
        if attrs is None:
            raise StoreError(f"{path} is not a campar {backend_name(path)} store")
        check_readable(path, attrs)
        return _READERS[backend](path, attrs, real)
    except OSError as exc:
        raise io_error(f"cannot read the store {path}", exc) from None


def is_store(path: str | Path) -> bool:
    """Whether ``path`` looks like a result store (a Zarr group, an HDF5 file), not a job file."""
    path = Path(path)
    if backend_name(path) == "hdf5":
        return path.is_file()
    return (path / "zarr.json").is_file()


def stored_job(path: str | Path) -> Job:
    """The job a store holds, writing into that store (``campar run STORE`` resumes it from
    any directory: a tabulated cam's table comes from the store)."""
    with read_store(path) as reader:
        return reader.job.model_copy(update={"store": str(path)})


def committed_tiles(path: str | Path) -> np.ndarray:
    """Per tile, whether it is committed now, from the root record alone (and an HDF5
    store's journal): no tile is read or verified, so this is cheap enough to ask every
    second; ``campar.open`` verifies what it reads. StoreError if there is no campar store
    with a root record at ``path``, StoreDamaged if the record is damaged."""
    path = Path(path)
    backend, real = _backend(path), real_path(path)
    if not real.exists():
        raise StoreError(f"no store at {path}")
    try:
        return backend.committed_now(real)
    except RootDamaged as exc:
        raise StoreDamaged(f"{path}: the root record is damaged ({exc})") from None
    except OSError as exc:
        raise io_error(f"cannot read the store {path}", exc) from None


def _empty_dir(path: Path) -> bool:
    return path.is_dir() and not any(path.iterdir())


LOCK_TMP = re.compile(r"\.lock\.(\d+)\.tmp$")


def _remove_aside(path: Path) -> None:
    """Remove what a killed creation or deletion left beside the store (we hold the lock),
    and lock files a killed run was writing."""
    for pattern in (".creating-*", ".deleting-*"):
        for leftover in path.parent.glob(glob.escape(path.name) + pattern):
            if leftover.is_dir():
                shutil.rmtree(leftover, ignore_errors=True)
            else:
                os.unlink(leftover)
    for leftover in path.parent.glob(glob.escape(path.name) + ".lock.*.tmp"):
        match = LOCK_TMP.search(leftover.name)
        if match and not holder_alive({"pid": int(match.group(1))}):
            leftover.unlink(missing_ok=True)
