"""``campar bench stress``: extreme parameters and starts — no crash, no hang, valid or failed.

The grid: μkn, μcn ∈ {0.99, 0.999, 0.9999}, ω ∈ {0.001, 50}, f0 ∈ {0, 100},
ζ ∈ {0, 2}, starts (y, y') ∈ {(0, 0), (100, −100), (−100, 100)}, tensile
clamp and allow (432 cells), plus a few edge cells at the paper's μ values:
a follower resting exactly on the grazing boundary (f0 = 0 or 1e-12 at low ω).
Every cell runs at each rtol (atol = rtol / 100) with a step budget per cell,
in a child process with a time limit, so that a hang or a crash of the
compiled kernel is caught and reported instead of stopping the benchmark.

A result is valid when it carries status ok with finite numbers, 0 ≤ DC ≤ 1,
ε min ≤ ε max, Pn max ≥ 0 under the clamp and a consistent duty cycle (DC > 0
only where ε < 0 somewhere) — or a failure status with NaNs. Anything else
(a hang, a crash, an exception, an invalid "ok") is a finding for the kernel.

Labels at the two tolerances are compared; a periodic label at the tighter
one (at both where the label changed) is checked against SciPy
(``scipy_model.integrate`` at that tolerance with at most 1000 steps per
revolution, from campar's final state, for n revolutions: the same detachment
count and a return to within 1e-5) when SciPy can afford it, in the child
process with the same time limit.
"""

import math
import multiprocessing
import time
from itertools import product
from typing import NamedTuple

import numpy as np

from ..core.codes import FAILED, OK, PERIODIC, Flag, Status, cell_label
from ..sweep.job import cell_job
from ..sweep.plan import Tile
from ..sweep.tile import run_tile
from .common import Cell, format_table, machine_line
from .scipy_model import integrate

MU = (0.99, 0.999, 0.9999)
STARTS = ((0.0, 0.0), (100.0, -100.0), (-100.0, 100.0))
EDGE_CELLS = (
    (Cell("rest on ε = 0, ω .001", 0.001, f0=0.0), (0.0, 0.0)),
    (Cell("rest on ε = 0, ω .01", 0.01, f0=0.0), (0.0, 0.0)),
    (Cell("rest at ε ≈ 4e-9, ω .001", 0.001, f0=1e-12), (0.0, 0.0)),
    (Cell("rest at ε ≈ 4e-9, ω .01", 0.01, f0=1e-12), (0.0, 0.0)),
)
# The fast subset (tests/test_stress.py): corners of the grid and the edge cells.
QUICK_CELLS = (
    (Cell("q1", 0.001, f0=100.0, mu_kn=0.9999, mu_cn=0.9999, zeta=2.0), (100.0, -100.0)),
    (Cell("q2", 0.001, f0=0.0, mu_kn=0.99, mu_cn=0.99, zeta=0.0, tensile="allow"), (0.0, 0.0)),
    (Cell("q3", 50.0, f0=100.0, mu_kn=0.9999, mu_cn=0.99, zeta=0.0), (-100.0, 100.0)),
    (Cell("q4", 50.0, f0=0.0, mu_kn=0.99, mu_cn=0.9999, zeta=2.0, tensile="allow"), (0.0, 0.0)),
    (Cell("q5", 50.0, f0=100.0, mu_kn=0.999, mu_cn=0.999, zeta=2.0), (100.0, -100.0)),
    (
        Cell("q6", 50.0, f0=0.0, mu_kn=0.9999, mu_cn=0.9999, zeta=0.0, tensile="allow"),
        (-100.0, 100.0),
    ),
    EDGE_CELLS[0],
    EDGE_CELLS[1],
)
QUICK = {"budget": 200_000, "timeout": 60.0, "check": 4}
SCIPY_MAX_STEPS = 100_000  # check with SciPy only cells campar needs fewer steps for
# solve_ivp sees an event only as a sign change between step ends: a short contact
# inside a step goes unseen (found at ω = 50, f0 = 100, μkn = .9999, μcn = .99, ζ = 2,
# where the closed-form free flight confirms campar's contact); bound its step.
SCIPY_STEPS_PER_REV = 1000
RETURN_TOL = 1e-5
WORKER_START = 120.0  # seconds a fresh worker may take to load the compiled kernel
BAD = ("HANG", "CRASH", "ERROR", "INVALID")


def grid_cells():
    for kn, cn, omega, f0, zeta, start, tensile in product(
        MU, MU, (0.001, 50.0), (0.0, 100.0), (0.0, 2.0), STARTS, ("clamp", "allow")
    ):
        name = (
            f"ω{omega:g} f0={f0:g} μkn={kn} μcn={cn} ζ={zeta:g} {tensile} "
            f"y0,v0={start[0]:g},{start[1]:g}"
        )
        yield Cell(name, omega, f0=f0, mu_kn=kn, mu_cn=cn, zeta=zeta, tensile=tensile), start


class Result(NamedTuple):
    outcome: str  # "ok", a failure ("failed: …"), or one of BAD
    label: str
    arrays: dict  # the cell's outputs (empty when the worker gave none)
    cpu: float  # CPU seconds in the worker
    wall: float  # wall seconds seen by the parent
    detail: str


def compute_cell(cell: Cell, start, rtol: float, budget: int) -> dict:
    """One cell through run_tile with a step budget: the outputs of the cell."""
    job = cell_job(
        omega=cell.omega,
        **cell.parameters,
        y0=start[0],
        v0=start[1],
        rtol=rtol,
        atol=rtol * 1e-2,
        outputs=["label", "dc", "eps", "pn"],
    )
    job = job.model_copy(
        update={"integrator": job.integrator.model_copy(update={"max_steps": budget})}
    )
    return {name: arr[0, 0] for name, arr in run_tile(job, Tile(0, 0, 1)).items()}


def _serve(conn) -> None:
    """Worker process: run the tasks sent over conn until None arrives."""
    tasks = {"cell": compute_cell, "scipy": scipy_check}
    while True:
        task = conn.recv()
        if task is None:
            return
        c0 = time.process_time()
        try:
            value = tasks[task[0]](*task[1:])
        except Exception as exc:  # reported as a finding, never raised in the parent
            conn.send(("ERROR", f"{type(exc).__name__}: {exc}", 0.0))
        else:
            conn.send(("done", value, time.process_time() - c0))


class Worker:
    """Tasks in a child process; one over its time limit kills the child (a hang)."""

    def __init__(self, timeout: float):
        self.timeout = timeout
        self.proc = None
        self.conn = None

    def _start(self) -> None:
        ctx = multiprocessing.get_context("spawn")
        self.conn, child = ctx.Pipe()
        self.proc = ctx.Process(target=_serve, args=(child,), daemon=True)
        self.proc.start()
        child.close()
        # load the compiled kernel before the first timed cell
        self.conn.send(("cell", Cell("warm-up", 1.0), (0.0, 0.0), 1e-8, 10_000))
        if not self.conn.poll(WORKER_START):
            raise RuntimeError("the stress worker did not start")
        self.conn.recv()

    def stop(self) -> None:
        if self.proc is not None:
            if self.proc.is_alive():
                self.conn.send(None)
                self.proc.join(5)
            if self.proc.is_alive():
                self.proc.kill()
            self.proc.join()
        self.proc = None

    def call(self, *task) -> tuple[str, object, float, float]:
        """(outcome "done" or one of BAD, value or message, CPU s in the child, wall s)."""
        if self.proc is None:
            self._start()
        w0 = time.perf_counter()
        self.conn.send(task)
        if not self.conn.poll(self.timeout):
            self.proc.kill()  # the child we started, by its handle
            self.proc.join()
            self.proc = None
            return "HANG", f"no result after {self.timeout:g} s", math.nan, self.timeout
        try:
            outcome, value, cpu = self.conn.recv()
        except EOFError:
            self.proc.join(1)
            code = self.proc.exitcode
            self.proc = None
            return "CRASH", f"worker died, exit code {code}", math.nan, time.perf_counter() - w0
        return outcome, value, cpu, time.perf_counter() - w0

    def run_cell(self, cell: Cell, start, rtol: float, budget: int) -> Result:
        outcome, value, cpu, wall = self.call("cell", cell, start, rtol, budget)
        if outcome != "done":
            return Result(outcome, "—", {}, cpu, wall, value)
        arrays = value
        label = cell_label(int(arrays["kind"]), int(arrays["n"]), int(arrays["p"]))
        problems = check(arrays, cell.clamp)
        if problems:
            return Result("INVALID", label, arrays, cpu, wall, "; ".join(problems))
        status = int(arrays["status"])
        outcome = "ok" if status == OK else f"failed: {Status(status).name.lower()}"
        return Result(outcome, label, arrays, cpu, wall, "")

    def scipy_verdict(self, cell: Cell, arrays: dict, rtol: float) -> str:
        outcome, value, _, _ = self.call("scipy", cell, arrays, rtol)
        return value if outcome == "done" else f"SciPy check {outcome}: {value}"


def check(a: dict, clamp: bool) -> list[str]:
    """What is wrong with one cell's outputs (empty: a valid result or a clean failure)."""
    numbers = [float(a[k]) for k in ("dc", "eps_min", "eps_max", "pn_max")] + list(a["state"])
    if int(a["status"]) != OK:
        bad = [] if int(a["kind"]) == FAILED else ["failure status but kind is not 'failed'"]
        if any(math.isfinite(x) for x in numbers):
            bad.append("failure status but finite numbers")
        return bad
    bad = []
    if int(a["kind"]) == FAILED:
        bad.append("status ok but kind 'failed'")
    if not all(math.isfinite(x) for x in numbers):
        bad.append("non-finite numbers with status ok")
        return bad
    dc, eps_min, eps_max, pn_max = numbers[:4]
    if not 0.0 <= dc <= 1.0:
        bad.append(f"DC = {dc} outside [0, 1]")
    if eps_min > eps_max:
        bad.append(f"ε min {eps_min} > ε max {eps_max}")
    if clamp and pn_max < 0.0:
        bad.append(f"Pn max {pn_max} < 0 under the clamp")
    if dc > 0.0 and eps_min > 0.0:
        bad.append(f"DC = {dc} > 0 but ε > 0 throughout (ε min {eps_min})")
    if int(a["kind"]) == PERIODIC and int(a["n"]) < 1:
        bad.append("periodic with n < 1")
    if int(a["p"]) < 0 or int(a["n"]) < 0:
        bad.append("negative n or p")
    return bad


def scipy_check(cell: Cell, a: dict, rtol: float) -> str:
    """SciPy's verdict on a periodic result: integrate n revolutions from its state."""
    n = int(a["n"])
    steps_per_rev = int(a["steps"]) / max(int(a["revolutions"]), 1)
    if steps_per_rev * n > SCIPY_MAX_STEPS:
        return "not checked (too long for SciPy)"
    x0 = np.array(a["state"], float)
    model = cell.scipy_model()
    max_step = 2 * math.pi / cell.omega / SCIPY_STEPS_PER_REV
    x, events, _ = integrate(model, x0, n, rtol=rtol, atol=rtol * 1e-2, max_step=max_step)
    p = sum(kind == "detachment" for _, kind in events)
    dx = float(np.max(np.abs(x - x0)))
    if p == int(a["p"]) and dx <= RETURN_TOL:
        return "SciPy agrees"
    return f"SciPy DISAGREES: p = {p}, |x_n − x_0| = {dx:.1e}"


class Row(NamedTuple):
    cell: Cell
    start: tuple
    results: list  # one Result per rtol
    scipy: str


def measure(cells, rtols=(1e-8, 1e-10), budget=1_000_000, timeout=120.0, check_max=40) -> list[Row]:
    worker = Worker(timeout)
    try:
        rows = [
            Row(cell, start, [worker.run_cell(cell, start, rtol, budget) for rtol in rtols], "")
            for cell, start in cells
        ]
        check_with_scipy(worker, rows, rtols, check_max)
    finally:
        worker.stop()
    return rows


def check_with_scipy(worker: Worker, rows: list, rtols, check_max: int) -> None:
    """SciPy's verdicts into rows: both tolerances where the label changed, else the
    tightest; label changes first, at most check_max checks."""
    order = sorted(range(len(rows)), key=lambda i: not label_changed(rows[i]))
    checked = 0
    for i in order:
        row = rows[i]
        which = range(len(rtols)) if label_changed(row) else [len(rtols) - 1]
        verdicts = []
        for j in which:
            r = row.results[j]
            if checked >= check_max or r.outcome != "ok" or int(r.arrays["kind"]) != PERIODIC:
                continue
            verdict = worker.scipy_verdict(row.cell, r.arrays, rtols[j])
            checked += not verdict.startswith("not checked")
            verdicts.append(f"{rtols[j]:g}: {verdict}" if len(which) > 1 else verdict)
        rows[i] = row._replace(scipy="; ".join(verdicts))


def label_changed(row: Row) -> bool:
    ok = [r for r in row.results if r.outcome == "ok"]
    return len(ok) == len(row.results) and len({r.label for r in ok}) > 1


def flags(r: Result) -> str:
    value = int(r.arrays.get("flags", 0))
    return ",".join(f.name.lower() for f in (Flag.GRAZING, Flag.SLOW) if value & f) or "-"


def format_row(row: Row) -> list:
    return [
        row.cell.name,
        " → ".join(r.outcome.removeprefix("failed: ") for r in row.results),
        " → ".join(r.label for r in row.results),
        " → ".join(flags(r) for r in row.results),
        max(r.cpu for r in row.results),
        max(r.wall for r in row.results),
        max(int(r.arrays.get("steps", 0)) for r in row.results),
        "; ".join(x for x in [*(r.detail for r in row.results), row.scipy] if x),
    ]


HEADERS = ["cell", "status", "labels (rtols)", "flags", "CPU s", "wall s", "steps", "remarks"]


def summary(rows: list[Row], rtols) -> str:
    results = [r for row in rows for r in row.results]
    outcomes = {}
    for r in results:
        key = r.outcome if r.outcome in BAD or r.outcome == "ok" else r.outcome
        outcomes[key] = outcomes.get(key, 0) + 1
    worst = max(results, key=lambda r: r.wall)
    worst_row = next(row for row in rows if worst in row.results)
    changed = [row for row in rows if label_changed(row)]
    grazing = [row for row in changed if "grazing" in flags(row.results[-1])]
    disagree = [row for row in rows if "DISAGREES" in row.scipy]
    unflagged = [row for row in disagree if "grazing" not in flags(row.results[-1])]
    agree = sum("agrees" in row.scipy for row in rows)
    lines = [f"{len(rows)} cells × {len(rtols)} rtols ({', '.join(f'{t:g}' for t in rtols)}):"]
    lines += [f"  {count:4d}  {name}" for name, count in sorted(outcomes.items())]
    lines += [
        f"worst time per cell: {worst.wall:.2f} s wall, {worst.cpu:.2f} s CPU "
        f"({worst_row.cell.name}); worst CPU: {max(r.cpu for r in results):.2f} s",
        f"label changes between rtols (both ok): {len(changed)}, of them flagged grazing "
        f"(p sensitive by design): {len(grazing)}",
        f"SciPy checks: {agree} cells agree, {len(disagree)} disagree, of them not flagged "
        f"grazing: {len(unflagged)}",
    ]
    lines += [
        f"  DISAGREES: {row.cell.describe()} start {row.start}: "
        f"{' → '.join(r.label for r in row.results)} [{flags(row.results[-1])}]; "
        f"{row.scipy}"
        for row in disagree
    ]
    bad = [row for row in rows if any(r.outcome in BAD for r in row.results)]
    lines += [
        f"  {r.outcome}: {row.cell.describe()} start {row.start}: {r.detail}"
        for row in bad
        for r in row.results
        if r.outcome in BAD
    ]
    return "\n".join(lines)


def run(args) -> int:
    budget, timeout, check_max = args.budget, args.timeout, args.check
    cells = [*grid_cells(), *EDGE_CELLS]
    if args.quick:
        cells = list(QUICK_CELLS)
        budget, timeout, check_max = QUICK["budget"], QUICK["timeout"], QUICK["check"]
    print(machine_line())
    print(f"step budget {budget} per cell, time limit {timeout:g} s per cell")
    t0 = time.perf_counter()
    rows = measure(cells, args.rtols, budget, timeout, check_max)
    print(format_table(HEADERS, [format_row(r) for r in rows]))
    print()
    print(summary(rows, args.rtols))
    print(
        f"total {time.perf_counter() - t0:.0f} s; load average at the end: "
        f"{machine_line().rsplit('load average ', 1)[1]}"
    )
    bad = any(r.outcome in BAD for row in rows for r in row.results)
    return 1 if bad else 0
