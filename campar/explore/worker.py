"""The worker process of the explorer's computations, and their time limit.

The computations of ``campar.explore.cells`` run in one worker process, spawned (the
server's threads never share numba's state with it) and kept warm between requests. A
request that outlives its time limit ends the worker, the page is told in one line, and
the next request starts a fresh one; a computation that fails sends its one line back
and the worker goes on.
"""

import multiprocessing
import threading
import time

from ..errors import CamparError
from .cells import ACTIONS as CELL_ACTIONS
from .lines import line_report

ACTIONS = {**CELL_ACTIONS, "line": line_report}

CELL_SECONDS = 60.0  # default time limit of one computation
WARM_UP_SECONDS = 900.0  # a cold compile of the kernel and the tracer on a loaded machine


def _serve(conn) -> None:
    """The worker's loop: (action, args) in, ("ok", data) or ("error", one line) out; it
    ends when the server closes its end (or is gone)."""
    while True:
        try:
            action, args = conn.recv()
        except (EOFError, OSError):
            return
        try:
            answer = ("ok", ACTIONS[action](*args))
        except Exception as exc:  # shown in the page: the worker goes on
            answer = ("error", f"{type(exc).__name__}: {' '.join(str(exc).split())}")
        try:
            conn.send(answer)
        except OSError:  # the server stopped meanwhile
            return


class CellTimeout(CamparError):
    pass


class Spawned:
    """A process of the server's, spawned (it shares no numba state with the server's
    threads), with a pipe to it; ``stop`` ends it."""

    def __init__(self):
        self._process = None
        self._conn = None

    def spawn(self, target, *args) -> None:
        """Start ``target(conn, *args)`` in a new process."""
        ctx = multiprocessing.get_context("spawn")
        self._conn, child = ctx.Pipe()
        self._process = ctx.Process(target=target, args=(child, *args), daemon=True)
        self._process.start()
        child.close()

    def stop(self) -> None:
        if self._process is not None:
            self._process.kill()
            self._process.join(5)
            self._conn.close()
        self._process = None


class CellWorker(Spawned):
    """One worker process for the cell computations, restarted after a time-out."""

    def __init__(self, seconds: float = CELL_SECONDS):
        super().__init__()
        self.seconds = seconds
        self._lock = threading.Lock()

    def start(self) -> None:
        self.spawn(_serve)

    def run(self, action: str, *args, seconds: float | None = None):
        """The action's data; CamparError with the failure's line, or CellTimeout after
        ``seconds`` (default: the worker's limit)."""
        limit = self.seconds if seconds is None else seconds
        if not self._lock.acquire(timeout=limit):
            raise CellTimeout(f"another computation held the worker for {limit:g} s; try again")
        try:
            if self._process is None or not self._process.is_alive():
                self.start()
            started = time.monotonic()
            self._conn.send((action, args))
            if not self._conn.poll(limit):
                self.stop()
                raise CellTimeout(
                    f"the computation ran over its limit of {limit:g} s and was ended"
                )
            kind, data = self._conn.recv()
            data_seconds = time.monotonic() - started
        finally:
            self._lock.release()
        if kind == "error":
            raise CamparError(data)
        if isinstance(data, dict):
            data["seconds"] = round(data_seconds, 3)
        return data
