"""Running a job: the serial runner, the MPI master and workers, signals, the run log.

One scheduling loop serves both runners. The ``Master`` hands tiles to lanes —
the compute thread of its own process, and under MPI one lane per worker
rank — writes each finished tile to the store (rank 0 is the only writer),
and stops on a signal. The kernel's ``run_chain`` releases the GIL, so the
master's compute thread keeps a core busy while its main thread does every
MPI call, store write and signal check: with two ranks on two cores both
cores compute.

Wire protocol (mpi4py.futures style: plain data, ``STOP`` ends a worker, the
master never blocks in a receive — it probes and sleeps with a backoff capped
at 1 ms). Results travel as one packed byte buffer whose layout both sides
know from the job (``pack``/``unpack``), never as pickles:

    worker → master   READY (host)  |  RESULT [tile, ns] + arrays  |  ERROR [tile, ns] + text
                      NOTICE [signal]  |  BYE [peak RSS kB, CPU ns]
    master → worker   TILE [index], or TILE [STOP]

Signals (SIGTERM, SIGINT, SIGUSR1 — mpich's mpirun forwards all three to every
rank): the first one stops handing out tiles and collects those in flight
for up to ``grace`` seconds; a second one, or the end of the grace, abandons
them. The run is logged and ``Interrupted`` (exit 75) raised; running the same
command again resumes with the tiles whose ``done`` is unset.

mpi4py is imported only here, and only when the process was started by an MPI
launcher, so ``campar --help`` and serial runs never load MPI.
"""

import contextlib
import logging
import os
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

from ..errors import (
    CamparError,
    Interrupted,
    JobError,
    StoreDamaged,
    StoreError,
    StoreIOError,
    StoreLocked,
    StoreMismatch,
)
from .arrays import array_names
from .budget import check_budget
from .job import Job
from .plan import Tile, pending_tiles, plan_tiles
from .progress import Progress, peak_rss_mb, setup_logging  # noqa: F401 (the CLI's)
from .signals import Signals, early_interruption
from .store import cell_arrays, open_store, tile_shape
from .tile import run_tile

log = logging.getLogger("campar.run")

TAG_READY, TAG_TILE, TAG_RESULT, TAG_ERROR, TAG_NOTICE, TAG_BYE = range(11, 17)
STOP = -1
BACKOFF_SECONDS = 1e-3  # longest sleep of an idle loop between probes (mpi4py.futures)
MAX_ATTEMPTS = 2  # a tile that fails on two lanes ends the run
BYE_SECONDS = 10.0  # how long the master waits for workers to leave after STOP
SIGNAL_CHECK_SECONDS = 0.05  # a serial run's idle wait: signals are seen within this
MPI_LAUNCHER_ENV = ("PMI_SIZE", "PMI_RANK", "OMPI_COMM_WORLD_SIZE", "PMIX_RANK")


@dataclass
class Outcome:
    """A lane's report on one tile: its arrays, or the error text."""

    index: int
    arrays: dict | None
    error: str | None
    seconds: float
    lane: int = 0  # the rank that computed it


class Backoff:
    """Waits between idle polls: double from ~1 µs to ``BACKOFF_SECONDS``, reset on activity."""

    def __init__(self, longest: float = BACKOFF_SECONDS):
        self.longest, self.shortest, self.now = longest, longest / 1024, 0.0

    def reset(self) -> None:
        self.now = 0.0

    def delay(self) -> float:
        """The next wait, in seconds."""
        now, self.now = self.now, min(self.longest, max(self.shortest, 2 * self.now))
        return now

    def sleep(self) -> None:
        time.sleep(self.delay())


class ThreadLane:
    """Runs tiles on a daemon thread so the calling thread stays free for MPI and signals."""

    def __init__(self, job: Job, where: str):
        self.job, self.where = job, where
        self.busy: int | None = None
        self.seconds = 0.0
        # queue.Queue, not SimpleQueue: CPython 3.11's SimpleQueue.get(timeout) can block
        # for good when a signal interrupts it (measured), which would deafen the master.
        self._inbox, self._outbox = queue.Queue(), queue.Queue()
        threading.Thread(target=self._loop, daemon=True, name="campar-compute").start()

    def start(self, tile: Tile) -> None:
        self.busy = tile.index
        self._inbox.put(tile)

    def poll(self, timeout: float = 0.0) -> Outcome | None:
        """The finished tile, waiting up to ``timeout`` s for it (woken the moment it is)."""
        try:
            out = self._outbox.get(timeout=timeout) if timeout > 0 else self._outbox.get_nowait()
        except queue.Empty:
            return None
        self.busy = None
        self.seconds += out.seconds
        return out

    def close(self) -> None:
        # A tile in progress is abandoned: the daemon thread dies with the process.
        self._inbox.put(None)

    def _loop(self):
        while (tile := self._inbox.get()) is not None:
            start = time.perf_counter()
            try:
                arrays, error = run_tile(self.job, tile), None
            except Exception:
                arrays, error = None, f"{self.where}: {traceback.format_exc()}"
            self._outbox.put(Outcome(tile.index, arrays, error, time.perf_counter() - start))


# -- packing tile arrays into one buffer -----------------------------------------------


def tile_layout(job: Job, tile: Tile) -> list[tuple[str, np.dtype, tuple[int, ...]]]:
    """(name, dtype, shape) of each array of a tile, in ``array_names`` order."""
    return [(a.name, a.dtype, tile_shape(a, tile)) for a in cell_arrays(job)]


def pack(header: list[int], arrays: list[np.ndarray]) -> np.ndarray:
    """One contiguous byte buffer: int64 header, then each array's bytes in order."""
    parts = [np.asarray(header, np.int64).view(np.uint8)]
    parts += [np.ascontiguousarray(a).reshape(-1).view(np.uint8) for a in arrays]
    return np.concatenate(parts)


def unpack(job: Job, tile: Tile, payload: np.ndarray) -> dict[str, np.ndarray]:
    layout = tile_layout(job, tile)
    expected = sum(np.dtype(d).itemsize * int(np.prod(s)) for _, d, s in layout)
    if payload.nbytes != expected:
        raise CamparError(
            f"tile {tile.index}: {payload.nbytes} bytes received, {expected} expected"
        )
    arrays, offset = {}, 0
    for name, dtype, shape in layout:
        count = int(np.prod(shape))
        arrays[name] = np.frombuffer(payload, dtype, count, offset).reshape(shape).copy()
        offset += count * np.dtype(dtype).itemsize
    return arrays


# -- the master's view of its worker ranks ---------------------------------------------


class Workers:
    """Master side of the wire protocol: which rank is idle, busy, told to stop, gone."""

    def __init__(self, comm, job: Job):
        from mpi4py import MPI

        self.MPI, self.comm, self.job = MPI, comm, job
        self.tiles = plan_tiles(job)
        self.status = MPI.Status()
        self.idle: list[int] = []
        self.busy: dict[int, int] = {}
        self.stopped: set[int] = set()
        self.gone: set[int] = set()
        self.hosts: dict[int, str] = {}
        self.rss: dict[int, float] = {}
        self.cpu: dict[int, float] = {}
        self.seconds = 0.0

    def poll(self) -> list:
        """Every message waiting now: Outcomes, and ("signal", signum) notices."""
        events = []
        MPI = self.MPI
        while self.comm.Iprobe(MPI.ANY_SOURCE, MPI.ANY_TAG, self.status):
            rank, tag = self.status.Get_source(), self.status.Get_tag()
            buf = np.empty(self.status.Get_count(MPI.BYTE), np.uint8)
            self.comm.Recv([buf, MPI.BYTE], rank, tag)
            head = buf[:16].view(np.int64) if buf.nbytes >= 16 else None
            if tag == TAG_READY:
                self.hosts[rank] = buf.tobytes().decode()
                self.idle.append(rank)
            elif tag in (TAG_RESULT, TAG_ERROR):
                index, seconds = int(head[0]), head[1] / 1e9
                self.busy.pop(rank, None)
                self.idle.append(rank)
                self.seconds += seconds
                if tag == TAG_RESULT:
                    arrays = unpack(self.job, self.tiles[index], buf[16:])
                    events.append(Outcome(index, arrays, None, seconds, rank))
                else:
                    text = buf[16:].tobytes().decode()
                    events.append(Outcome(index, None, text, seconds, rank))
            elif tag == TAG_NOTICE:
                events.append(("signal", int(buf.view(np.int64)[0])))
            elif tag == TAG_BYE:
                rss, cpu = buf.view(np.int64) / (1024, 1e9)
                self.rss[rank], self.cpu[rank] = round(rss, 1), round(cpu, 3)
                self.gone.add(rank)
        return events

    def assign(self, rank: int, tile: Tile) -> None:
        self.idle.remove(rank)
        self.busy[rank] = tile.index
        self._send(rank, tile.index)

    def stop(self, rank: int) -> None:
        if rank not in self.stopped:
            self.stopped.add(rank)
            self._send(rank, STOP)

    def _send(self, rank: int, value: int) -> None:
        # 8 bytes: sent eagerly, Send returns at once.
        self.comm.Send([np.array([value], np.int64), self.MPI.BYTE], rank, TAG_TILE)

    @property
    def all_gone(self) -> bool:
        return len(self.gone) == self.comm.Get_size() - 1


# -- the master ---------------------------------------------------------------------------


class Master:
    """Hands pending tiles to lanes, writes results, and stops on request."""

    def __init__(self, job, store, tiles, progress, grace, comm=None):
        self.job, self.store, self.progress, self.grace = job, store, progress, grace
        self.tiles = plan_tiles(job)
        self.queue = deque(tiles)
        self.failed_on: dict[int, list[int]] = {}  # tile → lanes (ranks) it failed on
        self.tiles_by_lane = Counter()
        self.host = socket.gethostname()
        self.local = ThreadLane(job, f"rank 0 on {self.host}")
        self.workers = Workers(comm, job) if comm is not None else None
        self.stop_reason: str | None = None
        self.failure: str | None = None
        self.abandon_at = None
        self.cpu = time.process_time()  # at the start of the run

    def stop(self, reason: str) -> None:
        if self.stop_reason is None:
            self.stop_reason = reason
            self.abandon_at = time.monotonic() + self.grace
            log.warning("%s: no more tiles handed out; waiting for tiles in flight", reason)

    @property
    def in_flight(self) -> int:
        return (self.local.busy is not None) + (len(self.workers.busy) if self.workers else 0)

    def handle(self, out) -> None:
        """Act on a notice or a failure; results are only counted (``write`` stores them)."""
        if isinstance(out, tuple):  # a worker's signal notice
            self.stop(f"{signal.Signals(out[1]).name} at a worker")
        elif out.error is None:
            return
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

    def write(self, out: Outcome) -> None:
        tile = self.tiles[out.index]
        self.store.write_tile(tile, out.arrays)
        self.tiles_by_lane[out.lane] += 1
        self.progress.tile_done(tile.n_rows * self.job.shape[1])

    def _loop(self, signals: Signals) -> None:
        backoff = Backoff()
        while True:
            if signals.count:
                self.stop(signal.Signals(signals.last).name)
                if signals.insist:
                    self.abandon_at = time.monotonic()
            # Idle waits happen here, on the compute thread's outbox: woken at once by it.
            # Serial runs have no messages to probe for: they only check signals now and then.
            if self.workers:
                timeout = backoff.delay()
            else:  # an idle lane gets its tile without waiting
                timeout = SIGNAL_CHECK_SECONDS if self.local.busy is not None else 0.0
            events = [out] if (out := self.local.poll(timeout)) else []
            events += self.workers.poll() if self.workers else []
            for event in events:
                self.handle(event)
            self.hand_out()  # before writing: no lane waits for the store
            for event in events:
                if isinstance(event, Outcome) and event.error is None:
                    self.write(event)
            if self.stop_reason and (self.in_flight == 0 or time.monotonic() >= self.abandon_at):
                break
            if not self.queue and self.in_flight == 0:
                break
            if events:
                backoff.reset()

    @property
    def n_lanes(self) -> int:
        return 1 + (self.workers.comm.Get_size() - 1 if self.workers else 0)

    def next_tile(self, lane: int) -> Tile | None:
        """The first pending tile that did not fail on ``lane`` (a retry goes elsewhere)."""
        for i, tile in enumerate(self.queue):
            if self.n_lanes == 1 or lane not in self.failed_on.get(tile.index, ()):
                del self.queue[i]
                return tile
        return None

    def hand_out(self) -> None:
        if self.stop_reason is not None:
            for rank in list(self.workers.idle if self.workers else ()):
                self.workers.stop(rank)
            return
        if self.local.busy is None and (tile := self.next_tile(0)):
            self.local.start(tile)
        for rank in list(self.workers.idle if self.workers else ()):
            if tile := self.next_tile(rank):
                self.workers.assign(rank, tile)
            elif not self.queue:
                self.workers.stop(rank)

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
            for out in events:
                if isinstance(out, Outcome) and out.error is None:
                    self.write(out)  # finished just before STOP: keep it
            backoff.reset() if events else backoff.sleep()
        missing = sorted(set(range(1, self.workers.comm.Get_size())) - self.workers.gone)
        if missing:
            log.warning("ranks %s did not confirm STOP within %.0f s", missing, BYE_SECONDS)


# -- workers --------------------------------------------------------------------------------


def work(comm, job: Job, signals: Signals) -> None:
    """A worker rank: ask for tiles, compute them on a thread, send results back."""
    from mpi4py import MPI

    rank, host, cpu = comm.Get_rank(), socket.gethostname(), time.process_time()
    tiles = plan_tiles(job)
    lane = ThreadLane(job, f"rank {rank} on {host}")
    comm.Send([np.frombuffer(host.encode(), np.uint8), MPI.BYTE], 0, TAG_READY)
    index = np.empty(1, np.int64)
    backoff, forwarded = Backoff(), 0
    while True:
        active = False
        if comm.Iprobe(0, TAG_TILE):
            comm.Recv([index, MPI.BYTE], 0, TAG_TILE)
            if index[0] == STOP:
                break
            lane.start(tiles[int(index[0])])
            active = True
        if out := lane.poll(backoff.delay()):
            head = [out.index, int(out.seconds * 1e9)]
            if out.error is None:
                buf, tag = pack(head, [out.arrays[n] for n in array_names(job)]), TAG_RESULT
            else:
                buf, tag = pack(head, [np.frombuffer(out.error.encode(), np.uint8)]), TAG_ERROR
            wait(comm.Isend([buf, MPI.BYTE], 0, tag))
            active = True
        if signals.count > forwarded:  # the master decides; it may not have been signalled
            forwarded = signals.count
            comm.Send([np.array([signals.last], np.int64), MPI.BYTE], 0, TAG_NOTICE)
        if active:
            backoff.reset()
    lane.close()
    usage = [int(peak_rss_mb() * 1024), int((time.process_time() - cpu) * 1e9)]
    comm.Send([np.array(usage, np.int64), MPI.BYTE], 0, TAG_BYE)


def wait(request) -> None:
    """Complete a request without spinning a core (MPI's Wait busy-polls in mpich)."""
    backoff = Backoff()
    while not request.Test():
        backoff.sleep()


# -- entry point ------------------------------------------------------------------------------


@dataclass
class RunSummary:
    outcome: str  # complete | nothing to do | worker
    entry: dict  # the run-log entry (empty on workers and when nothing was pending)


def mpi_world():
    """COMM_WORLD when started by an MPI launcher with more than one rank, else None."""
    if not any(name in os.environ for name in MPI_LAUNCHER_ENV):
        return None
    import mpi4py

    mpi4py.rc.thread_level = "funneled"  # only the main thread calls MPI
    from mpi4py import MPI

    return MPI.COMM_WORLD if MPI.COMM_WORLD.Get_size() > 1 else None


def run_job(
    job: Job,
    store_path: str | Path | None = None,
    *,
    overwrite=False,
    grace=30.0,
    max_store: int | None = None,
    max_memory: int | None = None,
):
    """Compute every pending tile of ``job`` into its store; serial, or MPI under mpirun.

    Returns a RunSummary on completion; raises Interrupted (exit 75) after a
    signal and CamparError when a tile fails twice; JobError, before anything
    touches the disk, if the store or a rank's memory would exceed ``max_store``
    or ``max_memory`` bytes (``budget``'s defaults if None). Under MPI every rank
    returns or raises alike (workers' errors carry ``rank``; the master reports them).
    """
    path = store_path or job.store
    if path is None:
        raise JobError(f"job {job.name} names no store: add 'store: PATH' or pass --store PATH")
    check_budget(job, max_store=max_store, max_memory=max_memory)
    with Signals() as signals:
        comm = mpi_world()
        if comm is not None and comm.Get_rank() > 0:
            receive_outcome(comm)  # of opening the store
            work(comm, job, signals)
            receive_outcome(comm)  # of the run
            return RunSummary("worker", {})
        with share_outcome(comm):
            store = open_store(path, job, overwrite=overwrite)
        with store, share_outcome(comm):
            return run_master(job, store, signals, comm, grace)


# Errors a worker re-raises after the master (by index); others arrive as CamparError.
SHARED_ERRORS = (
    CamparError, JobError, StoreError, StoreMismatch, StoreLocked, Interrupted, StoreIOError,
    StoreDamaged,
)  # fmt: skip


@contextlib.contextmanager
def share_outcome(comm):
    """Master: tell every worker whether the block raised, and what (so that all ranks
    of an SPMD caller take the same branch)."""
    try:
        yield
    except BaseException as exc:
        if comm is not None:
            code = next((i for i, c in enumerate(SHARED_ERRORS) if type(exc) is c), 0)
            _send_outcome(comm, code, str(exc), getattr(exc, "exit_code", 1))
        raise
    if comm is not None:
        _send_outcome(comm, -1, "", 0)


def _send_outcome(comm, code: int, text: str, exit_code: int) -> None:
    # The exit code too: mpirun ORs the ranks' codes, so they must agree (130 | 75 = 203).
    data = np.frombuffer(text.encode(), np.uint8).copy()
    wait(comm.Ibcast(np.array([code, data.size, exit_code], np.int64), root=0))
    if data.size:
        wait(comm.Ibcast(data, root=0))


def receive_outcome(comm) -> None:
    """Worker: raise what the master raised (marked with this rank: the master reports it)."""
    head = np.empty(3, np.int64)
    wait(comm.Ibcast(head, root=0))
    if head[0] < 0:
        return
    data = np.empty(int(head[1]), np.uint8)
    if data.size:
        wait(comm.Ibcast(data, root=0))
    error = SHARED_ERRORS[int(head[0])](data.tobytes().decode())
    error.rank, error.exit_code = comm.Get_rank(), int(head[2])
    raise error


def run_master(job, store, signals, comm, grace) -> RunSummary:
    tiles = pending_tiles(job, store.done)
    all_tiles = plan_tiles(job)
    n_rows, n_omega = job.shape
    done_cells = sum(t.n_rows for t in all_tiles if store.done[t.index]) * n_omega
    total_cells = n_rows * n_omega * len(job.directions)
    progress = Progress(len(all_tiles), total_cells, len(all_tiles) - len(tiles), done_cells)
    master = Master(job, store, tiles, progress, grace, comm)
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
        store.path, outcome, entry["tiles"], entry["cells"], entry["seconds"], entry["cells_per_s"],
    )  # fmt: skip
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


def usage(master: Master) -> dict:
    """Who computed what, and at what cost, for the run log (per rank: None if unknown)."""
    w, others = master.workers, range(1, master.n_lanes)
    return {
        "ranks": master.n_lanes,
        "host": master.host,
        "hosts": sorted({master.host, *(w.hosts.values() if w else ())}),
        "compute_seconds": round(master.local.seconds + (w.seconds if w else 0), 3),
        "tiles_per_rank": [master.tiles_by_lane[r] for r in range(master.n_lanes)],
        "cpu_seconds": [round(time.process_time() - master.cpu, 3)]
        + [w.cpu.get(r) for r in others],
        "peak_rss_mb": [round(peak_rss_mb(), 1), *(w.rss.get(r) for r in others)],
    }
