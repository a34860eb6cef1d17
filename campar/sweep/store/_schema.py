"""What a result store holds, independent of the backend: arrays, dims, fills, attributes.

Every per-cell array lies over (second, omega[, tail]) and is chunked one tile
of chains by the whole ω axis, so a tile is one chunk of every array and a
killed writer can only leave whole chunks behind. ``done`` has one element per
tile and one chunk per element: the commit flag of a tile never shares a chunk
with a neighbour's.
"""

import json
import math
from dataclasses import dataclass
from importlib import metadata

import numpy as np

from ... import __version__
from ...errors import StoreMismatch
from ..arrays import array_names, array_spec
from ..job import Job
from ..plan import Tile, plan_tiles

FORMAT = 1  # bumped when the layout changes in a way old readers cannot follow

# Names of the trailing dimensions of arrays with per-cell vectors.
TAIL_DIMS = {
    "state": ("var",),  # (y, ẏ)
    "sections": ("section_point", "var"),
    "multipliers": ("multiplier", "part"),  # (re, im) of each Floquet multiplier
}

DEPENDENCIES = ("numpy", "numba", "zarr", "h5py", "mpi4py", "pydantic")


@dataclass(frozen=True)
class ArraySchema:
    name: str
    dtype: np.dtype
    shape: tuple[int, ...]
    chunks: tuple[int, ...]
    dims: tuple[str, ...]

    @property
    def fill(self):
        return fill_value(self.dtype)


def fill_value(dtype: np.dtype):
    """The value of a cell that was never computed: NaN, -1, or False."""
    dtype = np.dtype(dtype)
    if dtype.kind == "f":
        return math.nan
    if dtype.kind == "b":
        return False
    return -1


def cell_arrays(job: Job) -> list[ArraySchema]:
    """Per-cell arrays of a job, in ``tile.array_names`` order."""
    n_second, n_omega = job.shape
    arrays = []
    for name in array_names(job):
        dtype, tail = array_spec(job, name)
        dims = (job.second, "omega", *TAIL_DIMS.get(name, ())[: len(tail)])
        arrays.append(
            ArraySchema(
                name, dtype, (n_second, n_omega, *tail), (job.tiles.rows, n_omega, *tail), dims
            )
        )
    return arrays


def done_array(job: Job) -> ArraySchema:
    n_tiles = len(plan_tiles(job))
    return ArraySchema("done", np.dtype(bool), (n_tiles,), (1,), ("tile",))


def coordinates(job: Job) -> dict[str, np.ndarray]:
    return {"omega": job.omega, job.second: job.second_values}


def versions() -> dict[str, str]:
    """campar's and its dependencies' versions (read from metadata: importing mpi4py.MPI
    would start MPI)."""
    found = {"campar": __version__}
    for name in DEPENDENCIES:
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = "absent"
    return found


def initial_attrs(job: Job) -> dict:
    return {
        "campar_store": FORMAT,
        "job": job.to_dict(),
        "job_hash": job.digest(),
        "versions": versions(),
        "runs": [],
    }


def check_tile_arrays(job: Job, tile: Tile, arrays: dict[str, np.ndarray]) -> None:
    """Raise ValueError unless ``arrays`` is exactly what ``run_tile`` returns for ``tile``."""
    expected = {a.name: a for a in cell_arrays(job)}
    if set(arrays) != set(expected):
        missing = sorted(set(expected) - set(arrays))
        extra = sorted(set(arrays) - set(expected))
        raise ValueError(f"tile {tile.index}: arrays missing {missing}, unexpected {extra}")
    for name, schema in expected.items():
        shape = (tile.n_rows, *schema.shape[1:])
        got = arrays[name]
        if got.shape != shape or got.dtype != schema.dtype:
            raise ValueError(
                f"tile {tile.index}: {name} is {got.dtype}{list(got.shape)}, "
                f"expected {schema.dtype}{list(shape)}"
            )


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


def check_same_job(path, attrs: dict, job: Job) -> None:
    """Raise StoreMismatch unless the store at ``path`` was made by ``job``."""
    if attrs.get("campar_store") != FORMAT:
        raise StoreMismatch(
            f"{path} has store format {attrs.get('campar_store')!r}, this campar writes "
            f"{FORMAT}; use --overwrite to recompute it, or another --store path"
        )
    if attrs.get("job_hash") == job.digest():
        return
    diffs = job_differences(attrs.get("job", {}), job) or ["(the job hashes differ)"]
    raise StoreMismatch(
        f"{path} holds results of a different job:\n  "
        + "\n  ".join(diffs)
        + "\nuse --overwrite to replace it, or another --store path"
    )
