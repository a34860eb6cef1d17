"""Running a job: the serial runner, the MPI master and workers, signals, the run log.

One scheduling loop serves both runners. The ``Master`` hands tiles to lanes —
the compute thread of its own process, and under MPI one lane per worker
rank — commits each finished tile to the store, and stops on a signal. Who
writes a tile's arrays depends on the backend (``Store.direct_writes``): into a
Zarr store every worker writes its own tiles' chunks (on a thread of its own,
while its lane computes the next tile) and the master only commits them
(checksum, then ``done``: a fraction of writing it, docs/scaling.md); into
HDF5 (serial h5py) the master writes every tile, as it does a job's with no
more tiles pending than workers (``workers_write_tiles``). ``CAMPAR_WRITER=master``
makes the master write Zarr tiles too (the single-writer path, for comparison).
The kernel's ``run_chain`` releases the GIL, so the master's compute thread
keeps a core busy while its main thread does every MPI call, store write and
signal check: with two ranks on two cores both cores compute.

Every lane holds its next tile as well (``TILES_HELD``, while the queue has one for
every lane): it starts it the moment the last one is done, whatever the master is
doing, instead of waiting for the master's answer and the GIL. The master
probes every ≤ 1 ms, except while every lane is provided for — holds its next tile, and
no worker is writing one (``provided_for``) —: then it waits on its own lane for up to a
quarter of the shortest tile, which on the 2-rank plane wakes it a quarter as often
(docs/scaling.md). It does not wait while a worker writes: a master that waits whenever
every lane holds two tiles falls behind at 16 stand-in ranks.

The wire protocol between the master and its worker ranks is ``campar.sweep.wire``'s.

Signals (SIGTERM, SIGINT, SIGUSR1 — mpich's mpirun forwards all three to every
rank): the first one stops handing out tiles, takes back those queued on lanes and
collects those being computed for up to ``grace`` seconds; a second one, or the end of
the grace, abandons them. The run is logged and ``Interrupted`` (exit 75) raised; running the same
command again resumes with the tiles whose ``done`` is unset.

mpi4py is imported only by ``wire``, and only when the process was started by an
MPI launcher, so ``campar --help`` and serial runs never load MPI.
"""

import contextlib
import logging
import queue
import signal
import socket
import threading
import time
import traceback
from collections import Counter, deque
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import CamparError, Interrupted, JobError, StoreIOError
from .budget import check_budget
from .curves_job import NOT_THE_KERNELS, CurvesWork
from .job import Job, check_store_path
from .plan import Tile, auto_tile_rows, pending_tiles, plan_tiles
from .progress import Progress, peak_rss_mb, setup_logging  # noqa: F401 (the CLI's)
from .signals import Signals, early_interruption
from .store import open_store, read_store, takes_direct_writes
from .tile import compile_kernel, load_kernel, located_cache_dir, run_tile
from .wire import (
    BACKOFF_SECONDS,
    TILES_HELD,
    Backoff,
    Outcome,
    Workers,
    cache_sharers,
    direct_path,
    mpi_world,
    receive_outcome,
    share_outcome,
    wait,
    work,
    workers_write,
)

log = logging.getLogger("campar.run")

MAX_ATTEMPTS = 2  # a tile that fails on two lanes ends the run
BYE_SECONDS = 10.0  # how long the master waits for workers to leave after STOP
SIGNAL_CHECK_SECONDS = 0.05  # a serial run's idle wait: signals are seen within this
PATIENT_WAIT_SECONDS = 0.02  # the master's longest wait while every lane is provided for


class ThreadLane:
    """Runs tiles on a daemon thread so the calling thread stays free for MPI and signals.

    It holds up to ``TILES_HELD`` tiles: the one it computes and the next, which it
    starts the moment the first is done, without waiting for the master (which may be
    writing a tile, holding the GIL, or busy with other ranks) — unless ``halted()``
    says a stop signal came: then the next waits for the master to take it back."""

    def __init__(
        self,
        job: Job,
        where: str,
        preload: bool = False,
        halted=lambda: False,
        share=None,
        tile_work: CurvesWork | None = None,
    ):
        """With ``preload`` the thread first loads the kernel (``load_kernel``, a cold
        compile split as ``share`` says) while the caller waits for the master; tiles
        queue behind it. ``tile_work``: what computes the tiles where the kernel does not.
        ``warm`` says whether the kernel is loaded (``Master.local_takes``): at once
        unless ``preload``, else once the load is over."""
        self.job, self.where, self.preload, self.halted = job, where, preload, halted
        self.share, self.tile_work = share, tile_work
        # Whether the kernel is loaded (set by the thread; a failed load counts: the first
        # tile meets the error and reports it).
        self.warm = not preload
        self.held: list[int] = []  # tiles started or queued, not yet reported, in order
        self.seconds = 0.0
        self.shortest_tile = float("inf")  # seconds, of the tiles it reported
        self._queued: deque = deque()  # tiles not started, then None once closed
        self._changed = threading.Condition()
        # queue.Queue, not SimpleQueue: CPython 3.11's SimpleQueue.get(timeout) can block
        # for good when a signal interrupts it (measured), which would deafen the master.
        self._outbox = queue.Queue()
        self._thread = threading.Thread(target=self._loop, daemon=True, name="campar-compute")
        self._thread.start()

    def start(self, tile: Tile) -> None:
        """Compute ``tile`` after those the lane holds."""
        self.held.append(tile.index)
        self._put(tile)

    def withdraw(self) -> list[Tile]:
        """Take back the tiles queued and not yet started (a stop: only started ones run)."""
        with self._changed:
            taken = [tile for tile in self._queued if tile is not None]
            self._queued = deque(tile for tile in self._queued if tile is None)
            self._changed.notify()
        for tile in taken:
            self.held.remove(tile.index)
        return taken

    def poll(self, timeout: float = 0.0) -> Outcome | None:
        """The finished tile, waiting up to ``timeout`` s for it (woken the moment it is)."""
        try:
            out = self._outbox.get(timeout=timeout) if timeout > 0 else self._outbox.get_nowait()
        except queue.Empty:
            return None
        self.held.remove(out.index)
        self.seconds += out.seconds
        self.shortest_tile = min(self.shortest_tile, out.seconds)
        return out

    def close(self, wait: bool = False) -> None:
        """Drop the queued tiles and end the thread; a tile in progress is abandoned (the
        daemon thread dies with the process) unless ``wait``, the kernel load never: a
        process that ends while a thread is inside llvmlite can crash (a segmentation fault
        under mpirun, when a Ctrl-C stops a run while a rank's lane still loads)."""
        self.withdraw()
        self._put(None)
        if wait or not self.warm:
            self._thread.join()

    def _put(self, tile: Tile | None) -> None:
        with self._changed:
            self._queued.append(tile)
            self._changed.notify()

    def _next(self) -> Tile | None:
        """The next tile to compute (None: closed); a tile waits while ``halted()``."""
        with self._changed:
            while not self._queued or (self._queued[0] is not None and self.halted()):
                self._changed.wait()  # woken by start, withdraw or close
            return self._queued.popleft()

    def _loop(self):
        try:
            if self.preload:
                (self.tile_work.load if self.tile_work else load_kernel)(self.job, self.share)
        except Exception:  # the first tile meets the same error and reports it
            log.debug("loading the kernel ahead failed", exc_info=True)
        self.warm = True
        while (tile := self._next()) is not None:
            start = time.perf_counter()
            try:
                compute = self.tile_work.tile if self.tile_work else run_tile
                arrays, error = compute(self.job, tile), None
            except Exception:
                arrays, error = None, f"{self.where}: {traceback.format_exc()}"
            self._outbox.put(Outcome(tile.index, arrays, error, time.perf_counter() - start))


# -- the master ---------------------------------------------------------------------------


class Master:
    """Hands pending tiles to lanes, writes results, and stops on request."""

    def __init__(self, job, store, tiles, progress, grace, lane, comm=None, direct=False):
        self.job, self.store, self.progress, self.grace = job, store, progress, grace
        self.tiles = plan_tiles(job)
        self.queue = deque(tiles)
        self.failed_on: dict[int, list[int]] = {}  # tile → lanes (ranks) it failed on
        self.tiles_by_lane = Counter()
        self.host = socket.gethostname()
        self.local = lane
        self.workers = Workers(comm, job) if comm is not None else None
        self.stop_reason: str | None = None
        self.failure: str | None = None
        self.abandon_at = None
        self.cpu = time.process_time()  # at the start of the run
        self.direct = direct  # the workers write their own tiles (the master commits them)

    def stop(self, reason: str) -> None:
        """Hand out no more tiles and take back those queued on lanes: only the started
        ones are collected."""
        if self.stop_reason is None:
            self.stop_reason = reason
            self.abandon_at = time.monotonic() + self.grace
            log.warning("%s: no more tiles handed out; waiting for tiles in flight", reason)
            self.queue.extendleft(reversed(self.local.withdraw()))
            if self.workers:
                self.workers.withdraw()  # their answers come as "withdrawn" events

    @property
    def in_flight(self) -> int:
        """Tiles handed out and not yet back: computing, queued on a lane, or written by
        their worker."""
        return len(self.local.held) + (self.workers.in_flight if self.workers else 0)

    def handle(self, out) -> None:
        """Act on a notice or a failure; results are only counted (``write`` stores them)."""
        if isinstance(out, tuple) and out[0] == "withdrawn":  # back from a worker's lane
            self.queue.extendleft(self.tiles[i] for i in reversed(out[1]))
        elif isinstance(out, tuple):  # a worker's signal notice
            self.stop(f"{signal.Signals(out[1]).name} at a worker")
        elif out.error is None:
            return
        elif out.io_error:  # as if the master's own write had failed
            raise StoreIOError(out.error)
        else:
            failed_on = self.failed_on.setdefault(out.index, [])
            failed_on.append(out.lane)
            log.error("tile %d failed: %s", out.index, out.error.rstrip())
            if len(failed_on) < MAX_ATTEMPTS:
                self.queue.appendleft(self.tiles[out.index])  # retried, on another lane if any
            else:
                where, _, trace = out.error.partition(": ")
                self.failure = (
                    f"tile {out.index} failed {len(failed_on)}×, last on {where}: "
                    f"{trace.strip().splitlines()[-1]} (tracebacks above)"
                )
                self.stop(f"tile {out.index} failed")

    def run(self, signals: Signals) -> None:
        try:
            self._loop(signals)
        finally:
            if self.in_flight:
                log.warning("abandoning %d tile(s) in flight", self.in_flight)
            self.local.close()
            self.dismiss_workers()

    def save(self, outcomes: list[Outcome]) -> None:
        """Store finished tiles: write those that came with their arrays, then commit those
        their workers wrote, all at once (a group commit: two store writes for the lot)."""
        for out in outcomes:
            if out.checksum is None:
                self.store.write_tile(self.tiles[out.index], out.arrays)
        written = [(self.tiles[o.index], o.checksum) for o in outcomes if o.checksum is not None]
        if written:
            self.store.commit_tiles(written)
        for out in outcomes:
            self.tiles_by_lane[out.lane] += 1
            self.progress.tile_done(self.tiles[out.index].n_rows * self.job.shape[1])

    def _loop(self, signals: Signals) -> None:
        backoff = Backoff()
        while True:
            # Idle waits happen here, on the compute thread's outbox: woken at once by it.
            # Serial runs have no messages to probe for: they only check signals now and then.
            if self.workers:
                timeout = self.patient_wait() if self.provided_for else backoff.delay()
            else:  # an idle lane gets its tile without waiting
                timeout = SIGNAL_CHECK_SECONDS if self.local.held else 0.0
            events = [out] if (out := self.local.poll(timeout)) else []
            events += self.workers.poll() if self.workers else []
            # After the wait, before any hand-out: a signal that came during it hands out nothing
            if signals.count:
                self.stop(signal.Signals(signals.last).name)
                if signals.insist:
                    self.abandon_at = time.monotonic()
            for event in events:
                self.handle(event)
            self.hand_out()  # before writing: no lane waits for the store
            self.save([e for e in events if isinstance(e, Outcome) and e.error is None])
            if self.stop_reason and (self.in_flight == 0 or time.monotonic() >= self.abandon_at):
                break
            if not self.queue and self.in_flight == 0:
                break
            if events:
                backoff.reset()

    @property
    def n_lanes(self) -> int:
        return 1 + (self.workers.comm.Get_size() - 1 if self.workers else 0)

    @property
    def provided_for(self) -> bool:
        """Whether no lane can need the master soon: every one holds its next tile and no
        worker writes (its WRITTEN is due within milliseconds, and a tile ahead with it)."""
        if self.stop_reason is not None or len(self.local.held) < TILES_HELD:
            return False
        ranks = self.workers.open_ranks()
        return len(ranks) == self.n_lanes - 1 and all(
            self.workers.holding(rank) >= TILES_HELD and not self.workers.writing[rank]
            for rank in ranks
        )

    def patient_wait(self) -> float:
        """The master's wait between probes while every lane is provided for: a quarter of
        the shortest tile yet (the least a lane's queued tile keeps it busy) — the local
        lane's result wakes it at once —, at most ``PATIENT_WAIT_SECONDS``; before any
        tile is back, ``BACKOFF_SECONDS``."""
        shortest = min(self.local.shortest_tile, self.workers.shortest_tile)
        if shortest == float("inf"):
            return BACKOFF_SECONDS
        return min(PATIENT_WAIT_SECONDS, max(BACKOFF_SECONDS, shortest / 4))

    def next_tile(self, lane: int) -> Tile | None:
        """The first pending tile that did not fail on ``lane`` (a retry goes elsewhere)."""
        for i, tile in enumerate(self.queue):
            if self.n_lanes == 1 or lane not in self.failed_on.get(tile.index, ()):
                del self.queue[i]
                return tile
        return None

    def hand_out(self) -> None:
        """Every lane its next tile, the workers' first (``local_takes``); then, while the
        queue holds one for every lane, one more to keep (``TILES_HELD``). A worker holding
        nothing once the queue is empty is told to stop."""
        ranks = self.workers.open_ranks() if self.workers else []
        if self.stop_reason is None:
            for depth in range(1, TILES_HELD + 1):
                if depth > 1 and len(self.queue) < self.n_lanes:
                    break  # near the end a queued tile would wait for its lane: no lane keeps one
                for rank in ranks:
                    if self.workers.room(rank, depth) and (tile := self.next_tile(rank)):
                        self.workers.assign(rank, tile)
                if self.local_takes(depth) and (tile := self.next_tile(0)):
                    self.local.start(tile)
        if self.stop_reason is not None or not self.queue:
            for rank in ranks:
                if not self.workers.holding(rank):
                    self.workers.stop(rank)

    def local_takes(self, depth: int) -> bool:
        """Whether the master's own lane takes a tile to hold ``depth``. Under MPI its lane
        loads the kernel after the store is open, after every worker's lane began to: while
        it loads, a tile goes to it only once every worker (ready or still to say so) holds
        one or cannot take the next (it failed there), so a job of fewer tiles than ranks is
        computed by the lanes that are warm first (a one-cell job by a worker, about a
        kernel load sooner)."""
        if len(self.local.held) >= depth:
            return False
        if self.workers is None or self.local.warm or not self.queue:
            return True
        failed = self.failed_on.get(self.queue[0].index, ())
        return not any(
            rank not in self.workers.stopped
            and not self.workers.holding(rank)
            and rank not in failed
            for rank in range(1, self.workers.comm.Get_size())
        )

    def dismiss_workers(self) -> None:
        """STOP every worker (busy ones abandon their tile) and wait for each to say BYE."""
        if self.workers is None:
            return
        deadline = time.monotonic() + BYE_SECONDS
        backoff = Backoff()
        while not self.workers.all_gone and time.monotonic() < deadline:
            for rank in range(1, self.workers.comm.Get_size()):
                self.workers.stop(rank)
            events = self.workers.poll()
            # finished just before STOP: keep them
            self.save([e for e in events if isinstance(e, Outcome) and e.error is None])
            backoff.reset() if events else backoff.sleep()
        missing = sorted(set(range(1, self.workers.comm.Get_size())) - self.workers.gone)
        if missing:
            log.warning("ranks %s did not confirm STOP within %.0f s", missing, BYE_SECONDS)


# -- entry point ------------------------------------------------------------------------------


@dataclass
class RunSummary:
    outcome: str  # complete | nothing to do | worker
    entry: dict  # the run-log entry (empty on workers and when nothing was pending)


def run_job(
    job: Job,
    store_path: str | Path | None = None,
    *,
    overwrite=False,
    grace=30.0,
    max_store: int | None = None,
    max_memory: int | None = None,
    tile_work: CurvesWork | None = None,
):
    """Compute every pending tile of ``job`` into its store; serial, or MPI under mpirun.

    ``tile_work`` computes a curves job's tiles (campar.continuation.tasks.CURVES_WORK); the
    kernel computes every other kind's.

    Returns a RunSummary on completion; raises Interrupted (exit 75) after a
    signal and CamparError when a tile fails twice; JobError, before anything
    touches the disk, if the store or a rank's memory would exceed ``max_store``
    or ``max_memory`` bytes (``budget``'s defaults if None). Under MPI every rank
    returns or raises alike (workers' errors carry ``rank``; the master reports them).
    """
    if (job.kind == "curves") != (tile_work is not None):
        raise ValueError(
            NOT_THE_KERNELS if tile_work is None else "tile_work is a curves job's alone"
        )
    path = job.store if store_path is None else store_path
    if path is None:
        raise JobError(f"job {job.name} names no store: add 'store: PATH' or pass --store PATH")
    try:
        check_store_path(path)
    except ValueError as exc:
        raise JobError(f"store {str(path)!r}: {exc}") from None
    if job.tiles.rows != "auto":
        check_budget(job, max_store=max_store, max_memory=max_memory)
    with Signals() as signals:
        comm = mpi_world()
        if job.tiles.rows == "auto":  # every rank the same number (rank 0's), then the budget
            job = job.with_tile_rows(agreed_tile_rows(job, path, comm, overwrite))
            check_budget(job, max_store=max_store, max_memory=max_memory)
        where = f"on {socket.gethostname()}"
        share = None if comm is None else cache_sharers(comm, str(located_cache_dir()))

        def halted() -> bool:  # a lane starts no tile once a stop signal came
            return signals.count > 0

        if comm is not None and comm.Get_rank() > 0:
            # The worker's lane loads the kernel while rank 0 opens the store (in rank 0's
            # own process the two would take turns on the GIL).
            lane = ThreadLane(
                job, f"rank {comm.Get_rank()} {where}", True, halted, share, tile_work
            )
            try:  # of opening the store: where to write, if at all
                direct = receive_outcome(comm)
            except BaseException:  # a refusal: the process ends once the kernel is loaded
                lane.close()
                raise
            work(comm, job, signals, lane, direct)
            receive_outcome(comm)  # of the run
            return RunSummary("worker", {})
        # Serial: compiled (or loaded) before the store opens and before the lane's thread
        # starts: the process then has one thread (zarr starts one of its own where a
        # resume verifies the store), so a cold compile may fork a helper (split_compile),
        # and the first tile runs at full speed. A store with nothing pending then has
        # loaded the kernel for nothing (a compile if the cache is cold).
        # Under MPI every worker waits for the store: rank 0 opens it first, and its lane
        # loads the kernel as a worker's does (a cold compile split between the ranks of a
        # node, ``share``) while the master hands out tiles, so the workers start one
        # kernel load sooner (benchmarks/RESULTS.md, "Start-up").
        if comm is None:
            (tile_work.load if tile_work else compile_kernel)(job, share)
            lane = ThreadLane(job, f"rank 0 {where}", halted=halted, tile_work=tile_work)
        opened = {}
        with share_outcome(comm, opened):
            store = open_store(path, job, overwrite=overwrite)
            opened["text"] = direct_path(store) if workers_write_tiles(job, store, comm) else ""
        if comm is not None:
            lane = ThreadLane(job, f"rank 0 {where}", True, halted, share, tile_work)
        with store, share_outcome(comm):
            return run_master(job, store, signals, comm, grace, lane, bool(opened["text"]))


def workers_write_tiles(job: Job, store, comm) -> bool:
    """Whether the workers are to write their own tiles where the store lets them
    (``wire.direct_path``): unless the job has no more tiles pending than workers. Each
    of them then computes about one tile, and the master writes a few tiles for less than
    a worker's import of the store's backend costs (zarr's: about a tenth of a second of
    CPU, after its tile, on the run's critical path; benchmarks/RESULTS.md)."""
    return comm is None or len(pending_tiles(job, store.done)) > comm.Get_size() - 1


# Errors a worker re-raises after the master (by index); others arrive as CamparError.


def agreed_tile_rows(job: Job, path, comm, overwrite: bool) -> int:
    """``tiles.rows`` of a job that says ``auto``: the store's, where it holds this job
    already (a resume keeps its layout, whatever the ranks now), else ``auto_tile_rows``
    for the ranks and the writer; decided on rank 0 and shared, so every rank plans the
    same tiles."""
    rows = np.zeros(1, np.int64)
    if comm is None or comm.Get_rank() == 0:
        rows[0], why = stored_tile_rows(job, path) if not overwrite else (0, "")
        if not rows[0]:
            direct = comm is not None and workers_write(takes_direct_writes(path))
            rows[0], why = auto_tile_rows(job, 1 if comm is None else comm.Get_size(), direct)
        log.info("tiles.rows %s", why)
    if comm is not None:
        wait(comm.Ibcast(rows, root=0))
    return int(rows[0])


def stored_tile_rows(job: Job, path) -> tuple[int, str]:
    """(rows, why) of the store at ``path`` if it holds this job but for ``tiles``, else 0."""
    with contextlib.suppress(Exception):  # no store, or not one of this job: choose anew
        with read_store(path) as reader:
            stored = reader.job
        if stored.with_tile_rows(1) == job.with_tile_rows(1):
            return stored.tiles.rows, f"{stored.tiles.rows}, as the store {path} has it"
    return 0, ""


def run_master(job, store, signals, comm, grace, lane, direct=False) -> RunSummary:
    tiles = pending_tiles(job, store.done)
    all_tiles = plan_tiles(job)
    n_rows, n_omega = job.shape
    done_cells = sum(t.n_rows for t in all_tiles if store.done[t.index]) * n_omega
    total_cells = n_rows * n_omega * len(job.directions)
    progress = Progress(len(all_tiles), total_cells, len(all_tiles) - len(tiles), done_cells)
    master = Master(job, store, tiles, progress, grace, lane, comm, direct)
    if not tiles:
        log.info("%s: all %d tiles are done already", store.path, len(all_tiles))
        master.run(signals)  # dismisses the workers
        return RunSummary("nothing to do", {})
    try:
        master.run(signals)
    except BaseException:
        # Log what was done (best effort: the store may be what failed), then re-raise.
        with contextlib.suppress(Exception):
            store.log_run(progress.entry("error", **usage(master)))
        raise
    finally:
        progress.close()
    remaining = int((~store.done).sum())
    outcome = "failed" if master.failure else "interrupted" if remaining else "complete"
    entry = progress.entry(outcome, **usage(master))
    store.log_run(entry)
    log.info(
        "%s: %s, %d tiles (%d cells) in %.1f s, %.1f cells/s",
        store.path,
        outcome,
        entry["tiles"],
        entry["cells"],
        entry["seconds"],
        entry["cells_per_s"],
    )
    if master.failure:
        raise CamparError(master.failure)
    if remaining and signals.early and entry["tiles"] == 0:  # under MPI, before the start
        raise early_interruption(signals.last)
    if remaining:
        why = master.stop_reason or "tiles damaged on disk since they were written (logged above)"
        raise Interrupted(
            f"stopped by {why} with {remaining} of {len(all_tiles)} tiles "
            f"pending; run the same command again to resume"
        )
    return RunSummary(outcome, entry)


def writer_of(master: Master) -> str:
    """Who wrote the workers' tiles: "workers" (each its own), "master", or "mixed" (ranks
    that did not see the store sent theirs to the master)."""
    kinds = set(master.workers.writers.values()) if master.workers else set()
    if not kinds:
        return "workers" if master.direct else "master"
    return "mixed" if len(kinds) > 1 else {"worker": "workers", "master": "master"}[kinds.pop()]


def usage(master: Master) -> dict:
    """Who computed what, and at what cost, for the run log (per rank: None if unknown)."""
    w, others = master.workers, range(1, master.n_lanes)
    return {
        "ranks": master.n_lanes,
        "writer": writer_of(master),
        "host": master.host,
        "hosts": sorted({master.host, *(w.hosts.values() if w else ())}),
        "compute_seconds": round(master.local.seconds + (w.seconds if w else 0), 3),
        "tiles_per_rank": [master.tiles_by_lane[r] for r in range(master.n_lanes)],
        "cpu_seconds": [round(time.process_time() - master.cpu, 3)]
        + [w.cpu.get(r) for r in others],
        "peak_rss_mb": [round(peak_rss_mb(), 1), *(w.rss.get(r) for r in others)],
    }
