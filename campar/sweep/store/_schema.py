"""What a result store holds, independent of the backend: arrays, dims, fills, attributes.

Every per-cell array lies over (second, omega[, tail]) — a basin's over (ydot0,
y0[, tail]): ``Job.second``, ``Job.first`` — and is chunked one tile of chains
by the whole first axis, so a tile is one chunk of every array and a
killed writer can only leave whole chunks behind. ``done`` has one element per
tile and one chunk per element: the commit flag of a tile never shares a chunk
with a neighbour's. Nor does its ``checksum`` (of the tile's arrays, ``_integrity``),
which is written between the arrays and the flag.

A ``chains.direction: both`` job's per-cell arrays lie over (direction, second,
omega[, tail]), chunked one tile of one direction: a tile is still one chunk
(``Tile.region``), its arrays as ``run_tile`` returns them have no direction
axis (``tile_shape``), and coordinates ``direction`` (down, up) and
``tile_direction`` label the new axis and the tiles. One-direction stores are
laid out exactly as before (same format, no direction axis).
"""

import contextlib
import json
import math
from dataclasses import dataclass, field
from datetime import UTC, datetime
from importlib import metadata

import numpy as np

from ... import __version__
from ...core.version import KERNEL_VERSION
from ...errors import StoreDamaged, StoreError, StoreMismatch
from ...model.cam_table import read_table, remember_table
from ..arrays import COMPONENTS, PARTS, TAIL_DIMS, array_names, array_spec
from ..job import DIRECTIONS, Job, job_digest
from ..plan import Tile, plan_tiles
from ._cf import cell_attrs, checksum_attrs, coordinate_attrs, done_attrs, global_attrs, history
from ._metadata import CHECKSUMS_ATTR
from ._root import MARK_ATTR

# Bumped when the layout changes in a way old readers cannot follow. 1: no CF
# metadata, tail dimension "var" unlabelled, ``done`` bool, Zarr attributes as
# nested JSON. 2: CF-1.10 attributes, every dimension a coordinate, ``done`` int8,
# the HDF5 file a netCDF-4 file, attributes job/versions/runs JSON text in both. 3: a
# ``checksum`` per tile, written before ``done`` (a committed tile can be verified).
FORMAT = 3
READABLE_FORMATS = (1, 2, 3)  # read_store reads these; only FORMAT is resumed
CHECKSUMS_FROM = 3  # the first format whose tiles carry a checksum
JSON_ATTRS = ("job", "versions", "runs")  # nested: JSON text (netCDF attributes cannot nest)

DEPENDENCIES = ("numpy", "numba", "zarr", "h5py", "mpi4py", "pydantic")


@dataclass(frozen=True)
class ArraySchema:
    """One variable of the store; ``values`` for coordinates, written at creation."""

    name: str
    dtype: np.dtype  # kind "U": text (a variable-length string in the store)
    shape: tuple[int, ...]
    chunks: tuple[int, ...]
    dims: tuple[str, ...]
    fill: object = None  # the value of elements never written
    attrs: dict = field(default_factory=dict, compare=False)
    values: np.ndarray | None = field(default=None, compare=False)

    @property
    def is_dimension(self) -> bool:
        """A coordinate variable: the labels of its own dimension (a dimension scale)."""
        return self.dims == (self.name,)


def fill_value(dtype: np.dtype):
    """The value of a cell that was never computed: NaN, -1, or False."""
    dtype = np.dtype(dtype)
    if dtype.kind == "f":
        return math.nan
    if dtype.kind == "b":
        return False
    return -1


def cell_arrays(job: Job) -> list[ArraySchema]:
    """Per-cell arrays of a job, in ``arrays.array_names`` order (a ``both`` job's with a
    leading ``direction`` axis, chunked one direction at a time)."""
    n_second, n_first = job.shape
    both = job.chains.direction == "both"
    lead, lead_chunks, lead_dims = (
        ((len(DIRECTIONS),), (1,), ("direction",)) if both else ((), (), ())
    )
    arrays = []
    for name in array_names(job):
        dtype, tail = array_spec(job, name)
        fill = fill_value(dtype)
        arrays.append(
            ArraySchema(
                name,
                dtype,
                (*lead, n_second, n_first, *tail),
                (*lead_chunks, job.tiles.rows, n_first, *tail),
                (*lead_dims, job.second, job.first, *TAIL_DIMS.get(name, ())),
                fill,
                cell_attrs(job, name, dtype, fill),
            )
        )
    return arrays


def tile_shape(array: ArraySchema, tile: Tile) -> tuple[int, ...]:
    """Shape of a per-cell array's part in ``tile`` as ``run_tile`` returns it: (tile rows,
    omega[, tail]), without a direction axis."""
    lead = 1 if array.dims[0] == "direction" else 0
    return (tile.n_rows, *array.shape[lead + 1 :])


def chunk_coords(job: Job, tile: Tile, array: ArraySchema) -> tuple[int, ...]:
    """Chunk grid coordinates of a per-cell array's chunk holding ``tile``."""
    row_chunk = tile.row_start // job.tiles.rows
    lead = () if tile.layer is None else (tile.layer,)
    return (*lead, row_chunk) + (0,) * (len(array.shape) - len(lead) - 1)


def done_array(job: Job) -> ArraySchema:
    """The commit flag per tile: int8 (netCDF has no bool), 0 pending, 1 committed."""
    n_tiles, dtype = len(plan_tiles(job)), np.dtype(np.int8)
    attrs = _tile_coordinates(job, done_attrs(dtype))
    return ArraySchema("done", dtype, (n_tiles,), (1,), ("tile",), 0, attrs)


def checksum_array(job: Job) -> ArraySchema:
    """The checksum of each committed tile's arrays (``_integrity``): uint64, 0 none."""
    n_tiles, dtype = len(plan_tiles(job)), np.dtype(np.uint64)
    attrs = _tile_coordinates(job, checksum_attrs(dtype))
    return ArraySchema("checksum", dtype, (n_tiles,), (1,), ("tile",), 0, attrs)


def _tile_coordinates(job: Job, attrs: dict) -> dict:
    """A per-tile array's attributes, naming ``tile_direction`` too where there is one."""
    if job.chains.direction == "both":
        attrs = {**attrs, "coordinates": attrs["coordinates"] + " tile_direction"}
    return attrs


# Arrays with one element per tile, one chunk each, uncompressed: the commit of a tile.
TILE_ARRAYS = ("checksum", "done")


def coordinates(job: Job) -> dict[str, np.ndarray]:
    return {job.first: job.first_values, job.second: job.second_values}


def coordinate_arrays(job: Job) -> list[ArraySchema]:
    """Coordinates: one per dimension, the tiles' row ranges, the fixed parameters (scalars)."""
    sizes = {d: n for a in cell_arrays(job) for d, n in zip(a.dims, a.shape, strict=True)}
    tiles = plan_tiles(job)
    labels = {
        job.second: job.second_values,
        job.first: job.first_values,
        "component": np.array(COMPONENTS),
        "section_point": np.arange(sizes.get("section_point", 0), dtype=np.int32),
        "multiplier": np.arange(sizes.get("multiplier", 0), dtype=np.int32),
        "attractor": np.arange(1, sizes.get("attractor", 0) + 1, dtype=np.int32),
        "part": np.array(PARTS),
        "plane_axis": np.array(job.curves.plane if job.curves else ("", "")),
        "direction": np.array(DIRECTIONS),
        "tile": np.arange(len(tiles), dtype=np.int32),
    }
    values = {name: (v, (name,)) for name, v in labels.items() if name in sizes or name == "tile"}
    for end in ("start", "stop"):
        rows = np.array([getattr(t, f"row_{end}") for t in tiles], np.int32)
        values[f"tile_row_{end}"] = (rows, ("tile",))
    if "direction" in sizes:
        values["tile_direction"] = (np.array([t.direction for t in tiles]), ("tile",))
    for name in sorted(job.fixed):
        values[name] = (np.array(job.fixed[name], np.float64), ())
    arrays = []
    for name, (v, dims) in values.items():
        if dims == (name,) and name in sizes and sizes[name] != v.size:
            raise ValueError(f"{name}: {v.size} labels for a dimension of {sizes[name]}")
        attrs = coordinate_attrs(job, name)
        arrays.append(ArraySchema(name, v.dtype, v.shape, v.shape, dims, None, attrs, v))
    return arrays


def store_arrays(job: Job) -> list[ArraySchema]:
    """Every variable of the store, in the order they are created."""
    return [*coordinate_arrays(job), *cell_arrays(job), checksum_array(job), done_array(job)]


def versions() -> dict[str, str]:
    """campar's, its numerical kernel's (``kernel``: KERNEL_VERSION, what ``campar point
    --from`` checks) and its dependencies' versions (read from metadata: importing
    mpi4py.MPI would start MPI)."""
    found = {"campar": __version__, "kernel": str(KERNEL_VERSION)}
    for name in DEPENDENCIES:
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = "absent"
    return found


def utc_now() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds")


def initial_attrs(job: Job) -> dict:
    """The attributes of a new store, as stored (nested ones as JSON text)."""
    return {
        **global_attrs(job, utc_now()),
        "campar_store": FORMAT,
        MARK_ATTR: 1,
        "job": json.dumps(job.to_dict()),
        "job_hash": job.digest(),
        **table_attrs(job),
        "versions": json.dumps(versions()),
        "runs": "[]",
    }


TABLE_ATTR = "cam_table"  # a tabulated cam's table, its file's text (under the checksums)


def table_attrs(job: Job) -> dict:
    """A tabulated cam's table, kept in the store: the store is read, verified, plotted and
    resumed without the file (``cam_table.remember_table``); {} for a cam of motion laws."""
    cam = job.model.cam
    if cam.table is None:
        return {}
    return {TABLE_ATTR: read_table(cam.table, cam.table_sha256).text}


def remember_stored_table(path, attrs: dict) -> None:
    """Make the table a store keeps known by its digest, so that its stored job reads (and
    computes) as it did wherever the file is; StoreDamaged if the kept table is damaged."""
    text = attrs.get(TABLE_ATTR)
    if text is None:
        return
    try:
        if not isinstance(text, str):
            raise ValueError("it is not text")
        remember_table(text, f"the cam table kept in {path}")
    except ValueError as exc:
        raise StoreDamaged(f"{path} is damaged: the cam table it keeps is ({exc})") from None


def upgraded_attrs(job: Job, attrs: dict) -> dict:
    """A readable older store's attributes (decoded) as the current format states them:
    its format, job, versions and run log kept; created when its first run started."""
    runs = attrs.get("runs", [])
    created = runs[0].get("start", "unknown") if runs else "unknown"
    version = attrs.get("versions", {}).get("campar", "unknown")
    return {
        **global_attrs(job, created),
        "campar_version": version,
        "campar_store": attrs.get("campar_store"),
        "job": json.dumps(attrs["job"]),
        "job_hash": attrs.get("job_hash"),
        "versions": json.dumps(attrs.get("versions", {})),
        **run_attrs(job, {"date_created": created, "campar_version": version}, runs),
    }


def run_attrs(job: Job, attrs: dict, runs: list[dict]) -> dict:
    """The attributes a new run log changes: ``runs`` and the CF ``history`` from it."""
    created, version = attrs.get("date_created", "?"), attrs.get("campar_version", "?")
    return {"runs": json.dumps(runs), "history": history(job, created, version, runs)}


def decode_attrs(raw) -> dict:
    """A store's attributes as Python values: JSON text parsed, numpy scalars unwrapped."""
    attrs = {}
    for key, value in raw.items():
        if isinstance(value, bytes):
            value = value.decode()
        elif isinstance(value, np.generic):
            value = value.item()
        if key in JSON_ATTRS and isinstance(value, str):  # format 1 Zarr: already nested
            value = json.loads(value)
        elif key == CHECKSUMS_ATTR:  # kept as it is if it is not JSON: a problem verify names
            with contextlib.suppress(TypeError, ValueError):
                value = json.loads(value)
        attrs[key] = value
    return attrs


def check_readable(path, attrs: dict) -> None:
    """Raise StoreError unless this campar can read the store's format."""
    found = attrs.get("campar_store")
    if found not in READABLE_FORMATS:
        raise StoreError(
            f"{path} has store format {found!r}, this campar reads formats "
            f"{', '.join(map(str, READABLE_FORMATS))}: it was written by a newer campar; "
            "upgrade campar to read it"
        )


def check_tile_arrays(
    job: Job, tile: Tile, arrays: dict[str, np.ndarray], schemas: list | None = None
) -> None:
    """Raise ValueError unless ``arrays`` is exactly what ``run_tile`` returns for ``tile``
    (``schemas``: the job's ``cell_arrays``, if the caller has them, made once)."""
    expected = {a.name: a for a in (schemas or cell_arrays(job))}
    if set(arrays) != set(expected):
        missing = sorted(set(expected) - set(arrays))
        extra = sorted(set(arrays) - set(expected))
        raise ValueError(f"tile {tile.index}: arrays missing {missing}, unexpected {extra}")
    for name, schema in expected.items():
        shape = tile_shape(schema, tile)
        got = arrays[name]
        if got.shape != shape or got.dtype != schema.dtype:
            raise ValueError(
                f"tile {tile.index}: {name} is {got.dtype}{list(got.shape)}, "
                f"expected {schema.dtype}{list(shape)}"
            )


def layout_problems(job: Job, attrs: dict, shapes: dict[str, tuple]) -> list[str]:
    """What in a store's metadata disagrees with itself: the stored job with its hash, the
    arrays' shapes (``shapes``: name → shape as stored) with the stored job's grid. An empty
    list for a store as campar wrote it; else the store was edited or damaged."""
    problems = []
    stored = attrs.get("job")
    if isinstance(stored, dict) and job_digest(stored) != attrs.get("job_hash"):
        problems.append(
            f"the stored job does not match its hash {attrs.get('job_hash')} "
            "(the metadata was edited or damaged)"
        )
    expected = cell_arrays(job) + [done_array(job)]
    if attrs.get("campar_store", 0) >= CHECKSUMS_FROM:
        expected.append(checksum_array(job))
    for a in expected:
        got = shapes.get(a.name)
        if got is None:
            problems.append(f"array {a.name} is missing")
        elif tuple(got) != a.shape:
            problems.append(
                f"array {a.name} has shape {list(got)}, the stored job's grid "
                f"({job.shape[0]} {job.second} × {job.shape[1]} {job.first}) makes it "
                f"{list(a.shape)}"
            )
    return problems


# -- is this the same job? ----------------------------------------------------


def flatten(data, prefix: str = "") -> dict[str, object]:
    """{"integrator.rtol": 1e-08, …} from a nested dict."""
    if not isinstance(data, dict):
        return {prefix: data}
    flat = {}
    for key, value in data.items():
        flat.update(flatten(value, f"{prefix}.{key}" if prefix else str(key)))
    return flat


def job_differences(stored: dict, job: Job, limit: int = 8) -> list[str]:
    """Lines "key: A in the store, B in the job" for every field that differs."""
    old, new = flatten(stored), flatten(job.to_dict())
    lines = []
    for key in sorted(set(old) | set(new)):
        a, b = old.get(key, ABSENT), new.get(key, ABSENT)
        if key != "store" and not _same(a, b):
            lines.append(f"{key}: {_show(a)} in the store, {_show(b)} in the job")
    if len(lines) > limit:
        lines[limit:] = [f"… and {len(lines) - limit} more"]
    return lines


ABSENT = object()


def _same(a, b) -> bool:
    if a is ABSENT or b is ABSENT:
        return a is b
    # The stored job went through JSON: lists come back for tuples.
    return json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


def _show(value) -> str:
    if value is ABSENT:
        return "(absent)"
    return json.dumps(value) if isinstance(value, (str, list, dict)) else str(value)


def stored_kernel(attrs: dict) -> str | None:
    """The version of the numerical kernel that computed a store (``versions.kernel``, as
    text); None for a store that records none (written before stores recorded it)."""
    versions = attrs.get("versions")
    kernel = versions.get("kernel") if isinstance(versions, dict) else None
    return None if kernel is None else str(kernel)


def other_kernel(attrs: dict) -> str | None:
    """Which kernel computed a store, said against this campar's, if another one did (its
    cells would not reproduce, nor join this kernel's in one map); None if this one did."""
    found = stored_kernel(attrs)
    if found == str(KERNEL_VERSION):
        return None
    which = f"kernel version {found}" if found else "an earlier kernel (it records no version)"
    return f"computed by {which}, this campar's is kernel version {KERNEL_VERSION}"


def check_same_job(path, attrs: dict, job: Job) -> None:
    """Raise StoreMismatch unless the store at ``path`` was made by ``job`` in this format
    and by this campar's kernel (a resume would mix two kernels' numbers in one map)."""
    found = attrs.get("campar_store")
    if found != FORMAT:
        raise StoreMismatch(
            f"{path} has store format {found!r}; this campar writes format {FORMAT} and "
            "resumes only that: run the job into another --store path (this one is left as "
            "it is), or use --overwrite to recompute it in place"
        )
    if attrs.get("job_hash") == job.digest():
        kernel = other_kernel(attrs)
        if kernel is not None:
            raise StoreMismatch(
                f"{path} was {kernel}: resuming it would mix two kernels' numbers in one "
                "map; run the job into another --store path (this one is left as it is), or "
                "use --overwrite to recompute it in place"
            )
        return
    diffs = job_differences(attrs.get("job", {}), job) or ["(the job hashes differ)"]
    if len(diffs) == 1 and diffs[0].startswith("model.cam.table_sha256:"):
        raise StoreMismatch(
            f"{path}: the cam table {job.model.cam.table} has changed since this store was "
            f"computed ({diffs[0].split(': ', 1)[1]}); restore the table the store was "
            "computed with (the store keeps a copy: attribute cam_table), or run into "
            "another --store path"
        )
    kernel = other_kernel(attrs)  # a default that changed with the kernel differs too
    raise StoreMismatch(
        f"{path} holds results of a different job ("
        + "; ".join(diffs)
        + (f") and was {kernel}" if kernel else ")")
        + ": use --overwrite to replace it, or another --store path"
    )
