"""Zarr v3 backend (the default): a directory, one chunk file per tile and array.

Crash safety comes from zarr's ``LocalStore``, which writes every chunk and
metadata document aside (``<key>.<32 hex>.partial``) and renames it into
place: a killed writer leaves whole files plus stray ``.partial`` files, which
``clean_leftovers`` deletes (also after a write that failed, a full disk).
A tile's ``checksum`` and then its ``done`` chunk are written after its array
chunks, so a kill in between leaves the tile pending and it is recomputed. A
damaged tile is repaired by deleting its chunks (they read as the fill) after
unsetting its flag. Every chunk ends with a CRC32C of its bytes (the ``crc32c``
codec of Zarr v3): a chunk changed on disk cannot be read, so damage is seen
even where the checksum of the decoded tile would not change.

Metadata is consolidated once at creation (array metadata never changes
afterwards) so ``xarray.open_zarr(path)`` opens the store without a warning.
Attributes follow xarray's Zarr v3 conventions: ``dimension_names``, a
``coordinates`` attribute naming auxiliary coordinates, and ``_FillValue`` as
xarray encodes it (floats as base64 of the little-endian double).
"""

import asyncio
import base64
import json
import os
import re
import shutil
import struct
import tempfile
import warnings
from pathlib import Path

import numpy as np
import zarr
from zarr.codecs import Crc32cCodec, ZstdCodec
from zarr.core.sync import sync
from zarr.errors import ZarrUserWarning

from ...errors import StoreDamaged
from ..job import Job
from ..plan import Tile, plan_tiles
from ._base import Store, StoreReader, tile_values
from ._chunks import DirectChunk
from ._integrity import Verification, describe_exception
from ._lock import StoreLock
from ._metadata import CHECKSUMS_ATTR, GLOBAL, VOLATILE_ATTRS, Variable, digests, global_document
from ._schema import (
    TILE_ARRAYS,
    cell_arrays,
    chunk_coords,
    decode_attrs,
    initial_attrs,
    run_attrs,
    store_arrays,
)

PARTIAL = re.compile(r"\.[0-9a-f]{32}\.partial$")


def read_attrs(path: Path) -> dict | None:
    """Attributes of the campar store at ``path``, or None if it is none; StoreDamaged if it
    has a campar store's layout but its metadata cannot be read."""
    if not (path / "zarr.json").is_file():
        if (path / "done").is_dir() and (path / "checksum").is_dir():
            raise StoreDamaged(
                f"{path} has a campar store's layout but its metadata (zarr.json) is missing: "
                "campar cannot tell which job it holds; move it away and run again"
            )
        return None
    try:
        attrs = zarr.open_group(path, mode="r").attrs.asdict()
        return decode_attrs(attrs) if "job_hash" in attrs else None
    except PermissionError:
        raise
    except (OSError, ValueError, TypeError) as exc:  # JSON errors are ValueErrors
        if (path / "done").is_dir():
            raise StoreDamaged(
                f"{path} has a campar store's layout but its metadata (zarr.json) cannot be "
                f"read ({describe_exception(exc)}): campar cannot tell which job it holds; "
                "move it away and run again"
            ) from None
        return None


def create(path: Path, job: Job) -> None:
    """Build the whole empty store aside, then rename it to ``path``; nothing is left of a
    creation that fails (a full disk)."""
    tmp = path.with_name(f"{path.name}.creating-{os.getpid()}")
    shutil.rmtree(tmp, ignore_errors=True)
    try:
        _build(tmp, job)
        os.rename(tmp, path)
    except BaseException:
        _settle()
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _settle(seconds: float = 30.0) -> None:
    """Wait for zarr's writes still running: a failed write inside zarr (a gather without
    ``return_exceptions``) raises at once while the others go on, and one that ended after
    the clean-up left a file in a store being deleted (seen on a full disk, under mpirun)."""

    async def others_done():
        me = asyncio.current_task()
        pending = [t for t in asyncio.all_tasks() if t is not me]
        if pending:
            await asyncio.wait(pending, timeout=seconds)

    sync(others_done())


def _build(tmp: Path, job: Job, separator: str | None = None) -> None:
    """A new store of ``job`` at ``tmp`` (chunk keys with ``separator``; None: CHUNK_KEYS)."""
    group = zarr.create_group(tmp, zarr_format=3, attributes=initial_attrs(job))
    keys = CHUNK_KEYS if separator is None else {**CHUNK_KEYS, "separator": separator}
    arrays = store_arrays(job)
    for a in arrays:
        text = a.dtype.kind == "U"
        array = group.create_array(
            a.name,
            shape=a.shape,
            dtype=str if text else a.dtype,
            chunks=a.chunks,
            fill_value="" if text else a.fill,
            dimension_names=list(a.dims),
            attributes=zarr_attrs(a.attrs, a.dtype),
            compressors=_codecs(a.name),
            chunk_key_encoding=keys,
        )
        if a.values is not None:
            array[...] = a.values
    record_checksums(tmp, arrays)


def record_checksums(path: Path, arrays) -> None:
    """Record the checksums of the variables as their own documents hold them
    (``_metadata``), then consolidate every document into the store's zarr.json."""
    group = zarr.open_group(path, mode="r+", use_consolidated=False)
    found = describe_variables(path, arrays, group, consolidated=False)
    group.attrs[CHECKSUMS_ATTR] = json.dumps(digests(found))
    with warnings.catch_warnings():
        # "consolidated metadata is not part of the v3 spec": xarray reads it, and we want that.
        warnings.simplefilter("ignore", ZarrUserWarning)
        zarr.consolidate_metadata(path)


# Chunk files named c.<i>.<j> beside the array's zarr.json, not c/<i>/<j>: a tile's first
# write into c/<i>/ makes that folder, a mkdir a tile row whose CPU is taken from the
# lanes (docs/scaling.md). Readers follow the metadata.
CHUNK_KEYS = {"name": "default", "separator": "."}
CONSOLIDATED = "zarr.json (consolidated)"  # where campar and xarray read a variable's metadata


def describe_variables(path: Path, arrays, group, consolidated: bool = True) -> dict:
    """{name: ``_metadata.Variable``, or why it cannot be read} of the store's variables
    ``arrays`` (``ArraySchema``): each one's own zarr.json and (``consolidated``) its copy in
    the store's zarr.json; a coordinate's values read as campar and xarray read them."""
    copies = None
    found: dict = {GLOBAL: "the store's zarr.json cannot be read"}
    try:
        document = json.loads((path / "zarr.json").read_bytes())
        found[GLOBAL] = Variable({"zarr.json": global_document(document["attributes"])})
        if consolidated:
            copies = document["consolidated_metadata"]["metadata"]
    except (OSError, ValueError, KeyError, TypeError):
        copies = {} if consolidated else None  # each variable then missing from it, and said so
    for a in arrays:
        variable, own = Variable(), path / a.name / "zarr.json"
        try:
            variable.documents[f"{a.name}/zarr.json"] = json.loads(own.read_bytes())
        except FileNotFoundError:
            found[a.name] = f"{a.name}/zarr.json is missing"
            continue
        except (OSError, ValueError) as exc:
            found[a.name] = f"{a.name}/zarr.json unreadable ({describe_exception(exc)})"
            continue
        if copies is not None:
            if not isinstance(copies.get(a.name), dict):
                found[a.name] = f"missing from the store's consolidated metadata ({CONSOLIDATED})"
                continue
            variable.documents[CONSOLIDATED] = copies[a.name]
        if a.values is not None:
            try:
                variable.values = np.asarray(group[a.name][...])
            except Exception as exc:  # zarr and numcodecs raise many kinds
                found[a.name] = f"values unreadable ({describe_exception(exc)})"
                continue
        found[a.name] = variable
    return found


_fresh: dict[tuple, dict] = {}  # (job hash, separator) → its variables: the last few jobs


def fresh_variables(job: Job, arrays, separator: str) -> dict:
    """The variables of a store of ``job`` built afresh (in a temporary folder, not free:
    kept for the next check of the same job, as ``status`` then ``verify`` make)."""
    key = (job.digest(), separator, tuple(a.name for a in arrays))
    if key not in _fresh:
        with tempfile.TemporaryDirectory(prefix="campar-expected-") as tmp:
            path = Path(tmp) / "expected.zarr"
            _build(path, job, separator)
            found = describe_variables(path, arrays, zarr.open_group(path, mode="r"))
        while len(_fresh) >= 4:
            _fresh.pop(next(iter(_fresh)))
        _fresh[key] = found
    return _fresh[key]


def chunk_separator(path: Path, job: Job) -> str:
    """The separator of the store's chunk keys: "." (c.<i>.<j>), or "/" in stores made
    before it (c/<i>/<j>), as the metadata says, or as the chunk files lie."""
    for a in cell_arrays(job):
        for document in (path / a.name / "zarr.json", path / "zarr.json"):
            try:
                data = json.loads(document.read_bytes())
                if document.parent == path:
                    data = data["consolidated_metadata"]["metadata"][a.name]
                return data["chunk_key_encoding"]["configuration"]["separator"]
            except (OSError, ValueError, KeyError, TypeError):
                continue
    return "/" if any((path / a.name / "c").is_dir() for a in cell_arrays(job)) else "."


def repair_variables(path: Path, job: Job, names) -> None:
    """Rewrite the variables ``names`` from the job — metadata documents, and coordinates'
    values — each file written aside and renamed into place, then record the checksums and
    consolidate. The cells' chunks are left as they are (their tiles verify on their own)."""
    arrays = store_arrays(job)
    if GLOBAL in names:  # what the store holds, from the job; what its runs wrote is kept
        group = zarr.open_group(path, mode="r+", use_consolidated=False)
        wanted = {k: v for k, v in initial_attrs(job).items() if k not in VOLATILE_ATTRS}
        for key in [k for k in group.attrs if k not in wanted and k not in VOLATILE_ATTRS]:
            del group.attrs[key]
        group.attrs.update(wanted)
    fresh = Path(tempfile.mkdtemp(prefix=f"{path.name}.creating-", dir=path.parent))
    try:
        _build(fresh / "store", job, chunk_separator(path, job))
        for a in arrays:
            if a.name not in names:
                continue
            source, target = fresh / "store" / a.name, path / a.name
            target.mkdir(exist_ok=True)
            if a.values is not None:  # a coordinate: its chunk files too
                for old in target.iterdir():
                    if old.name != "zarr.json":
                        shutil.rmtree(old) if old.is_dir() else old.unlink()
                for new in source.iterdir():
                    if new.name != "zarr.json":
                        os.replace(new, target / new.name)
            os.replace(source / "zarr.json", target / "zarr.json")
    finally:
        shutil.rmtree(fresh, ignore_errors=True)
    record_checksums(path, arrays)


def _codecs(name: str) -> list:
    """Zstd for the arrays (not the one-byte flags), then a CRC32C of every chunk's bytes:
    a chunk changed on disk fails to read, even where zstd would decode it alike."""
    return [Crc32cCodec()] if name in TILE_ARRAYS else [ZstdCodec(level=0), Crc32cCodec()]


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


def repair(path: Path, job: Job, report: Verification) -> None:
    """Rewrite the damaged variables from the job (and record the checksums of a store
    without them); then make the damaged tiles pending: unset the flag, then delete the
    checksum's and the arrays' chunks (read as the fill from then on)."""
    if report.variables or not report.metadata_checksums:
        repair_variables(path, job, report.variables)
    group = zarr.open_group(path, mode="r+")
    tiles = plan_tiles(job)
    for index in sorted(report.damaged):
        for name in TILE_ARRAYS[::-1]:  # the flag first
            key = group[name].metadata.encode_chunk_key((index,))
            group.store.delete_sync(f"{name}/{key}")
        for a in cell_arrays(job):
            key = group[a.name].metadata.encode_chunk_key(chunk_coords(job, tiles[index], a))
            group.store.delete_sync(f"{a.name}/{key}")


class ZarrTileArrays:
    """Writes tiles' array chunks into a Zarr store, without the lock and without commit:
    what a worker rank does for its own tiles (``Store.direct_writes``). Distinct tiles
    never share a chunk file, so writers of different tiles never meet; the master
    commits a tile (checksum, then ``done``) only after its writer reported it written,
    and resume clears the chunks of uncommitted tiles (``ZarrStore._clear``)."""

    def __init__(self, real: Path, job: Job, group=None):
        self.real, self.job = real, job
        group = group if group is not None else zarr.open_group(real, mode="r+")
        self.schemas = {a.name: a for a in cell_arrays(job)}
        self.arrays = {name: group[name] for name in self.schemas}
        self.direct = {
            name: DirectChunk.for_array(real / name, array) for name, array in self.arrays.items()
        }

    def write(self, tile: Tile, arrays: dict[str, np.ndarray]) -> None:
        try:
            lead = 0 if tile.layer is None else 1
            write_chunks(
                [
                    (
                        self.arrays[name],
                        self.direct[name],
                        tile.region,
                        chunk_coords(self.job, tile, self.schemas[name]),
                        lead,
                        values,
                    )
                    for name, values in arrays.items()
                ]
            )
        except OSError:
            clean_leftovers(self.real, self.job)  # a failed write's .partial files
            raise


class ZarrStore(Store):
    direct_writes = True

    def __init__(self, path: Path, job: Job, lock: StoreLock, done: np.ndarray, real: Path):
        group = zarr.open_group(real, mode="r+")
        super().__init__(path, job, lock, decode_attrs(group.attrs.asdict())["runs"], real)
        self._group = group
        self._tile_arrays = ZarrTileArrays(real, job, group)
        self._arrays = self._tile_arrays.arrays
        self._schemas = self._tile_arrays.schemas.values()
        self._checksums = group["checksum"]
        self._flags = group["done"]
        self._tile_direct = {
            a.basename: DirectChunk.for_array(real / a.basename, a)
            for a in (self._checksums, self._flags)
        }
        self._done = np.array(done, bool)
        self._clear(np.flatnonzero(~self._done))

    def _clear(self, tiles) -> None:
        """Delete the chunks of pending tiles that a killed or failed write left: outside the
        committed tiles the store holds only the fill, never numbers no flag vouches for."""
        for a in self._schemas:
            array = self._arrays[a.name]
            for index in tiles:
                coords = chunk_coords(self.job, self.tiles[int(index)], a)
                key = f"{a.name}/{array.metadata.encode_chunk_key(coords)}"
                if (self.real / key).exists():
                    self._group.store.delete_sync(key)

    @property
    def done(self) -> np.ndarray:
        return self._done.copy()

    def _write_tile(self, tile: Tile, arrays: dict[str, np.ndarray], checksum: int) -> None:
        self._tile_arrays.write(tile, arrays)
        self._commit([(tile, checksum)])

    def _commit(self, written: list[tuple[Tile, int]]) -> None:
        # Each tile's checksum and flag is a chunk of its own: every checksum, then the flags
        # after them (the commit of each tile); directly (DirectChunk) where it can.
        try:
            self._set_each(self._checksums, [(t.index, np.uint64(v)) for t, v in written])
            self._set_each(self._flags, [(t.index, np.int8(1)) for t, _ in written])
        except OSError:
            clean_leftovers(self.real, self.job)
            raise
        for tile, _ in written:
            self._done[tile.index] = True

    def _set_each(self, array, values: list[tuple[int, np.generic]]) -> None:
        """Set elements of a per-tile array, one chunk each (``write_chunks``)."""
        direct = self._tile_direct[array.basename]
        write_chunks([(array, direct, i, (i,), 0, np.array([v])) for i, v in values])

    def _write_runs(self, runs: list[dict]) -> None:
        try:
            self._group.attrs.update(run_attrs(self.job, self._group.attrs.asdict(), runs))
        except OSError:
            clean_leftovers(self.real, self.job)
            raise

    def _close(self) -> None:
        pass  # every write is already a whole file on disk


def write_chunks(chunks) -> None:
    """Write chunks given as (array, its DirectChunk or None, region, chunk coordinates,
    leading length-1 axes, values): each by DirectChunk where it can, the rest through
    zarr in one call of its event loop (one call per chunk costs each its own round trip
    through the loop, docs/scaling.md)."""
    rest = [
        (array, region, values)
        for array, direct, region, coords, lead, values in chunks
        if direct is None or not direct.write(coords, lead, values)
    ]
    if rest:
        sync(_all_at_once(a.async_array.setitem(r, v) for a, r, v in rest))


async def _all_at_once(writes) -> None:
    """Await every write (gathered inside zarr's loop: a gather made outside belongs to no
    loop), all to their end, then raise the first error: nothing still writes while a
    failed tile's ``.partial`` files are cleaned up."""
    for outcome in await asyncio.gather(*writes, return_exceptions=True):
        if isinstance(outcome, BaseException):
            raise outcome


class ZarrReader(StoreReader):
    def __init__(self, path: Path, attrs: dict, real: Path):
        self._group = zarr.open_group(real, mode="r")
        super().__init__(path, attrs, real)
        self._check_layout()

    def _shapes(self) -> dict[str, tuple]:
        return {name: tuple(array.shape) for name, array in self._group.arrays()}

    def _tile_values(self, name: str) -> tuple[np.ndarray, dict[int, str]]:
        array = self._group[name]
        return tile_values(array.__getitem__, len(plan_tiles(self.job)), array.dtype, name)

    def _read_rows(self, name: str, rows: slice, layer: int | None) -> np.ndarray:
        return self._group[name][self.selection(rows, layer)]

    def _describe(self, arrays) -> dict:
        return describe_variables(self.real, arrays, self._group)

    def _fresh(self, arrays) -> dict:
        return fresh_variables(self.job, arrays, chunk_separator(self.real, self.job))

    def close(self) -> None:
        pass  # zarr holds no open files between reads
