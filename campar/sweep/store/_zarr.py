"""Zarr v3 backend (the default): a directory, one chunk file per tile and array.

Crash safety comes from zarr's ``LocalStore``, which writes every chunk and
metadata document aside (``<key>.<32 hex>.partial``) and renames it into
place: a killed writer leaves whole files plus stray ``.partial`` files, which
``clean_leftovers`` deletes. A tile's ``done`` chunk is written after its array
chunks, so a kill in between leaves the tile pending and it is recomputed.

Metadata is consolidated once at creation (array metadata never changes
afterwards) so ``xarray.open_zarr(path)`` opens the store without a warning.
Attributes follow xarray's Zarr v3 conventions: ``dimension_names``, a
``coordinates`` attribute naming auxiliary coordinates, and ``_FillValue`` as
xarray encodes it (floats as base64 of the little-endian double).
"""

import base64
import os
import re
import shutil
import struct
import warnings
from pathlib import Path

import numpy as np
import zarr
from zarr.errors import ZarrUserWarning

from ..job import Job
from ..plan import Tile
from ._base import Store, StoreReader
from ._lock import StoreLock
from ._schema import cell_arrays, decode_attrs, initial_attrs, run_attrs, store_arrays

PARTIAL = re.compile(r"\.[0-9a-f]{32}\.partial$")


def read_attrs(path: Path) -> dict | None:
    """Attributes of the campar store at ``path``, or None if it is none."""
    if not (path / "zarr.json").is_file():
        return None
    try:
        attrs = zarr.open_group(path, mode="r").attrs.asdict()
    except (OSError, ValueError):
        return None
    return decode_attrs(attrs) if "job_hash" in attrs else None


def create(path: Path, job: Job) -> None:
    """Build the whole empty store aside, then rename it to ``path``."""
    tmp = path.with_name(f"{path.name}.creating-{os.getpid()}")
    shutil.rmtree(tmp, ignore_errors=True)
    group = zarr.create_group(tmp, zarr_format=3, attributes=initial_attrs(job))
    for a in store_arrays(job):
        text = a.dtype.kind == "U"
        array = group.create_array(
            a.name, shape=a.shape, dtype=str if text else a.dtype, chunks=a.chunks,
            fill_value="" if text else a.fill, dimension_names=list(a.dims),
            attributes=zarr_attrs(a.attrs, a.dtype),
            compressors=None if a.name == "done" else "auto",
        )  # fmt: skip
        if a.values is not None:
            array[...] = a.values
    with warnings.catch_warnings():
        # "consolidated metadata is not part of the v3 spec": xarray reads it, and we want that.
        warnings.simplefilter("ignore", ZarrUserWarning)
        zarr.consolidate_metadata(tmp)
    os.rename(tmp, path)


def zarr_attrs(attrs: dict, dtype: np.dtype) -> dict:
    """Attributes as JSON values; ``_FillValue`` encoded as xarray reads it from Zarr v3."""
    out = {}
    for key, value in attrs.items():
        if key == "_FillValue" and dtype.kind == "f":
            value = base64.standard_b64encode(struct.pack("<d", value)).decode()
        elif isinstance(value, np.ndarray):
            value = value.tolist()
        out[key] = value
    return out


def remove(path: Path) -> None:
    # Renamed first so a kill mid-delete leaves a leftover, never a half store.
    doomed = path.with_name(f"{path.name}.deleting-{os.getpid()}")
    os.rename(path, doomed)
    shutil.rmtree(doomed)


def clean_leftovers(path: Path, job: Job) -> list[Path]:
    """Delete the ``.partial`` files of a killed writer; returns what was removed."""
    removed = []
    for root, _, files in os.walk(path):
        for name in files:
            if PARTIAL.search(name):
                removed.append(Path(root, name))
                removed[-1].unlink(missing_ok=True)
    return removed


class ZarrStore(Store):
    def __init__(self, path: Path, job: Job, lock: StoreLock):
        group = zarr.open_group(path, mode="r+")
        super().__init__(path, job, lock, decode_attrs(group.attrs.asdict())["runs"])
        self._group = group
        self._arrays = {a.name: group[a.name] for a in cell_arrays(job)}
        self._flags = group["done"]
        self._done = self._flags[:].astype(bool)

    @property
    def done(self) -> np.ndarray:
        return self._done.copy()

    def _write_tile(self, tile: Tile, arrays: dict[str, np.ndarray]) -> None:
        for name, values in arrays.items():
            self._arrays[name][tile.rows] = values
        self._flags[tile.index] = 1  # the commit: after every array chunk
        self._done[tile.index] = True

    def _write_runs(self, runs: list[dict]) -> None:
        self._group.attrs.update(run_attrs(self.job, self._group.attrs.asdict(), runs))

    def _close(self) -> None:
        pass  # every write is already a whole file on disk


class ZarrReader(StoreReader):
    def __init__(self, path: Path, attrs: dict):
        self._group = zarr.open_group(path, mode="r")
        super().__init__(path, attrs)

    def _done(self) -> np.ndarray:
        return self._group["done"][:].astype(bool)  # int8 from format 2 on

    def _read(self, name: str) -> np.ndarray:
        return self._group[name][:]

    def close(self) -> None:
        pass  # zarr holds no open files between reads
