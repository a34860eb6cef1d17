"""``campar bench precision``: wall time and work against error, DP5(4) and RK4.

For each cell, campar integrates a few whole revolutions from a state on the
cell's attractor (its steady state at rtol 1e-10; for a chaotic cell a state
after 500 revolutions) with

* DP5(4) (Dormand–Prince 1980, adaptive, exact events) at rtol 1e-4 … 1e-12
  (atol = rtol / 100), and
* fixed-step RK4 at 60 … 7680 steps per revolution (steps still end on cam
  phase boundaries and events),

and compares the state after k revolutions and every event time (impact,
detachment, clamp switches) with SciPy's DOP853 at rtol 1e-13, integrated
piecewise between cam boundaries and exact events (``scipy_model.integrate``).
The reference's own error is estimated as its distance from the same
integration at rtol 1e-12, and fits use only errors above 3× that floor.

Fits (least squares in log-log): DP5 error against rtol (tolerance
proportionality: slope ≈ 1), DP5 error against accepted steps (slope −5 where
the field is smooth) and RK4 error against steps (−4 for a smooth field).
Steps are accepted steps (rejected DP5 steps are not counted; a DP5 step costs
6 field evaluations, an RK4 step 4).
"""

import math
from typing import NamedTuple

import numpy as np

from ..core.revolution import make_trace
from ..core.tracer import trace_orbit
from ..sweep.job import DEFAULT_INTEGRATOR, cell_job
from ..sweep.tile import cell_settings, solver_options
from ..views.point import EVENT_NAMES, simulate_point
from .common import (
    Cell,
    Timing,
    best_time,
    format_table,
    loglog_slope,
    machine_line,
    timed,
)
from .scipy_model import integrate

# (cell, revolutions integrated): contact only (smooth but for the cam law),
# impacts with clamp switches, a 2-cycle with impacts, and chaos (short horizon).
CELLS = (
    (Cell("1-0 contact", 0.3), 2),
    (Cell("1-2 impacts", 1.2, f0=0.01), 3),
    (Cell("2-2 impacts", 3.15, mu_kn=0.91), 4),
    (Cell("chaos", 4.5, mu_cn=0.97), 4),
)
RTOLS = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)
RK4_STEPS = (60, 120, 240, 480, 960, 1920, 3840, 7680)
SCIPY_RTOLS = (1e-6, 1e-8, 1e-10)
QUICK = {
    "cells": ["1-0 contact", "1-2 impacts"],
    "rtols": [1e-4, 1e-6, 1e-8, 1e-10],
    "rk4_steps": [120, 480],
    "scipy_rtols": [],
    "min_seconds": 0.02,
}
FLOOR_FACTOR = 3.0  # fit only errors above this multiple of the reference's own error
MAX_SAMPLES = 2_000_000  # trace rows: one per accepted step (enough for RK4 at 7680/rev × 4)


class Run(NamedTuple):
    cell: str
    method: str  # "dp54", "rk4" or "scipy"
    setting: float  # rtol, or RK4 steps per revolution
    steps: int  # accepted steps over the horizon (SciPy: -1)
    time: Timing  # fastest run
    state_error: float  # ∞-norm of (y, y') after the horizon
    event_error: float  # largest event-time error; NaN if the event sequence differs
    events_match: bool


class Reference(NamedTuple):
    state: np.ndarray
    events: list  # (t, kind)
    state_floor: float  # estimated error of the reference
    event_floor: float
    time: Timing


def start_state(cell: Cell) -> np.ndarray:
    """A state on the cell's attractor: its final state at rtol 1e-10."""
    r = simulate_point(cell.omega, **cell.parameters, rtol=1e-10)
    return np.array(r.state)


def reference(cell: Cell, x0, revolutions: int, rtol: float) -> Reference:
    model = cell.scipy_model()
    took, (state, events, _) = timed(
        lambda: integrate(model, x0, revolutions, rtol=rtol, atol=rtol * 1e-2)
    )
    coarse, coarse_events, _ = integrate(model, x0, revolutions, rtol=rtol * 10, atol=rtol * 0.1)
    event_floor = event_error(coarse_events, events)
    return Reference(state, events, float(np.max(np.abs(coarse - state))), event_floor, took)


def event_error(events, ref_events) -> float:
    """Largest event-time difference; NaN when the sequences of kinds differ."""
    if [k for _, k in events] != [k for _, k in ref_events]:
        return math.nan
    times = np.array([t for t, _ in events])
    return float(np.max(np.abs(times - np.array([t for t, _ in ref_events])), initial=0.0))


def campar_call(cell: Cell, x0, revolutions: int, method: str, rtol: float, rk4_steps: int):
    """A function f(rec) running trace_orbit once; rec = make_trace(0, 0, 1) records nothing."""
    job = cell_job(
        omega=cell.omega,
        **cell.parameters,
        y0=x0[0],
        v0=x0[1],
        transient="fixed",
        revolutions=1,
        rtol=rtol,
        atol=rtol * 1e-2,
        method=method,
        outputs=["label"],
    )
    settings = cell_settings(job)._replace(rk4_steps=rk4_steps, max_steps=10**9)
    solver = solver_options(job)
    x = np.asarray(x0, float)

    def call(rec):
        return trace_orbit(
            cell.omega,
            cell.zeta,
            cell.f0,
            cell.mu_kn,
            cell.mu_cn,
            cell.clamp,
            x,
            solver,
            settings,
            revolutions,
            rec,
        )

    return call


def campar_run(cell, x0, revolutions, ref: Reference, *, method, setting, min_seconds) -> Run:
    """One campar run: DP5(4) at rtol ``setting``, or RK4 at ``setting`` steps per revolution."""
    default = DEFAULT_INTEGRATOR
    rtol, n = (setting, default.rk4_steps) if method == "dp54" else (default.rtol, int(setting))
    call = campar_call(cell, x0, revolutions, method, rtol, n)
    # one sample row per revolution start and per accepted step: steps = rows − revolutions
    rec = make_trace(MAX_SAMPLES, 100_000, 1)
    status, y, v = call(rec)
    if status != 0:
        raise RuntimeError(f"{cell.name}: {method} {setting} failed with status {status}")
    steps = int(rec.count[0]) - revolutions
    events = [(t, EVENT_NAMES[int(code)]) for t, _, _, code in rec.events[: rec.count[1]]]
    no_trace = make_trace(0, 0, 1)
    took = best_time(lambda: call(no_trace), min_seconds)
    err = event_error(events, ref.events)
    state_error = float(np.max(np.abs(np.array([y, v]) - ref.state)))
    return Run(cell.name, method, setting, steps, took, state_error, err, not math.isnan(err))


def scipy_run(cell, x0, revolutions, ref: Reference, rtol) -> Run:
    model = cell.scipy_model()
    took, (state, events, _) = timed(
        lambda: integrate(model, x0, revolutions, rtol=rtol, atol=rtol * 1e-2)
    )
    err = event_error(events, ref.events)
    state_error = float(np.max(np.abs(state - ref.state)))
    return Run(cell.name, "scipy", rtol, -1, took, state_error, err, not math.isnan(err))


def measure(
    cells=None,
    rtols=RTOLS,
    rk4_steps=RK4_STEPS,
    scipy_rtols=SCIPY_RTOLS,
    reference_rtol=1e-13,
    min_seconds=0.3,
):
    """All runs of the benchmark: (list of Run, {cell name: Reference})."""
    chosen = [(c, k) for c, k in CELLS if cells is None or c.name in cells]
    runs, refs = [], {}
    for cell, revolutions in chosen:
        x0 = start_state(cell)
        ref = refs[cell.name] = reference(cell, x0, revolutions, reference_rtol)
        for rtol in rtols:
            runs.append(
                campar_run(
                    cell, x0, revolutions, ref, method="dp54", setting=rtol, min_seconds=min_seconds
                )
            )
        for n in rk4_steps:
            runs.append(
                campar_run(
                    cell, x0, revolutions, ref, method="rk4", setting=n, min_seconds=min_seconds
                )
            )
        for rtol in scipy_rtols:
            runs.append(scipy_run(cell, x0, revolutions, ref, rtol))
    return runs, refs


class Fit(NamedTuple):
    cell: str
    what: str  # e.g. "DP5 state err vs rtol"
    slope: float
    points: int
    expected: str


def fits(runs: list[Run], refs: dict) -> list[Fit]:
    """Log-log slopes of the errors above the reference floor."""
    out = []
    for name, ref in refs.items():
        for quantity, floor in (("state", ref.state_floor), ("event", ref.event_floor)):
            limit = FLOOR_FACTOR * max(floor, 1e-15)
            for method, against, expected in (
                ("dp54", "rtol", "≈ 1"),
                ("dp54", "steps", "−5 (smooth)"),
                ("rk4", "steps", "−4 (smooth), −2.5 (impacts)"),
            ):
                sel = [r for r in runs if r.cell == name and r.method == method]
                err = np.array([getattr(r, f"{quantity}_error") for r in sel])
                x = np.array([r.setting if against == "rtol" else r.steps for r in sel], float)
                keep = err > limit
                if not keep.any():  # e.g. no events in a contact-only cell
                    continue
                label = f"{'DP5' if method == 'dp54' else 'RK4'} {quantity} err vs {against}"
                out.append(
                    Fit(name, label, loglog_slope(x[keep], err[keep]), int(keep.sum()), expected)
                )
    return out


def local_orders(runs: list[Run]) -> dict:
    """Observed order between successive runs of one method: −Δlog err / Δlog steps."""
    orders = {}
    for i in range(1, len(runs)):
        a, b = runs[i - 1], runs[i]
        if a.cell == b.cell and a.method == b.method != "scipy":
            orders[i] = -math.log(b.state_error / a.state_error) / math.log(b.steps / a.steps)
    return orders


def format_runs(runs: list[Run], refs: dict) -> str:
    orders = local_orders(runs)
    rows = []
    for i, r in enumerate(runs):
        setting = f"rtol {r.setting:.0e}" if r.method != "rk4" else f"{int(r.setting)}/rev"
        rows.append(
            [
                r.cell,
                r.method,
                setting,
                r.steps if r.steps >= 0 else "—",
                r.time.wall * 1e3,
                r.time.cpu * 1e3,
                r.state_error,
                r.event_error if r.events_match else "differ",
                orders.get(i, math.nan),
            ]
        )
    headers = [
        "cell",
        "method",
        "setting",
        "steps",
        "wall ms",
        "CPU ms",
        "state err",
        "event-time err",
        "local order",
    ]
    ref_rows = [
        [name, len(ref.events), ref.time.cpu, ref.state_floor, ref.event_floor]
        for name, ref in refs.items()
    ]
    ref_table = format_table(
        ["cell", "events", "reference CPU s", "reference err (state)", "(event time)"], ref_rows
    )
    return format_table(headers, rows) + "\n\nSciPy reference:\n" + ref_table


def format_fits(fit_list: list[Fit]) -> str:
    rows = [[f.cell, f.what, f.slope, f.points, f.expected] for f in fit_list]
    return format_table(["cell", "fit (log-log)", "slope", "points", "expected"], rows)


def plot(runs: list[Run], refs: dict, fit_list: list[Fit], path: str) -> None:
    from matplotlib.ticker import NullFormatter

    from ..views.plot.style import new_figure

    names = list(refs)
    slope = {(f.cell, f.what): f.slope for f in fit_list}
    fig = new_figure(4.2 * len(names), 7.5)
    fig.subplots(2, len(names), squeeze=False)
    axes = fig.axes
    styles = {
        "dp54": ("C0", "o-", "DP5(4)"),
        "rk4": ("C1", "s-", "RK4 fixed step"),
        "scipy": ("C2", "^", "SciPy DOP853"),
    }
    for j, name in enumerate(names):
        top, bottom = axes[j], axes[len(names) + j]
        for method, (color, marker, label) in styles.items():
            sel = [r for r in runs if r.cell == name and r.method == method]
            if not sel:
                continue
            err = [r.state_error for r in sel]
            top.loglog([r.time.cpu * 1e3 for r in sel], err, marker, color=color, label=label)
            if method != "scipy":
                fitted = slope.get((name, f"{label[:3]} state err vs steps"), math.nan)
                bottom.loglog(
                    [r.steps for r in sel],
                    err,
                    marker,
                    color=color,
                    label=f"{label}: fit {fitted:.2f}",
                )
        floor = FLOOR_FACTOR * refs[name].state_floor
        for ax in (top, bottom):
            ax.axhline(floor, color="0.75", lw=2, label="3× reference error")
            ax.grid(True, which="major", alpha=0.3)
        top.set_title(
            f"{name} ({next(c.describe() for c, _ in CELLS if c.name == name)})", fontsize=10
        )
        top.set_xlabel("CPU time per run [ms] (fastest of repeats)")
        bottom.set_xlabel("accepted steps")
        if j == 0:
            top.set_ylabel("error of (y, y') after k revolutions")
            bottom.set_ylabel("error of (y, y') after k revolutions")
            top.legend(fontsize=8)
        for order, ls in ((5, "--"), (4, "-."), (2.5, ":")):
            sel = [r for r in runs if r.cell == name and r.method != "scipy"]
            x0 = min(r.steps for r in sel)
            e0 = max(r.state_error for r in sel)
            xs = np.array([x0, x0 * 10 ** (8 / (order + 2))])
            bottom.loglog(
                xs, e0 * (xs / x0) ** -order, ls, color="0.3", lw=0.8, label=f"slope −{order}"
            )
        bottom.legend(fontsize=7)
        for ax in (top, bottom):  # after every loglog call, which resets the formatters
            ax.xaxis.set_minor_formatter(NullFormatter())
    fig.savefig(path, dpi=130)


def run(args) -> int:
    config = {
        "cells": args.cells,
        "rtols": args.rtols or RTOLS,
        "rk4_steps": args.rk4_steps or RK4_STEPS,
        "scipy_rtols": SCIPY_RTOLS if args.scipy_rtols is None else args.scipy_rtols,
        "min_seconds": args.min_seconds,
    }
    if args.quick:
        config.update({k: v for k, v in QUICK.items() if k != "cells" or not args.cells})
    print(machine_line())
    runs, refs = measure(reference_rtol=args.reference_rtol, **config)
    print(format_runs(runs, refs))
    print("\nObserved slopes (errors above 3× the reference's own error):")
    fit_list = fits(runs, refs)
    print(format_fits(fit_list))
    print(f"\nload average at the end: {machine_line().rsplit('load average ', 1)[1]}")
    if args.plot:
        plot(runs, refs, fit_list, args.plot)
        print(f"wrote {args.plot}")
    return 0
