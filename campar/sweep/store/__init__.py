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
"""

import os
import shutil
from pathlib import Path

from ...errors import StoreError
from ..job import Job
from . import _hdf5, _zarr
from ._base import Store, StoreReader
from ._lock import StoreLock, lock_path
from ._schema import (
    FORMAT,
    ArraySchema,
    cell_arrays,
    check_readable,
    check_same_job,
    fill_value,
    job_differences,
    store_arrays,
    upgraded_attrs,
)

__all__ = [
    "FORMAT",
    "ArraySchema",
    "Store",
    "StoreReader",
    "backend_name",
    "cell_arrays",
    "fill_value",
    "job_differences",
    "lock_path",
    "open_store",
    "read_store",
    "store_arrays",
    "upgraded_attrs",
]

HDF5_SUFFIXES = (".h5", ".hdf5")
_STORES = {_zarr: _zarr.ZarrStore, _hdf5: _hdf5.Hdf5Store}
_READERS = {_zarr: _zarr.ZarrReader, _hdf5: _hdf5.Hdf5Reader}


def backend_name(path: str | Path) -> str:
    return "hdf5" if Path(path).suffix.lower() in HDF5_SUFFIXES else "zarr"


def _backend(path: Path):
    return _hdf5 if backend_name(path) == "hdf5" else _zarr


def open_store(path: str | Path, job: Job, *, overwrite: bool = False) -> Store:
    """Open the store of a run: create it, or resume it if it holds the same job.

    Raises StoreLocked if another live run holds it, StoreMismatch if it holds
    a different job (untouched, unless ``overwrite`` replaces it), StoreError
    if ``path`` is something other than a campar store (never replaced).
    """
    path = Path(path)
    backend = _backend(path)
    lock = StoreLock.acquire(path)
    try:
        _remove_aside(path)
        attrs = backend.read_attrs(path)
        if attrs is None and path.exists() and not _empty_dir(path):
            raise StoreError(
                f"{path} exists and is not a campar store; choose another --store path "
                "(campar never deletes what it did not write)"
            )
        if attrs is not None and not overwrite:
            check_same_job(path, attrs, job)
        if attrs is None and path.exists():
            path.rmdir()  # an empty directory
        elif attrs is not None and overwrite:
            backend.remove(path)
        if not path.exists():
            backend.create(path, job)
        backend.clean_leftovers(path, job)
        return _STORES[backend](path, job, lock)
    except BaseException:
        lock.release()
        raise


def read_store(path: str | Path) -> StoreReader:
    """Open a store read-only (no lock; safe while a run writes it)."""
    path = Path(path)
    backend = _backend(path)
    if not path.exists():
        raise StoreError(f"no store at {path}")
    attrs = backend.read_attrs(path)
    if attrs is None:
        raise StoreError(f"{path} is not a campar {backend_name(path)} store")
    check_readable(path, attrs)
    return _READERS[backend](path, attrs)


def _empty_dir(path: Path) -> bool:
    return path.is_dir() and not any(path.iterdir())


def _remove_aside(path: Path) -> None:
    """Remove what a killed creation or deletion left beside the store (we hold the lock)."""
    for pattern in (".creating-*", ".deleting-*"):
        for leftover in path.parent.glob(_hdf5.glob_escape(path.name) + pattern):
            if leftover.is_dir():
                shutil.rmtree(leftover, ignore_errors=True)
            else:
                os.unlink(leftover)
