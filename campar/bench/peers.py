"""``campar bench peers``: cells and a map row by campar, a SciPy script and the paper's recipe.

Every peer computes the same cells cold, from (y, y') = (0, 0) at θ = 0:

(a) campar as a map runs it: converged transient (Newton-accelerated), DP5(4)
    at rtol 1e-8, atol 1e-10, outputs label, dc, eps, pn (``run_tile``);
(b) the SciPy script a researcher writes today (``scipy_peer``): solve_ivp
    DOP853 with terminal events, piecewise between cam phase boundaries, rtol
    1e-8 / atol 1e-10 like campar, a fixed transient of 500 revolutions like
    the paper and the same read window as (c);
(c) the paper's recipe: fixed-step RK4 (600 steps per revolution, campar's
    default), a fixed 500-revolution transient and a 64-revolution read
    window — campar's own compiled RK4 path, so (c)/(a) measures the method
    (adaptive steps, early stop), not the language.

Times are CPU seconds of this process (the machine is shared; wall times of
SciPy are shown too). Agreement: the same n-p label and duty cycles within 0.002 (non-periodic
cells: non-periodic in every peer). Speed ratios are quoted only for cells
where the peers agree. A second SciPy ratio charges SciPy only for the
revolutions campar needed (its time per revolution × campar's revolutions):
what SciPy would cost with campar's transient policy, i.e. the compiled
kernel's share of the speed-up.

A second comparison computes a piece of a map the way each peer computes a
map: consecutive cells of the (ω, μcn) plane's 400 × 400 grid (jobs/mu_cn_wide.yaml)
along ω, each cell started from the previous cell's final state (the first
from rest), by campar (one ``run_tile`` of the row), by the SciPy script
(500 + 64 revolutions per cell, warm-started the same way) and by the paper's
recipe. Its ratio is the row's total time; it is quoted only when every peer
agrees on every cell.
"""

import math
from functools import partial
from typing import NamedTuple

import numpy as np

from ..core.codes import Kind, cell_label
from ..sweep.job import DEFAULT_CLASSIFY, DEFAULT_INTEGRATOR, DEFAULT_TRANSIENT, Job, cell_job
from ..sweep.plan import Tile
from ..sweep.tile import run_tile
from .common import Cell, Timing, best_time, format_table, machine_line, timed
from .scipy_peer import scipy_cell

CELLS = (
    Cell("1-0 ω0.3", 0.3),
    Cell("1-1 ω1", 1.0),
    Cell("1-2 ω1.2 f0.01", 1.2, f0=0.01),
    Cell("1-3 ω0.62 μcn.5", 0.62, mu_cn=0.5),
    Cell("2-2 ω3.15 μkn.91", 3.15, mu_kn=0.91),
    Cell("2-2 ω3.5 μcn.5", 3.5, mu_cn=0.5),
    Cell("chaos ω4.5 μcn.97", 4.5, mu_cn=0.97),
)
# The map row: the grid of jobs/mu_cn_wide.yaml (ω 6.0 → 0.02 and μcn 0.99 → 0.50, 400
# points each; the other parameters at the paper's base values), chain 155 (μcn ≈ 0.80),
# ω points 299 … 314 (ω ≈ 1.52 … 1.29): 1-1, then 1-2 from ω ≈ 1.504, then 1-1 again
# from ω ≈ 1.294.
ROW_GRID = {"omega": (6.0, 0.02, 400), "mu_cn": (0.99, 0.50, 400)}
ROW_CHAIN = 155
ROW_OMEGA = (299, 315)
QUICK = {
    "cells": ["1-0 ω0.3", "1-2 ω1.2 f0.01"],
    "revolutions": 20,
    "window": 8,
    "scipy_cells": 1,
    "min_seconds": 0.02,
    "row_omega": (299, 302),
}
DC_AGREEMENT = 0.002
OUTPUTS = ["label", "dc", "eps", "pn"]


class Outcome(NamedTuple):
    label: str
    periodic: bool
    dc: float
    revolutions: int
    seconds: float  # CPU seconds (fastest run for campar; one run for SciPy)
    wall: float


def with_window(job: Job, window: int) -> Job:
    return job.model_copy(
        update={"classify": job.classify.model_copy(update={"window_revolutions": window})}
    )


def campar_outcomes(job: Job, min_seconds: float) -> tuple[list[Outcome], Timing]:
    """Every cell of a one-chain job, and the fastest time of the whole chain."""
    tile = Tile(0, 0, 1)
    out = {name: arr[0] for name, arr in run_tile(job, tile).items()}
    took = best_time(lambda: run_tile(job, tile), min_seconds)
    cells = []
    for j in range(out["kind"].size):
        kind = int(out["kind"][j])
        label = cell_label(kind, int(out["n"][j]), int(out["p"][j]), job.classify.chatter_p)
        cells.append(
            Outcome(
                label,
                kind == Kind.PERIODIC,
                float(out["dc"][j]),
                int(out["revolutions"][j]),
                took.cpu,
                took.wall,
            )
        )
    return cells, took


def campar_outcome(
    cell: Cell, method: str, transient: str, revolutions: int, window: int, min_seconds: float
) -> Outcome:
    job = cell_job(
        omega=cell.omega,
        **cell.parameters,
        transient=transient,
        revolutions=revolutions,
        method=method,
        outputs=OUTPUTS,
    )
    return campar_outcomes(with_window(job, window), min_seconds)[0][0]


def scipy_outcome(cell: Cell, revolutions: int, window: int, rtol: float) -> Outcome:
    model = cell.scipy_model()
    took, r = timed(lambda: scipy_cell(model, (0.0, 0.0), revolutions, window, rtol=rtol))
    return Outcome(r.label, r.n > 0, r.dc, revolutions + window, took.cpu, took.wall)


def agree(a: Outcome, b: Outcome) -> bool:
    if not (a.periodic or b.periodic):
        return True
    return a.label == b.label and abs(a.dc - b.dc) <= DC_AGREEMENT


class PeerRow(NamedTuple):
    cell: Cell
    campar: Outcome
    paper: Outcome
    scipy: Outcome | None
    agree: bool


def measure(
    cells=None,
    revolutions=DEFAULT_TRANSIENT.max_revolutions,
    window=DEFAULT_CLASSIFY.window_revolutions,
    scipy_cells=None,
    scipy_rtol=DEFAULT_INTEGRATOR.rtol,
    min_seconds=0.3,
) -> list[PeerRow]:
    """Every peer on every chosen cell; SciPy only on the first scipy_cells (None: all)."""
    chosen = [c for c in CELLS if cells is None or c.name in cells]
    rows = []
    for i, cell in enumerate(chosen):
        a = campar_outcome(
            cell, DEFAULT_INTEGRATOR.method, "converged", revolutions, window, min_seconds
        )
        c = campar_outcome(cell, "rk4", "fixed", revolutions, window, min_seconds)
        b = None
        if scipy_cells is None or i < scipy_cells:
            b = scipy_outcome(cell, revolutions, window, scipy_rtol)
        ok = agree(a, c) and (b is None or (agree(a, b) and agree(b, c)))
        rows.append(PeerRow(cell, a, c, b, ok))
    return rows


def row_job(
    first: int, stop: int, method: str, transient: str, revolutions: int, window: int
) -> Job:
    """ω points first … stop−1 of chain ROW_CHAIN of the map row's grid, as one chain."""
    omega = np.linspace(*ROW_GRID["omega"])
    mu_cn = float(np.linspace(*ROW_GRID["mu_cn"])[ROW_CHAIN])
    data = {
        "name": "peers_row",
        "sweep": {
            "omega": {
                "from": float(omega[first]),
                "to": float(omega[stop - 1]),
                "points": stop - first,
            },
            "mu_cn": {"from": mu_cn, "to": mu_cn, "points": 1},
        },
        "integrator": {"method": method},
        "transient": {"mode": transient, "max_revolutions": revolutions},
        "outputs": OUTPUTS,
        "tiles": {"rows": 1},
    }
    return with_window(Job.from_dict(data, source="peers row"), window)


class RowResult(NamedTuple):
    omega: np.ndarray
    mu_cn: float
    campar: list[Outcome]  # per cell; seconds are those of the whole row
    paper: list[Outcome]
    scipy: list[Outcome]  # per cell, its own seconds
    campar_time: Timing
    paper_time: Timing
    agree: list[bool]


def measure_row(
    row_omega=ROW_OMEGA,
    revolutions=DEFAULT_TRANSIENT.max_revolutions,
    window=DEFAULT_CLASSIFY.window_revolutions,
    scipy_rtol=DEFAULT_INTEGRATOR.rtol,
    min_seconds=0.3,
) -> RowResult:
    """The map row by every peer, each cell warm-started from the one before."""
    first, stop = row_omega
    job = row_job(first, stop, DEFAULT_INTEGRATOR.method, "converged", revolutions, window)
    campar, campar_time = campar_outcomes(job, min_seconds)
    paper_job = row_job(first, stop, "rk4", "fixed", revolutions, window)
    paper, paper_time = campar_outcomes(paper_job, min_seconds)
    mu_cn = float(job.second_values[0])
    scipy = []
    x = np.zeros(2)
    for omega in job.omega:
        cell = Cell("", float(omega), mu_cn=mu_cn)
        took, r = timed(
            partial(scipy_cell, cell.scipy_model(), x, revolutions, window, rtol=scipy_rtol)
        )
        scipy.append(Outcome(r.label, r.n > 0, r.dc, revolutions + window, took.cpu, took.wall))
        x = r.sections[-1]  # the next cell starts where this one ended
    ok = [
        agree(a, b) and agree(a, c) and agree(b, c)
        for a, b, c in zip(campar, scipy, paper, strict=True)
    ]
    return RowResult(job.omega, mu_cn, campar, paper, scipy, campar_time, paper_time, ok)


def format_row(row: RowResult) -> str:
    headers = ["ω", "campar", "DC", "revs", "RK4 500", "DC", "SciPy 500", "DC", "CPU s", "agree"]
    lines = []
    for omega, a, c, b, ok in zip(
        row.omega, row.campar, row.paper, row.scipy, row.agree, strict=True
    ):
        lines.append(
            [
                float(omega),
                a.label,
                a.dc,
                a.revolutions,
                c.label,
                c.dc,
                b.label,
                b.dc,
                b.seconds,
                "yes" if ok else "NO",
            ]
        )
    return format_table(headers, lines)


def row_summary(row: RowResult) -> str:
    cells = len(row.campar)
    campar = row.campar_time.cpu
    paper = row.paper_time.cpu
    scipy = sum(b.seconds for b in row.scipy)
    revs = sum(a.revolutions for a in row.campar) / cells
    agreeing = sum(row.agree)
    lines = [
        f"map row, μcn {row.mu_cn:.4f}, ω {row.omega[0]:.4f} … {row.omega[-1]:.4f}, {cells} "
        f"cells warm-started along ω: all peers agree on {agreeing} of {cells}",
        f"  campar {campar * 1e3:.2f} CPU ms ({campar / cells * 1e3:.3f} ms, {revs:.2f} "
        f"revolutions per cell); RK4 recipe {paper:.2f} s; SciPy {scipy:.1f} s",
    ]
    if agreeing == cells:
        lines.append(
            f"  map row: RK4 recipe / campar {paper / campar:.0f}×, SciPy / campar "
            f"{scipy / campar:.0f}×"
        )
    else:
        lines.append("  map row: no ratio (the peers disagree on some cells)")
    return "\n".join(lines)


def geometric_mean(values) -> float:
    values = [v for v in values if v > 0 and math.isfinite(v)]
    return math.exp(sum(map(math.log, values)) / len(values)) if values else math.nan


def format_rows(rows: list[PeerRow]) -> str:
    headers = [
        "cell",
        "campar",
        "DC",
        "revs",
        "CPU ms",
        "RK4 500",
        "DC",
        "CPU ms",
        "SciPy 500",
        "DC",
        "CPU s",
        "wall s",
        "ms/rev",
        "agree",
        "RK4/campar",
        "SciPy/campar",
        "SciPy@revs/campar",
    ]
    out = []
    for r in rows:
        a, c, b = r.campar, r.paper, r.scipy
        line = [
            r.cell.name,
            a.label,
            a.dc,
            a.revolutions,
            a.seconds * 1e3,
            c.label,
            c.dc,
            c.seconds * 1e3,
        ]
        if b is None:
            line += ["not run", math.nan, math.nan, math.nan, math.nan]
        else:
            line += [b.label, b.dc, b.seconds, b.wall, b.seconds / b.revolutions * 1e3]
        line.append("yes" if r.agree else "NO")
        scale = 1.0 / a.seconds if r.agree else math.nan  # ratios only at equal agreement
        line.append(c.seconds * scale)
        line.append(b.seconds * scale if b else math.nan)
        line.append(b.seconds / b.revolutions * a.revolutions * scale if b else math.nan)
        out.append(line)
    return format_table(headers, out)


def summary(rows: list[PeerRow]) -> str:
    ok = [r for r in rows if r.agree]
    periodic = [r for r in ok if r.campar.periodic]
    scipy = [r for r in ok if r.scipy is not None]
    lines = [f"cells where all peers agree: {len(ok)} of {len(rows)}"]
    for name, sel in (("periodic cells", periodic), ("all agreeing cells", ok)):
        paper = [r.paper.seconds / r.campar.seconds for r in sel]
        if paper:
            lines.append(
                f"RK4 recipe / campar, {name}: geometric mean "
                f"{geometric_mean(paper):.0f}×, min {min(paper):.0f}×, "
                f"max {max(paper):.0f}×"
            )
    sel = [r for r in scipy if r.campar.periodic]
    if sel:
        per_cell = np.mean([r.scipy.seconds for r in sel])
        per_rev = np.mean([r.scipy.seconds / r.scipy.revolutions for r in sel])
        ratio = [r.scipy.seconds / r.campar.seconds for r in sel]
        at_revs = [
            r.scipy.seconds / r.scipy.revolutions * r.campar.revolutions / r.campar.seconds
            for r in sel
        ]
        campar_cell = np.mean([r.campar.seconds for r in sel])
        lines += [
            f"SciPy / campar, periodic cells timed ({len(sel)}): geometric mean "
            f"{geometric_mean(ratio):.0f}×, min {min(ratio):.0f}×",
            f"SciPy with campar's revolution count / campar: geometric mean "
            f"{geometric_mean(at_revs):.0f}× (the compiled kernel's share)",
            f"per cell: SciPy {per_cell:.2f} s ({per_rev * 1e3:.1f} ms/revolution), campar "
            f"{campar_cell * 1e3:.2f} ms; a 400 × 400 map: SciPy ≈ "
            f"{per_cell * 160_000 / 86400:.1f} CPU-days, campar (cold cells) ≈ "
            f"{campar_cell * 160_000 / 60:.1f} CPU-minutes",
        ]
    return "\n".join(lines)


def run(args) -> int:
    config = {
        "cells": args.cells,
        "revolutions": args.revolutions,
        "window": args.window,
        "scipy_cells": args.scipy_cells if args.scipy_cells >= 0 else None,
        "min_seconds": args.min_seconds,
        "row_omega": ROW_OMEGA,
    }
    if args.quick:
        config.update({k: v for k, v in QUICK.items() if k != "cells" or not args.cells})
    row_omega = config.pop("row_omega")
    print(machine_line())
    rows = measure(scipy_rtol=args.scipy_rtol, **config)
    print(format_rows(rows))
    print()
    print(summary(rows))
    if not args.no_row:
        row = measure_row(
            row_omega,
            config["revolutions"],
            config["window"],
            args.scipy_rtol,
            config["min_seconds"],
        )
        print()
        print(format_row(row))
        print()
        print(row_summary(row))
    print(f"load average at the end: {machine_line().rsplit('load average ', 1)[1]}")
    return 0
