"""What a job will cost in disk and memory, estimated before anything runs, and the limits
a run refuses to exceed unless told (``campar run --max-store/--max-memory``).

Store: every per-cell array uncompressed — an upper bound (both backends
compress; a chaotic cell's floats hardly do). Memory per rank: a fixed base
(Python, numpy, numba, zarr, h5py and the compiled kernel, measured), the
arrays of one tile in the copies a tile passes through (the kernel's outputs,
the packed buffer sent, the master's received buffer and its unpacked arrays),
and the plan's per-tile bookkeeping. Reading a store (``status``, ``verify``,
``plot``) streams it tile by tile, so no view's memory grows with the grid.
"""

import re
from dataclasses import dataclass

import numpy as np

from ..errors import JobError
from .arrays import array_names, array_spec
from .job import Job

GiB = 2**30
DEFAULT_MAX_STORE = 64 * GiB  # uncompressed; a 4000 × 4000 map of the default outputs is ~1 GiB
DEFAULT_MAX_MEMORY = 4 * GiB  # per rank
BASE_MEMORY = 256 * 2**20  # a rank's fixed peak (the base above) with a quarter to spare
TILE_COPIES = 4  # kernel outputs, packed buffer, received buffer, unpacked arrays
BYTES_PER_TILE = 512  # the plan's Tile, flags and queue entries, per tile
UNITS = {"": 1, "k": 2**10, "m": 2**20, "g": GiB, "t": 2**40}


@dataclass(frozen=True)
class Estimate:
    cells: int
    cell_bytes: int  # every per-cell array of one cell
    store_bytes: int  # uncompressed
    rank_bytes: int  # peak memory of one rank


def estimate(job: Job) -> Estimate:
    """The job's store size (uncompressed) and one rank's peak memory, in bytes."""
    cell_bytes = 0
    for name in array_names(job):
        dtype, tail = array_spec(job, name)
        cell_bytes += dtype.itemsize * int(np.prod(tail, dtype=np.int64))
    n_second, n_omega = job.shape
    cells = n_second * n_omega * len(job.directions)
    n_tiles = -(-n_second // job.tiles.rows) * len(job.directions)
    # A tile's chunk spans tiles.rows chains even past the grid's last row, and a writer
    # fills a whole chunk in memory: the chunk, not the tile's rows, is what a copy costs.
    tile_bytes = job.tiles.rows * n_omega * cell_bytes
    rank = BASE_MEMORY + TILE_COPIES * tile_bytes + BYTES_PER_TILE * n_tiles
    return Estimate(cells, cell_bytes, cells * cell_bytes + 16 * n_tiles, rank)


def check_budget(job: Job, *, max_store: int | None = None, max_memory: int | None = None):
    """The estimate; JobError (with it) if the store or a rank would exceed the limits."""
    max_store = DEFAULT_MAX_STORE if max_store is None else max_store
    max_memory = DEFAULT_MAX_MEMORY if max_memory is None else max_memory
    e = estimate(job)
    grid = f"{job.shape[0]} {job.second} × {job.shape[1]} {job.first}" + (
        " × 2 directions" if len(job.directions) > 1 else ""
    )
    if e.store_bytes > max_store:
        raise JobError(
            f"job {job.name}: its store would hold up to {format_size(e.store_bytes)} "
            f"({grid} = {e.cells} cells × {e.cell_bytes} B, uncompressed), more than the limit "
            f"{format_size(max_store)}: shrink the grid, or raise the limit with "
            f"--max-store {format_size(e.store_bytes, plain=True)}"
        )
    if e.rank_bytes > max_memory:
        raise JobError(
            f"job {job.name}: each rank would need about {format_size(e.rank_bytes)} of memory "
            f"(a tile of {job.tiles.rows} chains × {job.shape[1]} {job.first} × {e.cell_bytes} B, "
            f"{TILE_COPIES} copies, plus {format_size(BASE_MEMORY)}), more than the limit "
            f"{format_size(max_memory)}: lower tiles.rows or the omega points, or raise the "
            f"limit with --max-memory {format_size(e.rank_bytes, plain=True)}"
        )
    return e


def format_size(n: float, plain: bool = False) -> str:
    """1.5 GiB, 300 MiB, … (``plain``: "2G", rounded up, as ``parse_size`` reads it)."""
    for unit in ("T", "G", "M", "k"):
        if n >= UNITS[unit.lower()]:
            value = n / UNITS[unit.lower()]
            return f"{int(-(-value // 1))}{unit}" if plain else f"{value:.1f} {unit}iB"
    return f"{int(n)}" if plain else f"{int(n)} B"


def parse_size(text: str) -> int:
    """Bytes from "64G", "500M", "2T", "1048576" (binary units; a trailing B/iB allowed)."""
    match = re.fullmatch(r"\s*(\d+(?:\.\d+)?)\s*([kKmMgGtT]?)(?:i?[bB])?\s*", str(text))
    if not match:
        raise ValueError(f"expected a size such as 64G, 500M or 2T, got {text!r}")
    return int(float(match.group(1)) * UNITS[match.group(2).lower()])
