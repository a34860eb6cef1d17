"""How far a sweep has got: the live progress line of a run, its run-log entry, ``campar status``.

On a terminal the run rewrites one line (tiles done/total, cells/s, ETA) at
most a few times a second; otherwise (a batch job's log) it writes a log line
every ``every`` seconds, so logs stay short and still show the rate.
"""

import logging
import math
import resource
import sys
import time
from collections import Counter
from datetime import UTC, datetime

import numpy as np

from .. import __version__
from ..core.codes import KIND_NAMES, Kind, cell_label, status_message
from .plan import plan_tiles

log = logging.getLogger("campar.run")

REDRAW_SECONDS = 0.25  # a TTY line faster than this only flickers


def format_duration(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "?"
    seconds = int(round(seconds))
    if seconds < 60:
        return f"{seconds}s"
    if seconds < 3600:
        return f"{seconds // 60}m{seconds % 60:02d}s"
    return f"{seconds // 3600}h{seconds % 3600 // 60:02d}m"


def setup_logging() -> None:
    """Log lines of a run ("campar: …") on stderr, unless the caller configured logging."""
    if not logging.getLogger().handlers:
        logging.basicConfig(level=logging.INFO, format="%(asctime)s campar: %(message)s")


def peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # Linux: kB


class Progress:
    """Counts the tiles and cells of one run, reports them, and writes its run-log entry."""

    def __init__(self, total_tiles, total_cells, done_tiles, done_cells, stream=None, every=30.0):
        self.total_tiles, self.total_cells = total_tiles, total_cells
        self.tiles, self.cells = done_tiles, done_cells
        self.new_tiles = self.new_cells = 0
        self.stream = stream if stream is not None else sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.every = REDRAW_SECONDS if self.tty else every
        self.started = datetime.now(UTC)
        self.start = time.monotonic()
        self.last = self.start

    @property
    def rate(self) -> float:
        """Cells per second computed by this run."""
        elapsed = time.monotonic() - self.start
        return self.new_cells / elapsed if elapsed > 0 else 0.0

    def line(self) -> str:
        rate = self.rate
        eta = (self.total_cells - self.cells) / rate if rate > 0 else math.inf
        return (
            f"tiles {self.tiles}/{self.total_tiles}  cells {self.cells}/{self.total_cells}  "
            f"{rate:.1f} cells/s  ETA {format_duration(eta)}"
        )

    def tile_done(self, cells: int) -> None:
        self.tiles += 1
        self.new_tiles += 1
        self.cells += cells
        self.new_cells += cells
        now = time.monotonic()
        if now - self.last >= self.every or self.tiles == self.total_tiles:
            self.last = now
            self.show()

    def show(self) -> None:
        if self.tty:
            self.stream.write("\r" + self.line() + "\x1b[K")
            self.stream.flush()
        else:
            log.info(self.line())

    def close(self) -> None:
        if self.tty:
            self.stream.write("\n")
            self.stream.flush()

    def entry(self, outcome: str, **usage) -> dict:
        """This run's entry in the store's run log (``usage``: ranks, hosts, costs)."""
        seconds = time.monotonic() - self.start
        return {
            "start": self.started.isoformat(timespec="seconds"),
            "end": datetime.now(UTC).isoformat(timespec="seconds"),
            "tiles": self.new_tiles,
            "cells": self.new_cells,
            "cells_per_s": round(self.new_cells / seconds, 3) if seconds > 0 else 0.0,
            "seconds": round(seconds, 3),
            **usage,
            "outcome": outcome,
            "campar": __version__,
        }


# -- campar status ------------------------------------------------------------------


def summarize(reader) -> dict:
    """Counts behind ``campar status``: tiles, cells, failures, kinds, labels, time."""
    job = reader.job
    tiles = plan_tiles(job)
    done = reader.done
    n_omega = job.shape[1]
    cells_done = sum(t.n_rows for t in tiles if done[t.index]) * n_omega
    rows = np.zeros(job.shape[0], bool)
    for t in tiles:
        rows[t.rows] = done[t.index]
    status = reader.read("status")[rows]
    kind = reader.read("kind")[rows]
    periodic = kind == Kind.PERIODIC
    n, p = reader.read("n")[rows][periodic], reader.read("p")[rows][periodic]
    labels = Counter(cell_label(0, a, b, job.classify.chatter_p) for a, b in zip(n, p, strict=True))
    runs = reader.attrs.get("runs", [])
    seconds = sum(_seconds(r) for r in runs)
    cells_run = sum(r.get("cells", 0) for r in runs)
    return {
        "tiles": (int(done.sum()), len(tiles)),
        "cells": (cells_done, job.shape[0] * n_omega),
        "failed": {status_message(int(s)): int(c) for s, c in _counts(status[status != 0])},
        "kinds": {KIND_NAMES[Kind(int(k))]: int(c) for k, c in _counts(kind)},
        "labels": dict(labels.most_common()),
        "runs": len(runs),
        "seconds": seconds,
        "cells_per_s": cells_run / seconds if seconds > 0 else math.nan,
        "last_outcome": runs[-1].get("outcome") if runs else None,
    }


def describe(reader, max_labels: int = 12) -> str:
    """The text ``campar status`` prints."""
    s = summarize(reader)
    job = reader.job
    failed = sum(s["failed"].values())
    lines = [
        f"store   {reader.path}  (job {job.name}, hash {reader.attrs.get('job_hash')})",
        f"grid    {job.shape[0]} {job.second} × {job.shape[1]} omega, {job.tiles.rows} rows a tile",
        f"tiles   {s['tiles'][0]}/{s['tiles'][1]} done",
        f"cells   {s['cells'][0]}/{s['cells'][1]} done, {failed} failed (status ≠ 0)",
    ]
    lines += [f"          {count} × {why}" for why, count in s["failed"].items()]
    if s["kinds"]:
        lines.append("kinds   " + ", ".join(f"{k} {c}" for k, c in s["kinds"].items()))
    if s["labels"]:
        top = list(s["labels"].items())
        shown = ", ".join(f"{label} {c}" for label, c in top[:max_labels])
        more = f", … {len(top) - max_labels} more" if len(top) > max_labels else ""
        lines.append(f"labels  {shown}{more}")
    if s["runs"]:
        lines.append(
            f"runs    {s['runs']} ({s['last_outcome']} last), {format_duration(s['seconds'])} "
            f"in all, {s['cells_per_s']:.1f} cells/s"
        )
    else:
        lines.append("runs    none logged")
    return "\n".join(lines)


def _counts(values: np.ndarray):
    keys, counts = np.unique(values, return_counts=True)
    return zip(keys.tolist(), counts.tolist(), strict=True)


def _seconds(run: dict) -> float:
    if isinstance(run.get("seconds"), (int, float)):
        return float(run["seconds"])
    try:
        start = datetime.fromisoformat(run["start"])
        end = datetime.fromisoformat(run["end"])
    except (KeyError, TypeError, ValueError):
        return 0.0
    return (end - start).total_seconds()
