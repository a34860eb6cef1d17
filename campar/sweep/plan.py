"""Tiles and chains of a job's grid.

A chain is one row of the grid: one value of the second parameter, every ω in
the order of ``chains.direction`` (ω decreasing in the paper's planes); with
``chains.start: continue`` the first cells of the rows are themselves one chain
along the second axis, the plane's first column. A tile is ``tiles.rows``
consecutive chains (``auto``: chosen for the ranks when the store is created,
``auto_tile_rows``). Tiles are fixed by the job alone, so the numbers never
depend on how many ranks ran it or where it was interrupted; a tile is the unit
of work, of storage (one chunk) and of the ``done`` commit flag.

A ``chains.direction: both`` job has every tile twice: tiles 0 … T−1 run their
chains down, tiles T … 2T−1 the same rows up (``Tile.direction``), each exactly
as the tile of a one-direction job (``Job.one_direction``) would. Its per-cell
arrays carry a leading ``direction`` axis (``DIRECTIONS`` order) and a tile is
one chunk of one layer of it (``Tile.region``). One tile plan, one ``done`` and
one ``checksum`` per tile, so resume, verification, repair, ``campar status``
and the MPI runner treat the two directions' tiles alike, with no new commit
protocol; tiles of one-direction jobs have no direction and stores of them are
laid out as before.
"""

import math
from dataclasses import dataclass

import numpy as np

from .job import DIRECTIONS, Job


@dataclass(frozen=True)
class Tile:
    index: int
    row_start: int  # first chain (index along the second axis)
    row_stop: int  # one past the last
    direction: str | None = None  # of a ``both`` job's tile; None: the job's one direction

    @property
    def rows(self) -> slice:
        return slice(self.row_start, self.row_stop)

    @property
    def layer(self) -> int | None:
        """Index of the tile's direction along the store's ``direction`` axis (None: none)."""
        return None if self.direction is None else DIRECTIONS.index(self.direction)

    @property
    def region(self) -> tuple:
        """The tile's part of a per-cell array of the store: (rows,) or (layer, rows)."""
        return (self.rows,) if self.direction is None else (self.layer, self.rows)

    @property
    def n_rows(self) -> int:
        return self.row_stop - self.row_start


# ``tiles.rows: auto`` (``auto_tile_rows``) weighs a tile's compute against the rate the
# master commits tiles, with rough costs whose order of magnitude is all the choice needs
# (rounded down from ``campar bench master`` and the (ω, μcn) plane, benchmarks/RESULTS.md,
# so a faster machine still gets tiles long enough): a revolution of a core, the
# revolutions of a converged map cell (a fixed transient: its revolutions and window), a
# census cell K + 1 cells, a basin cell (a cold start) four; the commits a second when the
# workers write their own tiles (Zarr) and when the master writes every tile (HDF5).
REVOLUTION_SECONDS = 1.75e-5
CONVERGED_REVOLUTIONS = 8
BASIN_CELL_FACTOR = 4.0
COMMITS_PER_SECOND = {True: 550.0, False: 60.0}  # by "workers write their own tiles"
WRITER_HEADROOM = 3.0  # tiles arrive at most at a third of that rate
TILES_PER_LANE = 4  # for the last tiles' tail: each lane gets at least this many
DEFAULT_ROWS = 4  # the default of tiles.rows: what auto keeps where nothing asks for other


def cell_seconds(job: Job) -> float:
    """Estimated CPU seconds of one cell of ``job`` (``REVOLUTION_SECONDS`` and the rest)."""
    fixed = job.transient.max_revolutions + job.classify.window_revolutions
    revolutions = CONVERGED_REVOLUTIONS if job.transient.mode == "converged" else fixed
    cost = REVOLUTION_SECONDS * revolutions * (BASIN_CELL_FACTOR if job.kind == "basin" else 1)
    return cost * (1 + job.attractors.starts if job.attractors is not None else 1)


def auto_tile_rows(job: Job, lanes: int, direct: bool) -> tuple[int, str]:
    """``tiles.rows`` for ``lanes`` computing ranks; returns (rows, why).

    Two bounds: the master must keep up — tiles arrive at lanes / tile time, at most a
    ``WRITER_HEADROOM``-th of what it commits (``COMMITS_PER_SECOND``; ``direct``: the
    workers write their own tiles) — and every lane should get ``TILES_PER_LANE`` tiles,
    so the slowest last tiles leave the others idle for a small part of the run. Between
    them, ``DEFAULT_ROWS`` where allowed (the layout of a map made without ``auto``); where
    the grid is too small for both, the master's bound wins (a master that cannot keep up
    idles every lane) and ``why`` says so.
    """
    n_rows, n_first = job.shape
    tiles_wanted = TILES_PER_LANE * lanes
    balance = max(1, (n_rows * len(job.directions)) // tiles_wanted)
    row_seconds = n_first * cell_seconds(job)
    rate = COMMITS_PER_SECOND[direct] / WRITER_HEADROOM
    writer = max(1, math.ceil(lanes / (rate * row_seconds)))
    rows = min(n_rows, max(writer, min(DEFAULT_ROWS, balance)))
    why = f"auto for {lanes} lane{'s' if lanes != 1 else ''}: {rows} rows a tile"
    if writer > balance:
        n_tiles = -(-n_rows // rows) * len(job.directions)
        why += (
            f"; the master's pace needs ≥ {writer} rows a tile and {tiles_wanted} tiles "
            f"would need ≤ {balance}: {n_tiles} tiles for {lanes} lanes, some idle at "
            "the end (more rows in the grid, or fewer ranks)"
        )
    return rows, why


def plan_tiles(job: Job) -> list[Tile]:
    """Every tile of the job, in index order; together they cover each cell once (each
    cell of each direction, for a ``both`` job: every row range down, then up)."""
    n_rows, _ = job.shape
    size = job.tiles.rows
    if size == "auto":
        raise ValueError(f"job {job.name}: tiles.rows auto is chosen when its store is created")
    ranges = [(start, min(start + size, n_rows)) for start in range(0, n_rows, size)]
    layers = DIRECTIONS if job.chains.direction == "both" else (None,)
    return [
        Tile(i, start, stop, direction)
        for i, (direction, (start, stop)) in enumerate((d, r) for d in layers for r in ranges)
    ]


def pending_tiles(job: Job, done: np.ndarray) -> list[Tile]:
    """Tiles whose ``done`` flag is unset, in index order."""
    tiles = plan_tiles(job)
    if done.shape != (len(tiles),):
        raise ValueError(f"done mask has shape {done.shape}, the job has {len(tiles)} tiles")
    return [tile for tile in tiles if not done[tile.index]]


def chain_order(job: Job) -> np.ndarray:
    """Indices into the job's ω axis in the order every chain runs (``chains.direction``):
    down, ω decreasing, or up, increasing; equal values keep the axis order. A ``both``
    job has two: ask its ``one_direction`` jobs."""
    if job.chains.direction not in DIRECTIONS:
        raise ValueError(f"chains.direction {job.chains.direction}: take one_direction first")
    omega = job.omega
    return np.argsort(-omega if job.chains.direction == "down" else omega, kind="stable")


def chain_parameters(job: Job, row: int) -> dict[str, np.ndarray]:
    """Per-cell parameter arrays of chain ``row``, in the order the chain runs."""
    omega = job.omega[chain_order(job)]
    values = {"omega": omega}
    second_value = job.second_values[row]
    for name in ("f0", "mu_kn", "mu_cn", "zeta"):
        value = second_value if name == job.second else job.parameter(name)
        values[name] = np.full(omega.shape, value)
    return values


def first_column_parameters(job: Job) -> dict[str, np.ndarray]:
    """Per-cell parameter arrays of the chain along the second axis (from ``from`` to
    ``to``) at the ω where every row's chain starts: the seed of ``chains.start: continue``."""
    n_rows, _ = job.shape
    omega = job.omega[chain_order(job)[0]]
    values = {"omega": np.full(n_rows, omega)}
    for name in ("f0", "mu_kn", "mu_cn", "zeta"):
        values[name] = (
            job.second_values if name == job.second else np.full(n_rows, job.parameter(name))
        )
    return values
