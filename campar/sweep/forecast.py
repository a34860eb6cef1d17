"""What a run of a job would do, before it runs: ``campar run JOB --dry-run``.

Cells, tiles (``tiles.rows: auto`` resolved for the ranks, or kept as a store of this job
has it), what a store of it already holds, the store's size and each rank's memory
(``budget.estimate``), and an estimated time. Nothing is written; the store, if there is
one, is only read.

The time estimate is measured, not modelled: a few of the job's own chains (rows spread
over its second axis, ``SAMPLE_ROWS``, fewer once they take ``SAMPLE_SECONDS``) are
computed here, their results dropped, and timed in CPU seconds of this process. Their
mean cost a cell, times the pending cells, divided among the ranks (every rank computes,
rank 0 too), is the estimate when each rank has a core to itself. CPU time leaves out the
waits for a core that other programs cause, but a loaded machine still slows each core
(shared caches, a virtual machine's stolen time): the estimate holds for the machine as
loaded while it was made. A cell's cost depends on the grid's spacing (a warm start from
a nearer neighbour settles sooner), the transient, the outputs and the region (chaos
takes the whole budget), which a sample of the job's own rows captures and a model of a
typical cell (the planner's ``plan.cell_seconds``) does not. The numba cache is used as a
run uses it (a cold one is compiled first, as the run would). A store's logged runs give
the rate it met, shown beside the estimate.
"""

import contextlib
import time
from dataclasses import dataclass
from pathlib import Path

from ..errors import JobError
from .budget import check_budget, estimate, format_size
from .job import Job
from .plan import Tile, auto_tile_rows, plan_tiles

SAMPLE_ROWS = 5  # chains timed for the estimate, spread over the second axis
SAMPLE_SECONDS = 2.0  # … fewer once the sample has taken this long


@dataclass(frozen=True)
class Forecast:
    """The plan and cost of running ``job`` into ``store`` with ``ranks`` MPI ranks."""

    job: Job  # tiles.rows resolved
    store: str | None
    ranks: int
    tiles: int
    cells: int
    pending_tiles: int  # not committed in the store yet (all, for a new store)
    pending_cells: int
    store_state: str  # "new", "holds this job", or why a run would refuse or replace it
    store_bytes: int  # uncompressed, upper bound
    rank_bytes: int  # peak memory of one rank
    seconds: float  # estimated wall time of the pending cells on ``ranks`` ranks
    cell_seconds: float  # CPU seconds a cell, measured on the sample
    sampled_rows: int  # chains the sample computed
    logged_cells_per_s: float | None  # the store's runs so far (None: none logged)
    limits_exceeded: str | None  # the refusal ``campar run`` would print, if any

    def describe(self) -> str:
        """The text ``campar run --dry-run`` prints."""
        job = self.job
        directions = " × 2 directions" if len(job.directions) > 1 else ""
        grid = f"{job.shape[0]} {job.second} × {job.shape[1]} {job.first}{directions}"
        lines = [
            f"job      {job.name}",
            f"store    {self.store or '(none: give --store PATH)'}  ({self.store_state})",
            f"cells    {self.cells:,} ({grid}), {self.pending_cells:,} to compute",
            f"tiles    {self.tiles:,} of {job.tiles.rows} rows, {self.pending_tiles:,} to compute",
            f"size     up to {format_size(self.store_bytes)} (uncompressed)",
            f"memory   about {format_size(self.rank_bytes)} per rank",
            f"time     about {duration(self.seconds)} on {self.ranks} rank"
            + ("s" if self.ranks != 1 else ""),
            f"         ({self.cell_seconds * 1e6:,.0f} µs of CPU a cell, timed on "
            f"{self.sampled_rows} of its {job.shape[0]} chains just now; a core for each rank)",
        ]
        if self.logged_cells_per_s:
            at_rate = self.pending_cells / self.logged_cells_per_s
            lines.append(
                f"         {duration(at_rate)} at this store's logged "
                f"{self.logged_cells_per_s:,.0f} cells/s"
            )
        if self.limits_exceeded:
            lines.append(f"refused  {self.limits_exceeded}")
        return "\n".join(lines)


def forecast(
    job: Job,
    store: str | Path | None = None,
    *,
    ranks: int = 1,
    overwrite: bool = False,
    max_store: int | None = None,
    max_memory: int | None = None,
    tile_work=None,
) -> Forecast:
    """The plan and cost of ``campar run`` of ``job`` into ``store`` (default: the job's)
    on ``ranks`` ranks, computing nothing and writing nothing; ``tile_work`` as run_job's."""
    path = store or job.store
    stored, done, kernel = stored_state(job, path) if path and not overwrite else (None,) * 3
    if job.tiles.rows == "auto":
        if stored is not None:
            job = job.with_tile_rows(stored.tiles.rows)
        else:
            direct = ranks > 1 and path is not None and writers_are_workers(path)
            job = job.with_tile_rows(auto_tile_rows(job, ranks, direct)[0])
    tiles = plan_tiles(job)
    cells_of = [t.n_rows * job.shape[1] for t in tiles]
    exists = bool(path) and Path(path).exists()
    if stored is not None:
        state = "holds this job"
    elif not path:
        state = "a run refuses a job without one"
    elif not exists:
        state = "new"
    elif overwrite:
        state = "replaced: --overwrite"
    elif kernel is not None:
        state = f"holds this job, {kernel}: a run refuses it unless --overwrite"
    else:
        state = "not a readable store of this job: a run refuses it unless --overwrite"
    done = done or [False] * len(tiles)
    pending = [i for i, d in enumerate(done) if not d]
    pending_cells = sum(cells_of[i] for i in pending)
    cost = estimate(job)
    per_cell, sampled = sample_cost(job, tile_work) if pending_cells else (0.0, 0)
    refused = None
    try:
        check_budget(job, max_store=max_store, max_memory=max_memory)
    except JobError as exc:  # the refusal, as campar run would say it
        refused = str(exc)
    return Forecast(
        job=job,
        store=None if path is None else str(path),
        ranks=ranks,
        tiles=len(tiles),
        cells=cost.cells,
        pending_tiles=len(pending),
        pending_cells=pending_cells,
        store_state=state,
        store_bytes=cost.store_bytes,
        rank_bytes=cost.rank_bytes,
        seconds=pending_cells * per_cell / ranks,
        cell_seconds=per_cell,
        sampled_rows=sampled,
        logged_cells_per_s=logged_rate(stored_runs(path) if stored is not None else []),
        limits_exceeded=refused,
    )


def sample_cost(job: Job, tile_work=None) -> tuple[float, int]:
    """(CPU seconds a cell, rows timed): up to SAMPLE_ROWS of the job's chains, spread
    over its second axis, computed and timed (the kernel loaded, and a ``continue`` job's
    first column computed, before the clock starts)."""
    from .tile import load_kernel, run_tile

    load, compute = (tile_work.load, tile_work.tile) if tile_work else (load_kernel, run_tile)
    load(job, None)
    n_rows, n_cells = job.shape
    rows = sorted({round(i * (n_rows - 1) / max(SAMPLE_ROWS - 1, 1)) for i in range(SAMPLE_ROWS)})
    rows = [rows[len(rows) // 2], *(r for i, r in enumerate(rows) if i != len(rows) // 2)]
    direction = job.directions[0] if len(job.directions) > 1 else None
    start = time.process_time()
    timed = 0
    for row in rows:  # the middle row first: the one a short sample keeps
        compute(job, Tile(-1, row, row + 1, direction))
        timed += 1
        if time.process_time() - start > SAMPLE_SECONDS:
            break
    return (time.process_time() - start) / (timed * n_cells), timed


def writers_are_workers(path) -> bool:
    """Whether, under MPI, the workers would write their own tiles into ``path``."""
    import os

    from .store import takes_direct_writes

    return takes_direct_writes(path) and os.environ.get("CAMPAR_WRITER") != "master"


def stored_state(job: Job, path) -> tuple[Job | None, list | None, str | None]:
    """(the stored job, its done flags, None) if ``path`` is a store of ``job`` (by its
    digest, tiles.rows aside: ``auto`` keeps a store's layout) that a run resumes; (None,
    None, which kernel computed it) for one another kernel computed (a run refuses it);
    else (None,) * 3."""
    from .store import other_kernel, read_store

    # No store, a damaged one or another job's: the run decides (refuses, or repairs).
    with contextlib.suppress(Exception), read_store(path) as reader:
        if reader.job.with_tile_rows(1).digest() == job.with_tile_rows(1).digest():
            kernel = other_kernel(reader.attrs)
            if kernel is not None:
                return None, None, kernel
            return reader.job, reader.done.tolist(), None
    return None, None, None


def stored_runs(path) -> list[dict]:
    from .store import read_store

    with read_store(path) as reader:
        return list(reader.attrs.get("runs", []))


def logged_rate(runs: list[dict]) -> float | None:
    """Cells per second over a store's logged runs (None if none computed a cell)."""
    cells = sum(r.get("cells", 0) for r in runs)
    seconds = sum(r["seconds"] for r in runs if isinstance(r.get("seconds"), (int, float)))
    return cells / seconds if cells and seconds > 0 else None


def duration(seconds: float) -> str:
    """ "40 s", "12 min", "3.5 h": an estimate's precision."""
    if seconds < 90:
        return f"{max(seconds, 1):.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"
