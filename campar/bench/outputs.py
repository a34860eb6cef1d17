"""``campar bench outputs``: does a labels-only map cost less than one with every output?

The same sub-plane of the paper's (ω, μcn) plane (jobs/mu_cn.yaml's ranges,
default 20 μcn × 40 ω values) is computed with ``run_tile`` tile by tile, with
outputs [label] and with every output (label, dc, eps, pn, sections,
multipliers, lyapunov), for both transients. Runs alternate (label, all,
all, all, label, …) so that both see the same machine load; the fastest of
each is kept, in CPU seconds of this process (wall seconds shown too), and
the spread of the ratios of each pair of runs is shown beside. The labels of
both must be identical: outputs may not change results.

Where to look when the ratio is ≈ 1 (campar/kernel.py): in converged mode
every transient revolution integrates the variational equations (state of 6
instead of 2), because the Newton jumps on the section map need the one-
revolution Jacobians whatever the outputs; in fixed mode they run only in the
read window, also for labels only. What a labels-only job saves is the
per-step statistics (duty cycle, ε extremes, Pn max) and, in fixed mode, the
Floquet/Lyapunov bookkeeping — small against the integration itself.
"""

import numpy as np

from ..sweep.job import DEFAULT_CLASSIFY, DEFAULT_TRANSIENT, OUTPUT_NAMES, Job
from ..sweep.plan import plan_tiles
from ..sweep.tile import run_tile
from .common import Timing, format_table, machine_line, timed

QUICK = {"rows": 2, "omegas": 6, "repeat": 1, "min_seconds": 0.0}
LABEL_ARRAYS = ("n", "p", "kind", "status")


def make_job(
    rows: int,
    omegas: int,
    transient: str,
    outputs,
    revolutions=DEFAULT_TRANSIENT.max_revolutions,
    window=DEFAULT_CLASSIFY.window_revolutions,
) -> Job:
    return Job.from_dict(
        {
            "name": "bench_outputs",
            "sweep": {
                "omega": {"from": 6.0, "to": 0.02, "points": omegas},
                "mu_cn": {"from": 0.99, "to": 0.50, "points": rows},
            },
            "transient": {"mode": transient, "max_revolutions": revolutions},
            "classify": {"window_revolutions": window},
            "outputs": list(outputs),
            "tiles": {"rows": 4},
        },
        source="campar bench outputs",
    )


def run_map(job: Job) -> tuple[Timing, dict]:
    """Time of every tile of the job, and the label arrays of the map."""

    def tiles():
        return [run_tile(job, tile) for tile in plan_tiles(job)]

    took, arrays = timed(tiles)
    return took, {name: np.concatenate([a[name] for a in arrays]) for name in LABEL_ARRAYS}


def measure(rows=20, omegas=40, repeat=4, min_seconds=2.0) -> list[dict]:
    """Labels-only against all outputs, per transient; each variant runs at least
    ``repeat`` times and until ``min_seconds`` of CPU time, alternating."""
    results = []
    for transient in ("converged", "fixed"):
        jobs = {
            "label": make_job(rows, omegas, transient, ["label"]),
            "all": make_job(rows, omegas, transient, OUTPUT_NAMES),
        }
        for job in jobs.values():  # load the compiled kernel before timing
            run_map(make_job(1, 2, transient, job.outputs))
        best = {key: Timing(np.inf, np.inf) for key in jobs}
        cpu = {key: [] for key in jobs}
        maps = {}
        runs = 0
        while runs < repeat or min(sum(v) for v in cpu.values()) < min_seconds:
            for key in list(jobs)[:: 1 if runs % 2 == 0 else -1]:  # ABBA: no order bias
                took, maps[key] = run_map(jobs[key])
                best[key] = Timing(min(best[key].wall, took.wall), min(best[key].cpu, took.cpu))
                cpu[key].append(took.cpu)
            runs += 1
        pairs = [b / a for a, b in zip(cpu["label"], cpu["all"], strict=True)]
        same = all(np.array_equal(maps["label"][n], maps["all"][n]) for n in LABEL_ARRAYS)
        results.append(
            {
                "transient": transient,
                "cells": rows * omegas,
                "label_s": best["label"].cpu,
                "all_s": best["all"].cpu,
                "label_wall": best["label"].wall,
                "all_wall": best["all"].wall,
                "ratio": best["all"].cpu / best["label"].cpu,
                "wall_ratio": best["all"].wall / best["label"].wall,
                "same_labels": same,
                "runs": runs,
                "pair_ratios": (min(pairs), max(pairs)),
            }
        )
    return results


def variational_cost(
    rows=20, omegas=40, revolutions=DEFAULT_TRANSIENT.max_revolutions
) -> tuple[float, float]:
    """CPU seconds of the fixed transient with every revolution plain (2 equations)
    and with every revolution variational (6): what converged mode pays for its
    Newton jumps, since it integrates the variational equations throughout."""
    plain = make_job(rows, omegas, "fixed", ["label"], revolutions=revolutions, window=2)
    variational = make_job(rows, omegas, "fixed", ["label"], revolutions=1, window=revolutions)
    return run_map(plain)[0].cpu, run_map(variational)[0].cpu


MEASURABLE = 1.05  # all/labels below this is within the noise of a shared machine


def verdict(result: dict) -> str:
    saving = 1.0 - 1.0 / result["ratio"]
    if result["ratio"] < MEASURABLE:
        reason = (
            "variational equations run in every revolution for the Newton jumps"
            if result["transient"] == "converged"
            else "only per-step statistics and bookkeeping are skipped"
        )
        return f"NOT measurably cheaper ({saving:+.0%}): {reason}"
    return f"labels only saves {saving:.0%}"


def run(args) -> int:
    config = {"rows": args.rows, "omegas": args.omegas, "repeat": args.repeat}
    if args.quick:
        config.update(QUICK)
    print(machine_line())
    results = measure(**config)
    plain, variational = variational_cost(config["rows"], config["omegas"])
    rows = [
        [
            r["transient"],
            r["cells"],
            r["label_s"],
            r["all_s"],
            r["cells"] / r["label_s"],
            r["cells"] / r["all_s"],
            r["ratio"],
            f"{r['pair_ratios'][0]:.3f}–{r['pair_ratios'][1]:.3f} ({r['runs']})",
            r["label_wall"],
            r["all_wall"],
            r["wall_ratio"],
            "yes" if r["same_labels"] else "NO",
            verdict(r),
        ]
        for r in results
    ]
    headers = [
        "transient",
        "cells",
        "labels CPU s",
        "all CPU s",
        "labels cells/s",
        "all cells/s",
        "all/labels",
        "run pairs (n)",
        "labels wall s",
        "all wall s",
        "wall ratio",
        "same labels",
        "verdict",
    ]
    print(format_table(headers, rows))
    print(
        f"\nvariational equations (6 instead of 2): {DEFAULT_TRANSIENT.max_revolutions} fixed "
        f"revolutions per cell, all plain "
        f"{plain:.2f} CPU s, all variational {variational:.2f} CPU s (× {variational / plain:.2f})"
        "; converged mode integrates them in every revolution, for labels only too (transient."
        "transient_converged), fixed mode in its read window only (transient.transient_fixed)"
    )
    print(f"load average at the end: {machine_line().rsplit('load average ', 1)[1]}")
    return 0
