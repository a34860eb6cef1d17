"""How far a sweep has got: the live progress line of a run, its run-log entry, ``campar status``
and ``campar verify``.

On a terminal the run rewrites one line (tiles done/total, cells/s, ETA) at
most a few times a second; otherwise (a batch job's log) it writes a log line
every ``every`` seconds, so logs stay short and still show the rate.

``status`` and ``verify`` read the store once, tile by tile, checking every
committed tile against its checksum (``store.verify_store``): their memory does
not grow with the grid, and a damaged tile is counted apart, never as done.
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
from ..core.version import KERNEL_VERSION
from .attractor_sets import attractor_sets
from .curves_job import CURVE_TYPES
from .job import DIRECTIONS
from .store import adopt_store, other_kernel, read_store, stored_kernel, verify_store

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
        logging.getLogger("asyncio").addFilter(_only_new_news)


def _only_new_news(record: logging.LogRecord) -> bool:
    """Drop asyncio's "Task exception was never retrieved": zarr writes a store's keys as
    concurrent tasks, raises the first one's error (campar reports it in one line) and
    leaves the others' — the same error — for the garbage collector to log as a traceback."""
    return not record.getMessage().startswith("Task exception was never retrieved")


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


class Tally:
    """Counts of ``campar status``, added up tile by tile (memory does not grow with the grid)."""

    def __init__(self, chatter_p: int):
        self.chatter_p = chatter_p
        self.cells = 0
        self.failed, self.kinds = Counter(), Counter()
        self.labels: dict[str | None, Counter] = {}  # by sweep direction (None: the job's one)
        self.sets: dict[str | None, Counter] = {}  # cells where attractors coexist, by set

    def add(self, check) -> None:
        """One verified tile (``_integrity.TileCheck``)."""
        a = check.arrays
        labels = self.labels.setdefault(check.tile.direction, Counter())
        if "curve_status" in a:  # a curves job: its tasks and the curves they found
            self.cells += a["curve_status"].size
            for t in range(a["curve_index"].shape[0]):
                found = a["curve_index"][t] >= 0
                for k in sorted(set(a["curve_index"][t][found].tolist())):
                    at = a["curve_index"][t] == k
                    kind = CURVE_TYPES[int(a["curve_type"][t][at][0])]
                    labels[f"{kind} of {int(a['curve_n'][t][at][0])}-cycles"] += 1
                if not found.any():
                    labels["tasks without a curve"] += 1
            return
        status, kind = a["status"], a["kind"]
        self.cells += status.size
        self.failed.update(dict(_counts(status[status != 0])))
        self.kinds.update(dict(_counts(kind)))
        periodic = kind == Kind.PERIODIC
        if periodic.any():  # each (n, p) as one integer: a 1-D unique is fast
            pairs = a["n"][periodic].astype(np.int64) << 32 | a["p"][periodic].astype(np.uint32)
            for pair, count in _counts(pairs):
                n, p = pair >> 32, pair & 0xFFFFFFFF
                labels[cell_label(0, n, p, self.chatter_p)] += count
        if "n_attractors" in a:  # a census map: which attractors coexist (2 or more)
            codes, names = attractor_sets(
                a["attractor_kind"],
                a["attractor_n"],
                a["attractor_p"],
                a["n_attractors"],
                self.chatter_p,
            )
            several = self.sets.setdefault(check.tile.direction, Counter())
            for code, count in _counts(codes):
                if "+" in names[code]:
                    several[names[code]] += count


def summarize(reader) -> dict:
    """Counts behind ``campar status``: tiles, cells, failures, kinds, labels, time, and the
    tiles that fail verification (counted apart: not done)."""
    job = reader.job
    tally = Tally(job.classify.chatter_p)
    report = verify_store(reader, tally.add)
    runs = reader.attrs.get("runs", [])
    seconds = sum(_seconds(r) for r in runs)
    cells_run = sum(r.get("cells", 0) for r in runs)
    return {
        "tiles": (int(report.verified.sum()), report.tiles),
        "cells": (tally.cells, job.shape[0] * job.shape[1] * len(job.directions)),
        "failed": {status_message(int(s)): c for s, c in sorted(tally.failed.items())},
        "kinds": {_kind_name(k): c for k, c in sorted(tally.kinds.items())},
        "labels": {
            way: dict(c.most_common())
            for way, c in sorted(
                tally.labels.items(), key=lambda item: DIRECTIONS.index(item[0]) if item[0] else -1
            )
        },
        "sets": {way: dict(c.most_common()) for way, c in tally.sets.items()},
        "damaged": report.damaged,
        "variables": report.variables,
        "problems": report.problems,
        "checksums": report.checksums,
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
        f"grid    {job.shape[0]} {job.second} × {job.shape[1]} {job.first}, "
        f"{job.tiles.rows} rows a tile"
        + (", each chain down and up" if len(job.directions) > 1 else ""),
        f"tiles   {s['tiles'][0]}/{s['tiles'][1]} done" + _damage(s["damaged"]),
        f"cells   {s['cells'][0]}/{s['cells'][1]} done, {failed} failed (status ≠ 0)",
    ]
    lines += [f"          {count} × {why}" for why, count in s["failed"].items()]
    lines += [f"damage  variable {name}: {why}" for name, why in s["variables"].items()]
    lines += [f"damage  {problem}" for problem in s["problems"]]
    if not s["checksums"]:
        lines.append("check   format without checksums: tiles checked for being readable only")
    if s["kinds"]:
        lines.append("kinds   " + ", ".join(f"{k} {c}" for k, c in s["kinds"].items()))
    for way, labels in s["labels"].items():  # a both store: each direction's own
        top = list(labels.items())
        shown = ", ".join(f"{label} {c}" for label, c in top[:max_labels])
        more = f", … {len(top) - max_labels} more" if len(top) > max_labels else ""
        lines.append(f"labels  {f'({way}) ' if way else ''}{shown}{more}")
    for way, sets in s["sets"].items():  # a census map: the attractor sets of 2 or more
        top = list(sets.items())
        shown = ", ".join(f"{name} {c}" for name, c in top[:max_labels]) or "none"
        more = f", … {len(top) - max_labels} more" if len(top) > max_labels else ""
        lines.append(
            f"sets    {f'({way}) ' if way else ''}{shown}{more}  (cells where "
            "several attractors coexist)"
        )
    if s["runs"]:
        lines.append(
            f"runs    {s['runs']} ({s['last_outcome']} last), {format_duration(s['seconds'])} "
            f"in all, {s['cells_per_s']:.1f} cells/s"
        )
    else:
        lines.append("runs    none logged")
    lines.append(kernel_line(reader.attrs))
    return "\n".join(lines)


def kernel_line(attrs: dict) -> str:
    """The ``kernel`` line of ``campar status`` and ``verify``: the version of the kernel
    that computed the store and, where it is not this campar's, what that entails."""
    found = stored_kernel(attrs)
    if other_kernel(attrs) is None:
        return f"kernel  version {found} (this campar's)"
    which = f"version {found}" if found else "an earlier one (the store records no version)"
    return (
        f"kernel  {which}, not this campar's ({KERNEL_VERSION}): `campar run` does not resume "
        "it (--overwrite recomputes it), `campar point --from` recomputes its cells only "
        "with --recompute"
    )


def _damage(damaged: dict[int, str], shown: int = 8) -> str:
    if not damaged:
        return ""
    tiles = ", ".join(map(str, sorted(damaged)[:shown])) + (", …" if len(damaged) > shown else "")
    return (
        f", {len(damaged)} damaged (tiles {tiles}: `campar verify` says why, "
        "`campar run` computes them again)"
    )


def _kind_name(code: int) -> str:
    try:
        return KIND_NAMES[Kind(code)]
    except ValueError:
        return f"kind {code}"


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


# -- campar verify ------------------------------------------------------------------


def verify_report(path) -> tuple[str, bool]:
    """(the text ``campar verify`` prints, whether the store is intact)."""
    start = time.monotonic()
    with read_store(path) as reader:
        report = verify_store(reader)
        job, attrs = reader.job, reader.attrs
    seconds = time.monotonic() - start
    committed, damaged = len(report.committed), len(report.damaged)
    how = "checksums" if report.checksums else "readability only (a format without checksums)"
    lines = [
        f"store   {path}  (job {job.name}, {report.tiles} tiles)",
        (
            f"checked {committed} committed tiles ({how}) in {format_duration(seconds)}: "
            + (
                f"{damaged} damaged"
                if damaged
                else "all intact" + (", but:" if not report.clean else "")
            )
            if report.tiles_checked
            else "tiles not checked, the metadata they are read through is damaged:"
        ),
        *(f"  {line}" for line in report.lines()),
    ]
    lines += [f"note    {note}" for note in report.notes]
    lines.append(kernel_line(attrs))
    if report.root_digest:
        lines.append(f"root    {report.root_digest} (the root record's digest)")
    if not report.clean:
        lines.append(
            "`campar run` on this store repairs it: damaged variables rewritten from the job, "
            "damaged tiles computed again"
        )
    return "\n".join(lines), report.clean


def adopt_report(path) -> tuple[str, bool]:
    """(the text ``campar verify --adopt`` prints, True): the store checked and adopted."""
    report = adopt_store(path)
    kept = int(report.verified.sum())
    lines = [f"store   {path}: adopted, its root record written over {kept} verified tiles"]
    lines += [
        f"  variable {name}: {why} (rewritten from the job)"
        for name, why in report.variables.items()
    ]
    lines += [f"  tile {i}: {why} (left pending)" for i, why in sorted(report.damaged.items())]
    with read_store(path) as reader:
        lines.append(f"root    {reader.root.digest} (the root record's digest)")
    return "\n".join(lines), True
