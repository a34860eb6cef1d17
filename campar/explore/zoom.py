"""A zoom that computes: a rectangle of a map run again on a grid of its own.

The zoom is a job of the same model as the map — every setting of the map's job kept,
the sweep narrowed to the rectangle at ``points`` × ``points`` cells, the first chain
started from the map's stored final state at the rectangle's starting corner (so it
follows the map's attractor, not a start from rest) — run by ``campar run``: resumable,
verified, stored beside the map in ``<map>.zooms/<job>-<digest>.zarr`` with its job
file and run log. The same rectangle asked again finds the same store and resumes it.

A small zoom's cost is mostly a new process's start-up (the interpreter, campar's
imports, the compiled kernel loaded, MPI started), not its cells: a ``ZoomRunner``
process, started with the server and kept warm (the map's kernel loaded), runs a zoom
of at most WARM_CELLS cells with the serial runner when it is free. A larger zoom, or
one asked while it is busy, runs in a child process of its own (``start_zoom``: under
``mpirun`` on ``ranks`` ranks where the venv has it).
"""

import contextlib
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import yaml

from ..errors import JobError
from ..sweep.job import Job
from .source import MapSource, stored_cell
from .worker import Spawned

MAX_POINTS = 400  # cells along each side of a zoom's grid
# Cells of a zoom the warm runner takes: below about this many, one warm serial run ends
# before a new pair of ranks has started and computed its half.
WARM_CELLS = 20_000


def zoom_job(source: MapSource, box, points: int) -> Job:
    """The job of a zoom of ``source`` over ``box`` = (x0, x1, y0, y1), points × points."""
    if not 2 <= points <= MAX_POINTS:
        raise JobError(f"a zoom has 2 to {MAX_POINTS} points a side, got {points}")
    job = source.job
    x0, x1, y0, y1 = box
    lo_x, hi_x = source.x_edges[0], source.x_edges[-1]
    lo_y, hi_y = source.y_edges[0], source.y_edges[-1]
    x0, x1, y0, y1 = max(x0, lo_x), min(x1, hi_x), max(y0, lo_y), min(y1, hi_y)
    if not (x0 < x1 and y0 < y1):
        raise JobError("the zoom's rectangle lies outside the map")
    xs, ys = job.first_values, job.second_values
    # the map's own order along each axis (ω decreasing in the paper's planes)
    fx = (x1, x0) if xs[0] > xs[-1] else (x0, x1)
    fy = (y1, y0) if len(ys) > 1 and ys[0] > ys[-1] else (y0, y1)
    row = int(np.abs(ys - fy[0]).argmin())
    col = int(np.abs(xs - fx[0]).argmin())
    _, corner = stored_cell(source.path, row, col)
    state = [float(a) for a in corner["state"]]
    data = job.to_dict()
    data.update(
        sweep={
            job.first: {"from": float(fx[0]), "to": float(fx[1]), "points": points},
            job.second: {"from": float(fy[0]), "to": float(fy[1]), "points": points},
        },
        initial={"y": state[0], "v": state[1]} if all(map(np.isfinite, state)) else data["initial"],
        store=None,
    )
    data.pop("curves", None)
    data["name"] = f"{job.name}-zoom"
    named = Job.from_dict(data, source="zoom")
    data["name"] = f"{job.name}-zoom-{named.digest()[:10]}"
    return Job.from_dict(data, source="zoom")


def zoom_store(source: MapSource, job: Job) -> Path:
    return source.path.parent / f"{source.path.name}.zooms" / f"{job.name}.zarr"


def write_zoom_job(source: MapSource, job: Job) -> tuple[Path, Path]:
    """The zoom's job file beside the map, naming its store: (store, job file)."""
    store = zoom_store(source, job)
    store.parent.mkdir(exist_ok=True)
    data = {**job.to_dict(), "store": str(store)}
    job_file = store.with_suffix(".yaml")
    job_file.write_text(yaml.safe_dump(data, sort_keys=False))
    return store, job_file


def start_zoom(source: MapSource, job: Job, ranks: int = 2) -> tuple[Path, subprocess.Popen]:
    """Run the zoom's job into its store beside the map in a child process of its own:
    (store, the run's process)."""
    store, job_file = write_zoom_job(source, job)
    mpirun = Path(sys.executable).parent / "mpirun"
    command = [sys.executable, "-m", "campar.cli", "run", str(job_file)]
    if ranks > 1 and mpirun.exists():
        command = [str(mpirun), "-n", str(ranks), *command]
    log = store.with_suffix(".log").open("ab")
    process = subprocess.Popen(
        command, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL
    )
    log.close()
    return store, process


def _serve_zooms(conn, warm_job: dict) -> None:
    """The warm runner's loop: load the kernel of ``warm_job`` (the map's: a zoom keeps
    every setting of its map), then run each zoom's job it is sent (a job mapping naming
    its store) as ``campar run`` of its job file runs it — its progress lines appended
    to the zoom's log — and send back the exit code."""
    from ..errors import CamparError
    from ..sweep.progress import setup_logging
    from ..sweep.runner import run_job
    from ..sweep.tile import compile_kernel

    with contextlib.suppress(Exception):  # the first zoom compiles it, and says what fails
        compile_kernel(Job.from_dict(warm_job, source="the map of a zoom"))
    conn.send("ready")
    while True:
        try:
            data, log = conn.recv()
        except (EOFError, OSError):
            return
        sys.stderr.flush()
        fd = os.open(log, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        os.dup2(fd, 2)  # the run's log lines (and a failure's one line) go to the zoom's log
        os.close(fd)
        setup_logging()
        try:
            run_job(Job.from_dict(data, source=str(data["store"])), data["store"])
            code = 0
        except CamparError as exc:
            print(f"campar run: {exc}", file=sys.stderr)
            code = exc.exit_code
        sys.stderr.flush()
        try:
            conn.send(code)
        except OSError:
            return


class ZoomRunner(Spawned):
    """A process kept warm for zooms (one at a time), spawned when the server starts;
    ``stop`` ends it (a zoom it runs is stopped first by the server: ``WarmRun``)."""

    def __init__(self):
        super().__init__()
        self._ready = False
        self._running = None  # the WarmRun of the zoom it runs, if any

    def start(self, warm_job: Job) -> None:
        self.spawn(_serve_zooms, warm_job.to_dict())

    def free(self) -> bool:
        """Alive, warm and not running a zoom."""
        if self._process is None or not self._process.is_alive():
            return False
        if self._running is not None and self._running.poll() is None:
            return False
        if not self._ready and self._conn.poll():
            self._ready = self._conn.recv() == "ready"
        return self._ready

    def run(self, source: MapSource, job: Job) -> tuple[Path, "WarmRun"]:
        """Run the zoom's job in the warm process (``free()`` first): (store, its run)."""
        store, _ = write_zoom_job(source, job)  # the file resumes it: campar run FILE
        self._conn.send(({**job.to_dict(), "store": str(store)}, str(store.with_suffix(".log"))))
        self._running = WarmRun(self._process, self._conn)
        return store, self._running


class WarmRun:
    """A zoom run in the warm process, as ``subprocess.Popen`` offers a child's run:
    ``poll``, ``terminate`` (the runner stops at a tile's end), ``wait``, ``kill``."""

    def __init__(self, process, conn):
        self._process, self._conn = process, conn
        self.returncode = None

    def poll(self):
        if self.returncode is None:
            if self._conn.poll():
                self.returncode = self._conn.recv()
            elif not self._process.is_alive():
                self.returncode = self._process.exitcode
        return self.returncode

    def terminate(self) -> None:
        if self._process.is_alive():
            self._process.terminate()

    def wait(self, timeout=None):
        """The run's exit code once it has ended (the process stays, idle)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while self.poll() is None:
            if deadline is not None and time.monotonic() > deadline:
                raise subprocess.TimeoutExpired("campar run (the warm zoom runner)", timeout)
            self._conn.poll(0.05)
        return self.returncode

    def kill(self) -> None:
        self._process.kill()
