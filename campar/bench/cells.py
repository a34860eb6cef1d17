"""``campar bench cells``: one cell's cost against ω, cold and warm; compile and start-up time.

- Per ω in {0.02, 0.1, 0.5, 1, 2, 4, 6} (μcn plane values otherwise): the time
  and revolutions of ``simulate_point`` from rest (cold) and from the steady
  state of the neighbouring cell at ω + Δω of a 400-point row (warm, as a
  continuation hands it over). Times are the fastest of repeated calls and
  include the Python wrapper (the floor the ω = 6 warm 1-0 cell shows).
- Along whole warm-started rows (400 ω values from 6 down to 0.02, the tile
  runner with its extrapolated warm start, as ``campar run`` computes them):
  mean revolutions and milliseconds per cell, for several μcn.
- numba: the first call in a fresh process with an empty cache (compile) and
  with the warm on-disk cache (load), and ``campar point`` wall time.
"""

import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from ..sweep.job import PAPER_VALUES, Job
from ..sweep.plan import plan_tiles
from ..sweep.tile import run_tile
from ..views.point import simulate_point
from .common import best_time, format_table, machine_line

OMEGAS = (0.02, 0.1, 0.5, 1.0, 2.0, 4.0, 6.0)
ROW_MU_CN = (0.95, 0.8, 0.65, 0.5)
ROW_POINTS = 400
DELTA_OMEGA = (6.0 - 0.02) / (ROW_POINTS - 1)
QUICK = {"omegas": (0.5, 3.0), "rows": (0.8,), "row_points": 20, "rtol": 1e-9, "startup": False}


def cell_costs(omegas, rtol: float, min_seconds: float) -> list[list]:
    """Rows (ω, label, cold ms, cold revs, warm ms, warm revs) of the table."""
    rows = []
    for omega in omegas:
        cold = simulate_point(omega, rtol=rtol)
        neighbour = simulate_point(omega + DELTA_OMEGA, rtol=rtol)
        y0, v0 = neighbour.state
        warm = simulate_point(omega, rtol=rtol, y0=y0, v0=v0)
        t_cold = best_time(lambda o=omega: simulate_point(o, rtol=rtol), min_seconds)
        start = {"y0": y0, "v0": v0}
        t_warm = best_time(lambda o=omega, s=start: simulate_point(o, rtol=rtol, **s), min_seconds)
        rows.append(
            [
                omega,
                warm.label,
                1e3 * t_cold.cpu,
                cold.revolutions,
                1e3 * t_warm.cpu,
                warm.revolutions,
                warm.steps,
            ]
        )
    return rows


def row_job(mu_cn: float, points: int, rtol: float) -> Job:
    return Job.from_dict(
        {
            "name": "bench_cells_row",
            "sweep": {
                "omega": {"from": 6.0, "to": 0.02, "points": points},
                "mu_cn": {"from": mu_cn, "to": mu_cn, "points": 1},
            },
            "integrator": {"rtol": rtol},
            "outputs": ["label", "dc", "eps", "pn"],
        },
        source="campar bench cells",
    )


def row_costs(mu_cns, points: int, rtol: float) -> list[list]:
    """Rows (μcn, ms per cell, revolutions per cell, periodic %) along warm-started ω rows."""
    rows = []
    for mu_cn in mu_cns:
        job = row_job(mu_cn, points, rtol)
        (tile,) = plan_tiles(job)
        run_tile(job, tile)  # compiled and warm
        start = time.process_time()
        arrays = run_tile(job, tile)
        seconds = time.process_time() - start
        periodic = float(np.mean(arrays["n"] > 0))
        rows.append(
            [mu_cn, 1e3 * seconds / points, float(arrays["revolutions"].mean()), 100 * periodic]
        )
    return rows


def fresh_process_seconds(code: str, env: dict) -> float:
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], check=True, env=env, capture_output=True)
    return time.perf_counter() - start


def startup_costs() -> list[list]:
    """Wall seconds of a first cell in a new process: empty cache, warm cache; `campar point`."""
    code = "from campar import simulate_point; simulate_point(3.0)"
    rows = []
    with tempfile.TemporaryDirectory(prefix="campar-numba-") as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        rows.append(["first cell, empty numba cache (compile)", fresh_process_seconds(code, env)])
        rows.append(["first cell, warm cache (load)", fresh_process_seconds(code, env)])
    campar = os.path.join(os.path.dirname(sys.executable), "campar")
    fresh_process_seconds(code, dict(os.environ))  # the default cache is warm
    start = time.perf_counter()
    subprocess.run([campar, "point", "--omega", "3"], check=True, capture_output=True)
    rows.append(["campar point --omega 3, warm cache", time.perf_counter() - start])
    return rows


def run(args) -> int:
    settings = {
        "omegas": OMEGAS,
        "rows": ROW_MU_CN,
        "row_points": ROW_POINTS,
        "rtol": args.rtol,
        "startup": True,
    }
    if args.quick:
        settings.update(QUICK)
    print(machine_line())
    rtol = settings["rtol"]
    base = ", ".join(f"{name} {value:g}" for name, value in PAPER_VALUES.items())
    print(
        f"\nOne cell ({base}) at rtol {rtol:g}; CPU ms, fastest run;"
        f" warm = from the steady state at ω + {DELTA_OMEGA:.4f}\n"
    )
    cells = cell_costs(settings["omegas"], rtol, args.min_seconds)
    headers = ["ω", "label", "cold ms", "cold revs", "warm ms", "warm revs", "warm steps"]
    print(format_table(headers, cells))
    print(f"\nWarm-started rows of {settings['row_points']} ω values, 6 → 0.02 (tile runner)\n")
    rows = row_costs(settings["rows"], settings["row_points"], rtol)
    print(format_table(["μcn", "ms/cell", "rev/cell", "periodic %"], rows))
    mean = np.mean([r[2] for r in rows])
    print(
        f"\nmean over the rows: {np.mean([r[1] for r in rows]):.3f} ms and {mean:.2f} "
        "revolutions per cell"
    )
    if settings["startup"]:
        print()
        print(format_table(["start-up", "wall s"], startup_costs()))
    return 0
