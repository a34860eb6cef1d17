"""Zarr v3 backend (the default): a directory, one chunk file per tile and array.

A run creates the store, writes its tiles and its run log without zarr
(``_zarr_documents``, ``_chunks``: zarr's own documents and chunk files, byte for
byte); reading, verifying and repairing a store go through zarr, imported then.
Crash safety comes from writing every chunk and metadata document aside
(``<key>.<32 hex>.partial``) and renaming it into place, as zarr's ``LocalStore``
does: a killed writer leaves whole files plus stray ``.partial`` files, which
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

import itertools
import json
import math
import os
import re
import shutil
import tempfile
from pathlib import Path

import numpy as np

from ...errors import StoreDamaged, StoreError
from ..job import Job
from ..plan import Tile, plan_tiles
from ._base import Store, StoreReader, tile_values
from ._chunks import DirectChunk
from ._integrity import Verification, describe_exception
from ._lock import StoreLock
from ._metadata import CHECKSUMS_ATTR, GLOBAL, VOLATILE_ATTRS, Variable, digests, global_document
from ._root import Root, RootLog, new_root, read_zarr_root, write_zarr_root
from ._schema import (
    TILE_ARRAYS,
    ArraySchema,
    cell_arrays,
    chunk_coords,
    decode_attrs,
    initial_attrs,
    run_attrs,
    store_arrays,
)
from ._zarr_documents import (
    ZARR_JSON,
    array_document,
    chunk_key,
    group_document,
    read_document,
    write_document,
)

PARTIAL = re.compile(r"\.[0-9a-f]{32}\.partial$")


def _zarr():
    """zarr, imported where a store is read, verified or repaired through it (a run's own
    writes never need it, and its import is a good part of a process's start-up)."""
    import zarr

    return zarr


def read_attrs(path: Path) -> dict | None:
    """Attributes of the campar store at ``path``, or None if it is none; StoreDamaged if it
    has a campar store's layout but its metadata cannot be read. Read from the group's
    zarr.json as JSON, not through zarr: an array's damaged metadata in the consolidated
    copy (a data type its fill value does not fit) must not hide which job the store holds."""
    if not (path / "zarr.json").is_file():
        if (path / "done").is_dir() and (path / "checksum").is_dir():
            raise StoreDamaged(
                f"{path} has a campar store's layout but its metadata (zarr.json) is missing: "
                "campar cannot tell which job it holds; move it away and run again"
            )
        return None
    try:
        document = json.loads((path / "zarr.json").read_bytes())
        attrs = document["attributes"]
        if not isinstance(attrs, dict):
            raise TypeError("its attributes are not an object")
        return decode_attrs(attrs) if "job_hash" in attrs else None
    except PermissionError:
        raise
    except (OSError, ValueError, TypeError, KeyError) as exc:  # JSON errors are ValueErrors
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
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _build(tmp: Path, job: Job, separator: str | None = None) -> None:
    """A new store of ``job`` at ``tmp`` (chunk keys with ``separator``; None: CHUNK_KEYS):
    every array's zarr.json and a coordinate's values, then the group's zarr.json with the
    checksums of its variables (``_metadata``) and every array's document consolidated,
    then the root record."""
    arrays = store_arrays(job)
    separator = CHUNK_KEYS["separator"] if separator is None else separator
    attrs = initial_attrs(job)
    tmp.mkdir(parents=True)
    documents = {}
    found: dict = {GLOBAL: global_variable(group_document(attrs))}
    for a in arrays:
        document = array_document(a, separator)
        (tmp / a.name).mkdir()
        write_document(tmp / a.name / ZARR_JSON, document)
        values = None if a.values is None else _write_values(tmp / a.name, document, a)
        documents[a.name] = document
        found[a.name] = Variable({f"{a.name}/{ZARR_JSON}": document}, values)
    recorded = digests(found)
    group = group_document({**attrs, CHECKSUMS_ATTR: json.dumps(recorded)}, documents)
    write_document(tmp / ZARR_JSON, group)
    write_zarr_root(tmp, new_root(attrs, recorded, len(plan_tiles(job))))


def _write_values(folder: Path, document: dict, a: ArraySchema) -> np.ndarray:
    """Write a coordinate's values, chunk by chunk as zarr does (the last chunk padded with
    the fill, a chunk of the fill alone left out); returns them as zarr reads them."""
    writer = DirectChunk.for_document(folder, document)
    values = np.asarray(a.values, dtype=writer.fill.dtype)
    counts = [math.ceil(n / c) for n, c in zip(a.shape, a.chunks, strict=True)]
    for coords in itertools.product(*map(range, counts)):
        bounds = zip(coords, a.chunks, a.shape, strict=True)
        region = tuple(slice(i * c, min((i + 1) * c, n)) for i, c, n in bounds)
        part = values[region]
        chunk = writer.fill.copy()
        chunk[tuple(slice(0, m) for m in part.shape)] = part
        writer.put(coords, chunk)
    return values


def record_checksums(path: Path, arrays) -> dict[str, str]:
    """Record the checksums of the variables as their own documents hold them
    (``_metadata``), then consolidate every document into the store's zarr.json; returns
    them (what the root record holds)."""
    group = _zarr().open_group(path, mode="r", use_consolidated=False)
    found = describe_variables(path, arrays, group, consolidated=False)
    recorded = digests(found)
    document = read_document(path / ZARR_JSON)
    attrs = {**document["attributes"], CHECKSUMS_ATTR: json.dumps(recorded)}
    own = {a.name: found[a.name].documents[f"{a.name}/{ZARR_JSON}"] for a in arrays}
    write_document(path / ZARR_JSON, group_document(attrs, own))
    return recorded


# Chunk files named c.<i>.<j> beside the array's zarr.json, not c/<i>/<j>: a tile's first
# write into c/<i>/ makes that folder, a mkdir a tile row whose CPU is taken from the
# lanes (docs/scaling.md). Readers follow the metadata.
CHUNK_KEYS = {"name": "default", "separator": "."}
CONSOLIDATED = "zarr.json (consolidated)"  # where campar and xarray read a variable's metadata
GROUP_KEYS = ("zarr_format", "node_type")  # the group's own, under the global checksum


def describe_variables(path: Path, arrays, group, consolidated: bool = True) -> dict:
    """{name: ``_metadata.Variable``, or why it cannot be read} of the store's variables
    ``arrays`` (``ArraySchema``): each one's own zarr.json and (``consolidated``) its copy in
    the store's zarr.json; a coordinate's values read as campar and xarray read them."""
    copies = None
    found: dict = {GLOBAL: "the store's zarr.json cannot be read"}
    try:
        document = json.loads((path / "zarr.json").read_bytes())
        found[GLOBAL] = global_variable(document)
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


def global_variable(document: dict) -> Variable:
    """The store's attributes as a variable (``_metadata.GLOBAL``) from its group's zarr.json:
    those under the checksum, and the group's own keys."""
    own = {f"(zarr.json) {key}": document.get(key) for key in GROUP_KEYS}
    return Variable({"zarr.json": {**global_document(document["attributes"]), **own}})


_fresh: dict[tuple, dict] = {}  # (job hash, separator) → its variables: the last few jobs


def fresh_variables(job: Job, arrays, separator: str) -> dict:
    """The variables of a store of ``job`` built afresh (in a temporary folder, not free:
    kept for the next check of the same job, as ``status`` then ``verify`` make)."""
    key = (job.digest(), separator, tuple(a.name for a in arrays))
    if key not in _fresh:
        with tempfile.TemporaryDirectory(prefix="campar-expected-") as tmp:
            path = Path(tmp) / "expected.zarr"
            _build(path, job, separator)
            found = describe_variables(path, arrays, _zarr().open_group(path, mode="r"))
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


def repair_variables(path: Path, job: Job, names) -> dict[str, str]:
    """Rewrite the variables ``names`` from the job — metadata documents, and coordinates'
    values — each file written aside and renamed into place, then record the checksums and
    consolidate. The cells' chunks are left as they are (their tiles verify on their own)."""
    arrays = store_arrays(job)
    if not names:
        return record_checksums(path, arrays)
    if GLOBAL in names:  # what the store holds, from the job; what its runs wrote is kept
        _rewrite_group(path, job)
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
    return record_checksums(path, arrays)


def committed_now(path: Path) -> np.ndarray:
    """Per tile, committed in the store's root record now (``committed_tiles``)."""
    root = read_zarr_root(path)
    if root is None:
        raise StoreError(f"{path} has no root record (see `campar verify --adopt`)")
    return root.committed


def _rewrite_group(path: Path, job: Job) -> None:
    """The group's zarr.json as a new store of ``job`` has it — its own keys (the Zarr
    format) and the attributes that say what it holds — keeping what its runs wrote
    (``VOLATILE_ATTRS``); written aside and renamed (consolidated again afterwards)."""
    target = path / "zarr.json"
    try:
        document = json.loads(target.read_bytes())
        kept = {k: v for k, v in document.get("attributes", {}).items() if k in VOLATILE_ATTRS}
    except (OSError, ValueError, AttributeError):
        kept = {}
    wanted = {k: v for k, v in initial_attrs(job).items() if k not in VOLATILE_ATTRS}
    write_document(target, group_document({**wanted, **kept}))


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
    """Rewrite the damaged variables from the job (every one's metadata, and the group's,
    for a store being adopted); make the damaged tiles and the flags set on pending tiles
    pending: unset the flag, then delete the checksum's and the arrays' chunks (read as the
    fill from then on); then write the root record of what verified."""
    names = set(report.variables) | ({GLOBAL} if report.adopting else set())
    variables = repair_variables(path, job, names)
    documents = {a.name: read_document(path / a.name / ZARR_JSON) for a in store_arrays(job)}
    tiles = plan_tiles(job)
    for index in sorted(set(report.damaged) | set(report.stray)):
        for name in TILE_ARRAYS[::-1]:  # the flag first
            _delete_chunk(path / name, chunk_key(documents[name], (index,)))
        for a in cell_arrays(job):
            coords = chunk_coords(job, tiles[index], a)
            _delete_chunk(path / a.name, chunk_key(documents[a.name], coords))
    group = read_document(path / ZARR_JSON)
    attrs = {"campar_store": int(group["attributes"]["campar_store"]), "job_hash": job.digest()}
    if report.tiles_checked:
        sums = np.where(report.verified, report.sums, 0).astype(np.uint64)
    else:  # the tiles are checked next, against the record as it stands
        sums = report.root.checksums if report.root is not None else np.zeros(len(tiles), "u8")
    write_zarr_root(path, new_root(attrs, variables, len(tiles)).with_sums(sums))


def _delete_chunk(folder: Path, key: str) -> None:
    """Delete a chunk (it reads as the fill from then on), as zarr's ``LocalStore`` does."""
    path = folder / key
    if path.is_dir():  # zarr deletes a key that is a folder with everything under it
        shutil.rmtree(path)
    else:
        path.unlink(missing_ok=True)


class ZarrTileArrays:
    """Writes tiles' array chunks into a Zarr store, without the lock and without commit:
    what a worker rank does for its own tiles (``Store.direct_writes``). Distinct tiles
    never share a chunk file, so writers of different tiles never meet; the master
    commits a tile (checksum, then ``done``) only after its writer reported it written,
    and resume clears the chunks of uncommitted tiles (``ZarrStore._clear``)."""

    def __init__(self, real: Path, job: Job):
        self.real, self.job = real, job
        self.schemas = {a.name: a for a in cell_arrays(job)}
        self.documents = {name: read_document(real / name / ZARR_JSON) for name in self.schemas}
        self.direct = {
            name: DirectChunk.for_document(real / name, document)
            for name, document in self.documents.items()
        }

    def write(self, tile: Tile, arrays: dict[str, np.ndarray]) -> None:
        try:
            lead = 0 if tile.layer is None else 1
            write_chunks(
                self.real,
                [
                    (
                        name,
                        self.direct[name],
                        tile.region,
                        chunk_coords(self.job, tile, self.schemas[name]),
                        lead,
                        values,
                    )
                    for name, values in arrays.items()
                ],
            )
        except OSError:
            clean_leftovers(self.real, self.job)  # a failed write's .partial files
            raise


class ZarrStore(Store):
    direct_writes = True

    def __init__(self, path: Path, job: Job, lock: StoreLock, done: np.ndarray, real: Path):
        self._document = read_document(real / ZARR_JSON)
        runs = decode_attrs(self._document["attributes"])["runs"]
        super().__init__(path, job, lock, runs, real)
        self._tile_arrays = ZarrTileArrays(real, job)
        self._tile_direct = {name: DirectChunk.for_array(real / name) for name in TILE_ARRAYS}
        self._done = np.array(done, bool)
        self._root = RootLog(real, read_zarr_root(real))  # sound: ``open_store`` checked it
        self._clear(np.flatnonzero(~self._done))

    def _clear(self, tiles) -> None:
        """Delete the chunks of pending tiles that a killed or failed write left: outside the
        committed tiles the store holds only the fill, never numbers no flag vouches for."""
        for name, a in self._tile_arrays.schemas.items():
            document = self._tile_arrays.documents[name]
            for index in tiles:
                coords = chunk_coords(self.job, self.tiles[int(index)], a)
                _delete_chunk(self.real / name, chunk_key(document, coords))

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
            self._set_each("checksum", [(t.index, np.uint64(v)) for t, v in written])
            self._set_each("done", [(t.index, np.int8(1)) for t, _ in written])
            self._root.commit(written)  # the commit: readers see the tiles from now on
        except OSError:
            clean_leftovers(self.real, self.job)
            raise
        for tile, _ in written:
            self._done[tile.index] = True

    def _set_each(self, name: str, values: list[tuple[int, np.generic]]) -> None:
        """Set elements of a per-tile array, one chunk each (``write_chunks``)."""
        direct = self._tile_direct[name]
        write_chunks(self.real, [(name, direct, i, (i,), 0, np.array([v])) for i, v in values])

    def _write_runs(self, runs: list[dict]) -> None:
        """The run log into the group's attributes: its zarr.json replaced whole, the
        consolidated documents in it as they were (array metadata never changes)."""
        attrs = self._document["attributes"]
        group = {**self._document, "attributes": {**attrs, **run_attrs(self.job, attrs, runs)}}
        try:
            write_document(self.real / ZARR_JSON, group)
        except OSError:
            clean_leftovers(self.real, self.job)
            raise
        self._document = group

    def _close(self) -> None:
        self._root.fold()  # every other write is already a whole file on disk


def write_chunks(real: Path, chunks) -> None:
    """Write chunks of the store at ``real`` given as (array name, its DirectChunk or None,
    region, chunk coordinates, leading length-1 axes, values): each by DirectChunk where it
    can, the rest through zarr in one call of its event loop (an array of a codec chain
    campar does not write)."""
    rest = [
        (name, region, values)
        for name, direct, region, coords, lead, values in chunks
        if direct is None or not direct.write(coords, lead, values)
    ]
    if rest:
        from zarr.core.sync import sync

        group = _zarr().open_group(real, mode="r+", use_consolidated=False)
        arrays = {name: group[name] for name in {name for name, _, _ in rest}}
        sync(_all_at_once(arrays[n].async_array.setitem(r, v) for n, r, v in rest))


async def _all_at_once(writes) -> None:
    """Await every write (gathered inside zarr's loop: a gather made outside belongs to no
    loop), all to their end, then raise the first error: nothing still writes while a
    failed tile's ``.partial`` files are cleaned up."""
    import asyncio  # with zarr alone: a run's own writes need neither

    for outcome in await asyncio.gather(*writes, return_exceptions=True):
        if isinstance(outcome, BaseException):
            raise outcome


class ZarrReader(StoreReader):
    rewrites_variables_in_place = True

    def __init__(self, path: Path, attrs: dict, real: Path, *, adopting: bool = False):
        # The root record first: everything it holds committed was written before it (the
        # reader's snapshot); tiles committed after it read as pending.
        try:
            root, damaged = read_zarr_root(real), None
        except ValueError as exc:  # RootDamaged
            root, damaged = None, exc
        self._group = _open_group(path, real)
        super().__init__(path, attrs, real, adopting=adopting)
        self._check_layout()
        self._take_root(lambda: _given(root, damaged))

    def _shapes(self) -> dict[str, tuple]:
        """Each array's shape as its own zarr.json says (read as JSON: an array whose
        metadata zarr cannot parse still has a shape, and ``variable_damage`` says what)."""
        shapes = {}
        for a in store_arrays(self.job):
            try:
                shape = json.loads((self.real / a.name / "zarr.json").read_bytes())["shape"]
                shapes[a.name] = tuple(int(n) for n in shape)
            except (OSError, ValueError, KeyError, TypeError):
                continue  # missing, or damaged: ``variable_damage`` names it
        return shapes

    def _tile_values(self, name: str) -> tuple[np.ndarray, dict[int, str]]:
        n_tiles = len(plan_tiles(self.job))
        try:
            array = self._group[name]
        except Exception as exc:  # zarr raises many kinds on damaged metadata
            why = f"{name} unreadable ({describe_exception(exc)})"
            return np.zeros(n_tiles, np.uint64), dict.fromkeys(range(n_tiles), why)
        return tile_values(array.__getitem__, n_tiles, array.dtype, name)

    def _read_rows(self, name: str, rows: slice, layer: int | None) -> np.ndarray:
        return self._group[name][self.selection(rows, layer)]

    def _describe(self, arrays) -> dict:
        return describe_variables(self.real, arrays, self._group)

    def _fresh(self, arrays) -> dict:
        return fresh_variables(self.job, arrays, chunk_separator(self.real, self.job))

    def close(self) -> None:
        pass  # zarr holds no open files between reads


def _open_group(path: Path, real: Path):
    """The store's group through its consolidated metadata, or through each array's own
    if that copy is damaged (``variable_damage`` then says how); StoreDamaged if neither."""
    for consolidated in (None, False):
        try:
            return _zarr().open_group(real, mode="r", use_consolidated=consolidated)
        except Exception as exc:  # zarr raises many kinds on damaged metadata
            failure = exc
    raise StoreDamaged(
        f"{path}: its group metadata cannot be read ({describe_exception(failure)}); move it "
        "away and run again"
    )


def _given(root: Root | None, damaged: Exception | None) -> Root | None:
    if damaged is not None:
        raise damaged
    return root
