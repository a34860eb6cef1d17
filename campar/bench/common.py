"""What every benchmark shares: cells, timing, machine load, tables, fits.

Every timing is taken twice: wall-clock seconds (``time.perf_counter``) and
the CPU seconds of this process (``time.process_time``), which other
processes on a shared machine disturb much less (they still share caches and
memory bandwidth). A timing repeats the call for at least ``min_seconds`` and
keeps the fastest run of each. Load averages are printed with every result
because absolute times depend on them; ratios measured in the same run depend
on them much less.
"""

import datetime
import math
import os
import platform
import time
from dataclasses import asdict, dataclass
from typing import NamedTuple

import numpy as np

from ..sweep.job import DEFAULT_MODEL, PAPER_VALUES


@dataclass(frozen=True)
class Cell:
    """One grid cell: the model parameters (docs/model.md) and a short name for tables;
    those not given take the paper's base values."""

    name: str
    omega: float
    f0: float = PAPER_VALUES["f0"]
    mu_kn: float = PAPER_VALUES["mu_kn"]
    mu_cn: float = PAPER_VALUES["mu_cn"]
    zeta: float = PAPER_VALUES["zeta"]
    tensile: str = DEFAULT_MODEL.tensile

    @property
    def parameters(self) -> dict:
        """Keyword arguments of ``simulate_point`` (besides ω)."""
        par = asdict(self)
        par.pop("name")
        par.pop("omega")
        return par

    @property
    def clamp(self) -> bool:
        return self.tensile == "clamp"

    def scipy_model(self):
        from .scipy_model import Model

        return Model(self.omega, self.f0, self.mu_kn, self.mu_cn, self.zeta, self.clamp)

    def describe(self) -> str:
        base = Cell("", 1.0)
        diff = [
            f"{k}={v}"
            for k, v in asdict(self).items()
            if k not in ("name", "omega") and v != getattr(base, k)
        ]
        return " ".join([f"ω={self.omega}", *diff])


class Timing(NamedTuple):
    wall: float  # seconds
    cpu: float  # CPU seconds of this process


def timed(fn) -> tuple[Timing, object]:
    """One call of fn(): its timing and its result."""
    w0, c0 = time.perf_counter(), time.process_time()
    result = fn()
    return Timing(time.perf_counter() - w0, time.process_time() - c0), result


def best_time(fn, min_seconds: float = 0.3, min_runs: int = 3) -> Timing:
    """Fastest wall and CPU time of calls of fn(), repeated for at least min_seconds."""
    wall = cpu = math.inf
    runs = 0
    start = time.perf_counter()
    while runs < min_runs or time.perf_counter() - start < min_seconds:
        t, _ = timed(fn)
        wall, cpu = min(wall, t.wall), min(cpu, t.cpu)
        runs += 1
    return Timing(wall, cpu)


def load_average() -> str:
    one, five, fifteen = os.getloadavg()
    return f"{one:.2f} {five:.2f} {fifteen:.2f}"


def machine_line() -> str:
    """Host, cores, date and load: the line printed above every result table."""
    now = datetime.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z")
    return (
        f"machine: {platform.node()}, {os.cpu_count()} cores, {platform.python_implementation()}"
        f" {platform.python_version()}; {now}; load average {load_average()}"
    )


def format_table(headers: list[str], rows: list[list]) -> str:
    """A plain-text table with right-aligned columns (numbers) and a rule under the header."""
    cells = [[str(h) for h in headers]] + [[cell_text(v) for v in row] for row in rows]
    widths = [max(len(r[j]) for r in cells) for j in range(len(headers))]
    lines = ["  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def cell_text(value) -> str:
    """A table cell: floats to 4 significant digits (NaN "—"), anything else as str()."""
    if isinstance(value, float):
        if math.isnan(value):
            return "—"
        if value == 0.0 or 1e-3 <= abs(value) < 1e5:
            return f"{value:.4g}"
        return f"{value:.2e}"
    return str(value)


def loglog_slope(x, y) -> float:
    """Least-squares slope of log y against log x (NaN with fewer than two points)."""
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    keep = (x > 0) & (y > 0) & np.isfinite(x) & np.isfinite(y)
    if keep.sum() < 2:
        return math.nan
    return float(np.polyfit(np.log(x[keep]), np.log(y[keep]), 1)[0])
