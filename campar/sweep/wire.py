"""The wire between the runner's master (rank 0) and its worker ranks, and MPI itself.

Wire protocol (mpi4py.futures style: plain data, ``STOP`` ends a worker, the
master never blocks in a receive — it probes and sleeps with a backoff capped
at 1 ms). Results travel as one packed byte buffer whose layout both sides
know from the job (``pack``/``unpack``), never as pickles:

    worker → master   READY (host)  |  RESULT [tile, ns] + arrays  |  ERROR [tile, ns] + text
                      COMPUTED [tile, ns]  |  WRITTEN [tile, checksum]  |  IO_ERROR [tile] + text
                      NOTICE [signal]  |  BYE [peak RSS kB, CPU ns]
                      WITHDRAWN [tile, …]
    master → worker   TILE [index]  |  TILE [WITHDRAW]  |  TILE [STOP]

(COMPUTED, WRITTEN and IO_ERROR where workers write their own tiles: COMPUTED frees
the rank for its next tile, WRITTEN lets the master commit the tile, IO_ERROR ends
the run as a failed write of the master's own would, exit 74.)

A worker holds up to ``TILES_HELD`` tiles: the one its lane computes and the next,
which the lane starts the moment the first is done, whatever the master is doing. On a
stop the master sends WITHDRAW: the worker takes back the tiles its lane has not
started and names them (WITHDRAWN, perhaps none); only started tiles are collected.

Every rank learns the outcome of what the master does alone — opening the store,
then the run — as one broadcast (``share_outcome``/``receive_outcome``): all ranks of
an SPMD caller raise the same error, with the same exit code (mpirun ORs them).

mpi4py is imported only here, and only when the process was started by an MPI
launcher (``mpi_world``), so ``campar --help`` and serial runs never load MPI.
"""

import contextlib
import logging
import os
import queue
import socket
import threading
import time
import traceback
from collections import Counter
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
from .job import Job
from .plan import Tile, plan_tiles
from .progress import peak_rss_mb
from .store import cell_arrays, lock_path, tile_shape

log = logging.getLogger("campar.run")

TAG_READY, TAG_TILE, TAG_RESULT, TAG_ERROR, TAG_NOTICE, TAG_BYE = range(11, 17)
TAG_COMPUTED, TAG_WRITTEN, TAG_IO_ERROR, TAG_WITHDRAWN = range(17, 21)
WRITER_ENV = "CAMPAR_WRITER"  # "master": the master writes every tile, whatever the backend
STOP, WITHDRAW = -1, -2
TILES_HELD = 2  # tiles a lane holds: the one it computes and the one it starts next
BACKOFF_SECONDS = 1e-3  # longest sleep of an idle loop between probes (mpi4py.futures)
# A worker whose lane computes and whose writer is idle expects nothing from the master
# but STOP or WITHDRAW — tiles come only in answer to its results, within
# ANSWER_SECONDS of one (the next tile to hold), or not at all near the end —: it waits
# on its lane, woken the moment a tile is done, and looks for messages and signals this
# often (not 1000× a second: hundreds of ranks polling would take the cores their lanes
# compute on).
COMPUTING_WAIT_SECONDS = 0.05
ANSWER_SECONDS = 0.02
# An idle worker's probes for its next tile: from ~1 µs, doubling, up to this. The master
# answers a result at once (a tile or STOP), so a longer wait means it is busy: probing
# 1,000 times a second would only take the cores of the ranks that compute.
IDLE_WORKER_BACKOFF_SECONDS = 0.01
MPI_LAUNCHER_ENV = ("PMI_SIZE", "PMI_RANK", "OMPI_COMM_WORLD_SIZE", "PMIX_RANK")


@dataclass
class Outcome:
    """A lane's report on one tile: its arrays, or the error text."""

    index: int
    arrays: dict | None
    error: str | None
    seconds: float
    lane: int = 0  # the rank that computed it
    checksum: int | None = None  # written by its worker already: only the commit is left
    io_error: bool = False  # ``error`` is its worker's failed write: the run ends (exit 74)


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


# -- packing tile arrays into one buffer -----------------------------------------------


def tile_layout(schemas: list, tile: Tile) -> list[tuple[str, np.dtype, tuple[int, ...]]]:
    """(name, dtype, shape) of each array of a tile, in ``array_names`` order (``schemas``:
    the job's ``cell_arrays``, made once by the caller, not on every call)."""
    return [(a.name, a.dtype, tile_shape(a, tile)) for a in schemas]


def pack(header: list[int], arrays: list[np.ndarray]) -> np.ndarray:
    """One contiguous byte buffer: int64 header, then each array's bytes in order."""
    parts = [np.asarray(header, np.int64).view(np.uint8)]
    parts += [np.ascontiguousarray(a).reshape(-1).view(np.uint8) for a in arrays]
    return np.concatenate(parts)


def unpack(schemas: list, tile: Tile, payload: np.ndarray) -> dict[str, np.ndarray]:
    layout = tile_layout(schemas, tile)
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
    """Master side of the wire protocol: which rank is ready, holds which tiles, was told
    to stop, is gone."""

    def __init__(self, comm, job: Job):
        from mpi4py import MPI

        self.MPI, self.comm, self.job = MPI, comm, job
        self.tiles = plan_tiles(job)
        self.schemas = cell_arrays(job)  # to unpack the tiles sent for the master to write
        self.status = MPI.Status()
        self.ready: list[int] = []  # ranks that asked for tiles, in that order
        self.held: dict[int, list[int]] = {}  # rank → tiles it computes or queues, in order
        self.writing = Counter()  # rank → tiles whose arrays it is writing
        self.writers: dict[int, str] = {}  # rank → "worker" (wrote its tiles) or "master"
        self.stopped: set[int] = set()
        self.gone: set[int] = set()
        self.hosts: dict[int, str] = {}
        self.rss: dict[int, float] = {}
        self.cpu: dict[int, float] = {}
        self.seconds = 0.0
        self.shortest_tile = float("inf")  # seconds, of the workers' tiles

    def poll(self) -> list:
        """Every message waiting now: Outcomes, ("signal", signum) notices and
        ("withdrawn", [tile, …]) answers to WITHDRAW."""
        events = []
        MPI = self.MPI
        for _ in waiting_messages(self.comm, MPI.ANY_SOURCE, MPI.ANY_TAG, self.status):
            rank, tag = self.status.Get_source(), self.status.Get_tag()
            buf = np.empty(self.status.Get_count(MPI.BYTE), np.uint8)
            self.comm.Recv([buf, MPI.BYTE], rank, tag)
            head = buf[:16].view(np.int64) if buf.nbytes >= 16 else None
            if tag == TAG_READY:
                self.hosts[rank] = buf.tobytes().decode()
                self.ready.append(rank)
                self.held[rank] = []
            elif tag in (TAG_RESULT, TAG_ERROR):
                index, seconds = int(head[0]), head[1] / 1e9
                self._computed(rank, index, seconds)
                if tag == TAG_RESULT:
                    self.writers[rank] = "master"
                    arrays = unpack(self.schemas, self.tiles[index], buf[16:])
                    events.append(Outcome(index, arrays, None, seconds, rank))
                else:
                    text = buf[16:].tobytes().decode()
                    events.append(Outcome(index, None, text, seconds, rank))
            elif tag == TAG_COMPUTED:  # the rank writes it now and is free for another
                index, seconds = int(head[0]), head[1] / 1e9
                self._computed(rank, index, seconds)
                self.writing[rank] += 1
                self.writers[rank] = "worker"
            elif tag == TAG_WRITTEN:
                index, checksum = int(head[0]), int(head[1:2].view(np.uint64)[0])
                self.writing[rank] -= 1
                events.append(Outcome(index, None, None, 0.0, rank, checksum))
            elif tag == TAG_IO_ERROR:
                index = int(buf[:8].view(np.int64)[0])
                self.writing[rank] -= 1
                text = buf[8:].tobytes().decode()
                events.append(Outcome(index, None, text, 0.0, rank, io_error=True))
            elif tag == TAG_NOTICE:
                events.append(("signal", int(buf.view(np.int64)[0])))
            elif tag == TAG_WITHDRAWN:
                taken = [int(i) for i in buf.view(np.int64)]
                for index in taken:
                    self.held[rank].remove(index)
                events.append(("withdrawn", taken))
            elif tag == TAG_BYE:
                rss, cpu = buf.view(np.int64) / (1024, 1e9)
                self.rss[rank], self.cpu[rank] = round(rss, 1), round(cpu, 3)
                self.gone.add(rank)
        return events

    def _computed(self, rank: int, index: int, seconds: float) -> None:
        self.held[rank].remove(index)
        self.seconds += seconds
        self.shortest_tile = min(self.shortest_tile, seconds)

    def open_ranks(self) -> list[int]:
        """Ranks that take tiles: ready, not told to stop."""
        return [rank for rank in self.ready if rank not in self.stopped]

    def holding(self, rank: int) -> int:
        return len(self.held.get(rank, ()))

    def room(self, rank: int, depth: int) -> bool:
        """Whether ``rank`` takes a tile to hold ``depth``: a tile ahead (depth 2) only while
        it writes none. A worker whose writes fall behind its lane gets no tiles ahead of
        them (``campar bench master`` measures the commits' delay with and without)."""
        return self.holding(rank) < depth and (depth == 1 or not self.writing[rank])

    @property
    def in_flight(self) -> int:
        """Tiles handed out and not back: held by a lane, or being written by its worker."""
        return sum(map(len, self.held.values())) + self.writing.total()

    def assign(self, rank: int, tile: Tile) -> None:
        self.held[rank].append(tile.index)
        self._send(rank, tile.index)

    def withdraw(self) -> None:
        """Ask every rank holding a tile it has not started for it back (a stop)."""
        for rank in self.open_ranks():
            if self.holding(rank) > 1:
                self._send(rank, WITHDRAW)

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


# -- the worker ranks ----------------------------------------------------------------------


class WriterThread:
    """A worker's writes of its own tiles (``TileWriter`` into the store at ``real``), on a
    daemon thread: the lane computes its next tile meanwhile. Results come back in order
    as (tile index, checksum, None) or (tile index, None, the StoreIOError's text)."""

    def __init__(self, real: str, job: Job):
        self.real, self.job, self.pending = real, job, 0
        self._inbox, self._outbox = queue.Queue(), queue.Queue()
        threading.Thread(target=self._loop, daemon=True, name="campar-writer").start()

    def put(self, tile: Tile, arrays: dict) -> None:
        self.pending += 1
        self._inbox.put((tile, arrays))

    def poll(self, timeout: float | None = 0.0):
        try:
            done = (
                self._outbox.get(timeout=timeout) if timeout != 0.0 else self._outbox.get_nowait()
            )
        except queue.Empty:
            return None
        self.pending -= 1
        return done

    def close(self) -> None:
        self._inbox.put(None)

    def _loop(self):
        from .store import TileWriter

        writer = None
        while (item := self._inbox.get()) is not None:
            tile, arrays = item
            try:
                writer = writer or TileWriter(self.real, self.job)
                self._outbox.put((tile.index, writer.write_tile(tile, arrays), None))
            except StoreIOError as exc:
                self._outbox.put((tile.index, None, str(exc)))
            except Exception:
                self._outbox.put((tile.index, None, traceback.format_exc()))


def work(comm, job: Job, signals, lane, direct: str = "") -> None:
    """A worker rank: ask for tiles, compute them on ``lane`` (a thread: ``start``,
    ``poll``, ``close``), send results back — or, where ``direct`` (``direct_path``) names
    a store this rank sees, write them there and report that."""
    from mpi4py import MPI

    host, cpu = socket.gethostname(), time.process_time()
    tiles = plan_tiles(job)
    real = seen_store(direct)
    writer = WriterThread(real, job) if real else None

    def report(done) -> None:  # a write's outcome, to the master
        index, checksum, error = done
        if error is None:
            head = np.array([index, 0], np.int64)
            head[1:] = np.array([checksum], np.uint64).view(np.int64)
            wait(comm.Isend([head, MPI.BYTE], 0, TAG_WRITTEN))
        else:
            buf = pack([index], [np.frombuffer(error.encode(), np.uint8)])
            wait(comm.Isend([buf, MPI.BYTE], 0, TAG_IO_ERROR))

    comm.Send([np.frombuffer(host.encode(), np.uint8), MPI.BYTE], 0, TAG_READY)
    backoff, forwarded = Backoff(IDLE_WORKER_BACKOFF_SECONDS), 0
    answer_by = 0.0  # the master's answer to the last result is due before this
    while True:
        orders = take_orders(comm, lane, tiles)
        if orders == "stop":
            break
        active = orders == "taken"
        expecting = len(lane.held) < TILES_HELD and time.monotonic() < answer_by
        waiting = lane.held and not expecting and not (writer is not None and writer.pending)
        if out := lane.poll(COMPUTING_WAIT_SECONDS if waiting else backoff.delay()):
            head = [out.index, int(out.seconds * 1e9)]
            if out.error is not None:
                buf, tag = pack(head, [np.frombuffer(out.error.encode(), np.uint8)]), TAG_ERROR
            elif writer is not None:  # free for the next tile; the writer takes this one
                buf, tag = pack(head, []), TAG_COMPUTED
                writer.put(tiles[out.index], out.arrays)
            else:
                buf, tag = pack(head, [out.arrays[n] for n in array_names(job)]), TAG_RESULT
            wait(comm.Isend([buf, MPI.BYTE], 0, tag))
            answer_by = time.monotonic() + ANSWER_SECONDS
            active = True
        if writer is not None and (done := writer.poll()):
            report(done)
            active = True
        if signals.count > forwarded:  # the master decides; it may not have been signalled
            forwarded = signals.count
            comm.Send([np.array([signals.last], np.int64), MPI.BYTE], 0, TAG_NOTICE)
        if active:
            backoff.reset()
    lane.close()
    if writer is not None:  # tiles computed before STOP: written, so the master may commit them
        while writer.pending:
            report(writer.poll(timeout=None))
        writer.close()
    usage = [int(peak_rss_mb() * 1024), int((time.process_time() - cpu) * 1e9)]
    comm.Send([np.array(usage, np.int64), MPI.BYTE], 0, TAG_BYE)


def take_orders(comm, lane, tiles: list[Tile]) -> str:
    """A worker's messages from the master: tiles go to ``lane``, WITHDRAW is answered.
    "stop" on STOP, else "taken" if anything came, "" if nothing did."""
    from mpi4py import MPI

    order, taken = np.zeros(1, np.int64), ""
    for _ in waiting_messages(comm, 0, TAG_TILE):
        comm.Recv([order, MPI.BYTE], 0, TAG_TILE)
        if order[0] == STOP:
            return "stop"
        if order[0] == WITHDRAW:
            back = np.array([tile.index for tile in lane.withdraw()], np.int64)
            wait(comm.Isend([back, MPI.BYTE], 0, TAG_WITHDRAWN))
        else:
            lane.start(tiles[int(order[0])])
        taken = "taken"
    return taken


def waiting_messages(comm, source: int, tag: int, status=None):
    """Yield once for each message waiting (``status`` describes it): the caller receives
    it. mpich's Iprobe can bring the next message in and still answer no, so only two
    noes in a row end the loop (measured: 15 ranks' 45 waiting messages took 46 polls
    when one no ended it, one poll with two)."""
    noes = 0
    while noes < 2:
        if comm.Iprobe(source, tag, status):
            noes = 0
            yield
        else:
            noes += 1


def wait(request) -> None:
    """Complete a request without spinning a core (MPI's Wait busy-polls in mpich)."""
    backoff = Backoff()
    while not request.Test():
        backoff.sleep()


def mpi_world():
    """COMM_WORLD when started by an MPI launcher with more than one rank, else None."""
    if not any(name in os.environ for name in MPI_LAUNCHER_ENV):
        return None
    import mpi4py

    mpi4py.rc.thread_level = "funneled"  # only the main thread calls MPI
    from mpi4py import MPI

    return MPI.COMM_WORLD if MPI.COMM_WORLD.Get_size() > 1 else None


def cache_sharers(comm, cache_dir: str) -> tuple[int, int]:
    """(this rank's index, their number) among the ranks of its node whose numba cache is
    ``cache_dir``: one directory on one node, so a cold compile can be split between them
    (campar.core.split_compile.share_with_ranks). A collective: every rank calls it."""
    from mpi4py import MPI

    node = comm.Split_type(MPI.COMM_TYPE_SHARED)
    try:
        dirs = node.allgather(cache_dir)
        sharers = [rank for rank, other in enumerate(dirs) if other == cache_dir]
        return sharers.index(node.Get_rank()), len(sharers)
    finally:
        node.Free()


SHARED_ERRORS = (
    CamparError,
    JobError,
    StoreError,
    StoreMismatch,
    StoreLocked,
    Interrupted,
    StoreIOError,
    StoreDamaged,
)


def workers_write(direct_writes: bool) -> bool:
    """Whether workers write their own tiles into a store whose backend allows it
    (``Store.direct_writes``), unless ``CAMPAR_WRITER=master`` asks otherwise."""
    return direct_writes and os.environ.get(WRITER_ENV) != "master"


def direct_path(store) -> str:
    """Where workers write their own tiles, as the master tells them: the store's real path
    and its lock file's text, one per line ("" where the master writes every tile)."""
    if not workers_write(store.direct_writes):
        return ""
    return f"{store.real}\n{lock_path(store.real).read_text()}"


def seen_store(direct: str) -> str:
    """The store path of ``direct_path``'s text if this rank sees the store the master
    opened — the lock file at its path holds the master's text: the same file system —
    else "" (this rank then sends its tiles to the master, which writes them)."""
    if not direct:
        return ""
    real, _, lock = direct.partition("\n")
    try:
        if lock_path(Path(real)).read_text() == lock:
            return real
    except OSError:
        pass
    log.warning(
        "rank on %s does not see the store %s as rank 0 does (not a shared file system?): "
        "it sends its tiles to rank 0 to write",
        socket.gethostname(),
        real,
    )
    return ""


@contextlib.contextmanager
def share_outcome(comm, success: dict | None = None):
    """Master: tell every worker whether the block raised, and what (so that all ranks
    of an SPMD caller take the same branch); on success, ``success["text"]`` if set."""
    try:
        yield
    except BaseException as exc:
        if comm is not None:
            code = next((i for i, c in enumerate(SHARED_ERRORS) if type(exc) is c), 0)
            _send_outcome(comm, code, str(exc), getattr(exc, "exit_code", 1))
        raise
    if comm is not None:
        _send_outcome(comm, -1, (success or {}).get("text", ""), 0)


def _send_outcome(comm, code: int, text: str, exit_code: int) -> None:
    # The exit code too: mpirun ORs the ranks' codes, so they must agree (130 | 75 = 203).
    data = np.frombuffer(text.encode(), np.uint8).copy()
    wait(comm.Ibcast(np.array([code, data.size, exit_code], np.int64), root=0))
    if data.size:
        wait(comm.Ibcast(data, root=0))


def receive_outcome(comm) -> str:
    """Worker: raise what the master raised (marked with this rank: the master reports it);
    on success, return the text the master sent with it."""
    head = np.empty(3, np.int64)
    wait(comm.Ibcast(head, root=0))
    data = np.empty(int(head[1]), np.uint8)
    if data.size:
        wait(comm.Ibcast(data, root=0))
    if head[0] < 0:
        return data.tobytes().decode()
    error = SHARED_ERRORS[int(head[0])](data.tobytes().decode())
    error.rank, error.exit_code = comm.Get_rank(), int(head[2])
    raise error
