"""`campar bench map`: how well a map agrees with a reference map, against run time.

For each of the paper's three planes a sub-plane (default 100 × 100, the same
ranges as the full plane, continuation along ω as always) is computed by
every candidate setting (transient policy × rtol) and compared cell by cell
with a reference: the paper's recipe at high accuracy (a fixed transient of
500 revolutions, then a 64-revolution read window, rtol 1e-11), computed once
with `campar run` and kept in a store.

A 500-revolution reference is itself wrong where a cell converges slowly (a
multiplier near −1 passes a 2n-repeat test before it has converged, and one
near the unit circle looks quasi-periodic). So every disagreeing cell is
adjudicated: the reference's own recipe is run again from the reference's
warm start (its state at the previous cell) with a long transient, and the
verdict of that long run is recorded beside the raw agreement. Both numbers
are reported; nothing is dropped.
"""

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.codes import Flag, Kind, cell_label
from ..sweep.job import Job, load_job
from ..sweep.plan import plan_tiles
from ..sweep.tile import run_tile

PLANES = ("mu_cn", "mu_kn", "omega_f0")
REFERENCE = {
    "integrator": {"method": "dp54", "rtol": 1e-11, "atol": 1e-13, "max_steps": 50_000_000},
    "transient": {"mode": "fixed", "max_revolutions": 500, "extrapolate": 1},
    "classify": {"window_revolutions": 64},
}
ADJUDICATION_REVOLUTIONS = 4000
COMPARED_OUTPUTS = ["label", "dc"]


def plane_job(plane: str, jobs_dir: Path = Path("jobs")) -> Job:
    return load_job(jobs_dir / f"{plane}.yaml")


def subplane_job(job: Job, size: int, name: str, overrides: dict, outputs=None) -> Job:
    """The plane of ``job`` at size × size points with settings overridden."""
    data = job.to_dict()
    data["name"] = name
    for axis in data["sweep"].values():
        axis["points"] = size
    for section, values in overrides.items():
        if isinstance(values, dict):
            data[section] = {**data.get(section, {}), **values}
        else:
            data[section] = values
    data["outputs"] = outputs or COMPARED_OUTPUTS
    data["tiles"] = {"rows": 1}
    data["store"] = None
    return Job.from_dict(data, source=name)


def reference_job(job: Job, size: int) -> Job:
    return subplane_job(
        job,
        size,
        f"{job.name}_{size}_reference",
        REFERENCE,
        outputs=["label", "dc", "eps", "pn", "lyapunov"],
    )


def compute(job: Job) -> tuple[dict[str, np.ndarray], float]:
    """Every tile of a job in this process; (arrays over (second, omega), seconds)."""
    start = time.perf_counter()
    parts = [run_tile(job, tile) for tile in plan_tiles(job)]
    seconds = time.perf_counter() - start
    return {name: np.concatenate([p[name] for p in parts]) for name in parts[0]}, seconds


def label_codes(arrays: dict[str, np.ndarray]) -> np.ndarray:
    """One integer per cell that is equal exactly when the n-p labels (or kinds) are."""
    periodic = arrays["kind"] == Kind.PERIODIC
    return np.where(periodic, arrays["n"] * 100_000 + arrays["p"], -1 - arrays["kind"])


def label_of(arrays, i, j) -> str:
    return cell_label(int(arrays["kind"][i, j]), int(arrays["n"][i, j]), int(arrays["p"][i, j]), 99)


@dataclass
class Comparison:
    cells: int
    agree: float  # fraction of cells with the reference's label
    adjudicated: float  # … with the reference's label or the long run's verdict
    dc_error_mean: float  # |ΔDC| over periodic cells that agree
    dc_error_max: float
    disagreements: list = field(default_factory=list)  # (i, j, ref, cand, verdict, flags)

    def flagged(self, flag: Flag) -> int:
        """Disagreeing cells carrying ``flag`` (slow: a multiplier near the unit
        circle; grazing: p sensitive to a dip of ε near 0)."""
        return sum(1 for d in self.disagreements if d[5] & flag)


def compare(cand, ref, verdicts: dict | None = None) -> Comparison:
    ours, theirs = label_codes(cand), label_codes(ref)
    agree = ours == theirs
    verdicts = verdicts or {}
    rescued = 0
    rows = []
    for i, j in np.argwhere(~agree):
        verdict = verdicts.get(f"{i},{j}")
        mine = label_of(cand, i, j)
        if verdict == mine:
            rescued += 1
        rows.append((int(i), int(j), label_of(ref, i, j), mine, verdict, int(cand["flags"][i, j])))
    both = agree & (ref["kind"] == Kind.PERIODIC)
    dc_err = np.abs(cand["dc"] - ref["dc"])[both]
    return Comparison(
        cells=agree.size,
        agree=float(agree.mean()),
        adjudicated=float((agree.sum() + rescued) / agree.size),
        dc_error_mean=float(dc_err.mean()) if dc_err.size else float("nan"),
        dc_error_max=float(dc_err.max()) if dc_err.size else float("nan"),
        disagreements=rows,
    )


def long_run_job(ref_job: Job, ref: dict, i: int, j: int, outputs: list[str]) -> Job:
    """Cell (i, j) by the reference's own settings with a transient of
    ADJUDICATION_REVOLUTIONS, from the reference's final state at the previous
    cell of its chain (the state the reference itself started from)."""
    data = ref_job.to_dict()
    data["name"] = f"{ref_job.name}_adjudication"
    data["sweep"]["omega"] = {
        "from": float(ref_job.omega[j]),
        "to": float(ref_job.omega[j]),
        "points": 1,
    }
    value = float(ref_job.second_values[i])
    data["sweep"][ref_job.second] = {"from": value, "to": value, "points": 1}
    if j > 0 and np.all(np.isfinite(ref["state"][i, j - 1])):
        y, v = (float(x) for x in ref["state"][i, j - 1])
        data["initial"] = {"y": y, "v": v}  # else the chain restarted there too
    data["transient"]["max_revolutions"] = ADJUDICATION_REVOLUTIONS
    data["outputs"] = outputs
    return Job.from_dict(data)


def adjudicate(ref_job: Job, ref: dict, cells, cache: Path) -> dict[str, str]:
    """Long-run verdicts (long_run_job) of cells; cached in ``cache``."""
    verdicts = json.loads(cache.read_text()) if cache.exists() else {}
    for i, j in cells:
        key = f"{i},{j}"
        if key in verdicts:
            continue
        cell, _ = compute(long_run_job(ref_job, ref, i, j, ["label"]))
        verdicts[key] = label_of(cell, 0, 0)
        cache.write_text(json.dumps(verdicts, indent=0, sort_keys=True))
    return verdicts


def period_of_label(label: str | None) -> int:
    """n of an n-p label (0 for QP, chaos, unconverged or no label)."""
    return int(label.split("-")[0]) if label and label[0].isdigit() else 0


def audit_doubled_periods(
    candidate: Job, ref_job: Job, ref: dict, comparison: Comparison, out
) -> int:
    """Audit the disagreeing cells whose long run found twice campar's period.

    The long run reads its period with the plain repeat test, which takes a
    slowly converging n-cycle (multiplier near −1) for a 2n-cycle. For each
    such cell the long run is repeated with its multipliers and section points,
    and the cell is run again from the long run's final state with the
    candidate's own settings. Returns how many cells are such a misread: the
    restart gives campar's label and the long run's P^2n has a multiplier
    above 0.99 (the square of one near −1).
    """
    misread = 0
    for i, j, _, mine, verdict, _ in comparison.disagreements:
        n = period_of_label(mine)
        if n == 0 or period_of_label(verdict) != 2 * n:
            continue
        long_job = long_run_job(ref_job, ref, i, j, ["label", "multipliers", "sections"])
        long, _ = compute(long_job)
        y, v = (float(x) for x in long["state"][0, 0])
        data = long_job.to_dict()
        data.update(
            transient=candidate.transient.model_dump(),
            initial={"y": y, "v": v},
            integrator=candidate.integrator.model_dump(),
            classify=candidate.classify.model_dump(),
        )
        again, _ = compute(Job.from_dict(data))
        lead = float(np.hypot(*long["multipliers"][0, 0, 0]))
        points = long["sections"][0, 0]
        spread = float(np.abs(points[0] - points[1]).max())
        same = label_of(again, 0, 0) == mine
        misread += same and lead > 0.99
        restart_lead = float(np.hypot(*again["multipliers"][0, 0, 0]))
        print(
            f"  cell ({i}, {j}): campar {mine}; long run {verdict}, multiplier {lead:.4f}, "
            f"its two points {spread:.1e} apart; from its end campar's test gives "
            f"{label_of(again, 0, 0)} in {int(again['revolutions'][0, 0])} revolutions "
            f"(|multiplier| {restart_lead:.4f})",
            file=out,
            flush=True,
        )
    return misread


# -- the benchmark ---------------------------------------------------------------------------


def integration(method: str, rtol: float, chaos_after: int) -> dict:
    """Overrides of a candidate that states its integrator and chaotic verdict in full."""
    return {
        "integrator": {"method": method, "rtol": rtol},
        "transient": {"chaos_after": chaos_after},
    }


CANDIDATES = {
    # name: job overrides; "default" is the job file's own settings
    "default": {},
    "rtol 1e-6": {"integrator": {"rtol": 1e-6}},
    "rtol 1e-7": {"integrator": {"rtol": 1e-7}},
    "rtol 1e-9": {"integrator": {"rtol": 1e-9}},
    "rtol 1e-10": {"integrator": {"rtol": 1e-10}},
    # the defaults before DOP853 (benchmarks/RESULTS.md), and the steps to the new
    # ones (integrator.method, integrator.rtol and transient.chaos_after, all three stated)
    "previous default": integration("dp54", 1e-8, 64),
    **{
        f"{method} rtol {rtol:g} chaos after {after}".replace("e-0", "e-"): integration(
            method, rtol, after
        )
        for method, rtol, after in [
            ("dp54", 1e-8, 96),
            ("dop853", 1e-9, 64),
            ("dop853", 1e-8, 64),
            ("dop853", 1e-7, 64),
            ("dop853", 1e-8, 96),
            ("dop853", 3e-8, 96),
            ("dop853", 1e-7, 80),
            ("dop853", 1e-8, 128),
        ]
    },
    "no Newton": {"transient": {"newton": False}},
    "QP at 150 no agree jumps": {  # the defaults before jumps on agreeing estimates
        "transient": {"jump_agree": 0.0, "quasiperiodic_after": 150}
    },
    "no agree jumps": {"transient": {"jump_agree": 0.0}},
    "jump agree 0.03": {"transient": {"jump_agree": 0.03}},
    "jump agree 0.3": {"transient": {"jump_agree": 0.3}},
    "QP after 150": {"transient": {"quasiperiodic_after": 150}},
    "QP after 250": {"transient": {"quasiperiodic_after": 250}},
    "no early verdicts": {"transient": {"chaos_after": 0}},
    "chaos after 100": {"transient": {"chaos_after": 100}},
    "chaos after 150": {"transient": {"chaos_after": 150}},
    "chaos after 48 window 48": {
        "transient": {"chaos_after": 48},
        "classify": {"window_revolutions": 48},
    },
    "chaos lyapunov 0.05": {"transient": {"chaos_lyapunov": 0.05}},
    "conv_tol 1e-6": {"transient": {"conv_tol": 1e-6}},
    "linear warm start": {"transient": {"extrapolate": 1}},
    "no extrapolation": {"transient": {"extrapolate": 0}},
    "paper recipe 500": {"transient": {"mode": "fixed", "max_revolutions": 500}},
}


def reference_arrays(ref: Job, directory: Path, ranks: int) -> dict[str, np.ndarray]:
    """The reference map (reference_job): read its store, computing it first if needed."""
    from ..sweep.store import read_store

    path = directory / f"{ref.name}.zarr"
    if not _complete(path):
        run_reference(ref, path, ranks)
    with read_store(path) as store:
        return {name: store.read(name) for name in store.names}


def _complete(path: Path) -> bool:
    from ..sweep.store import read_store

    if not path.exists():
        return False
    with read_store(path) as store:
        return bool(store.done.all())


def run_reference(job: Job, path: Path, ranks: int) -> None:
    """Compute a reference store with `campar run`, under mpirun when ranks > 1."""
    import subprocess
    import sys

    import yaml

    path.parent.mkdir(parents=True, exist_ok=True)
    job_file = path.with_suffix(".yaml")
    job_file.write_text(yaml.safe_dump(job.to_dict(), sort_keys=False))
    command = [sys.executable, "-m", "campar.cli", "run", str(job_file), "--store", str(path)]
    if ranks > 1:
        mpirun = Path(sys.executable).parent / "mpirun"
        command = [str(mpirun), "-n", str(ranks), *command]
    subprocess.run(command, check=True)


def bench_map(
    planes,
    size,
    candidates,
    directory: Path,
    *,
    ranks: int,
    long_runs: bool,
    out,
    audit: bool = False,
):
    """Run every candidate on every plane; print one table row per (plane, candidate),
    and with ``audit`` the audit of its doubled-period cells (audit_doubled_periods)."""
    results = {}
    header = (
        f"{'plane':9} {'candidate':26} {'time s':>7} {'rev/cell':>8} {'agree %':>8} "
        f"{'adjud. %':>8} {'disagree':>8} {'slow':>5} {'graze':>5} {'|ΔDC| mean':>10} "
        f"{'|ΔDC| max':>9}"
    )
    print(header, file=out)
    for plane in planes:
        base = plane_job(plane)
        ref_job = reference_job(base, size)
        ref = reference_arrays(ref_job, directory, ranks)
        for name in candidates:
            job = subplane_job(base, size, f"{plane}_{size}_candidate", CANDIDATES[name])
            cand, seconds = compute(job)
            verdicts = {}
            if long_runs:
                first = compare(cand, ref)
                cells = [(i, j) for i, j, *_ in first.disagreements]
                cache = directory / f"{base.name}_{size}_verdicts.json"
                verdicts = adjudicate(ref_job, ref, cells, cache)
            c = compare(cand, ref, verdicts)
            results[(plane, name)] = (c, seconds, float(cand["revolutions"].mean()))
            print(
                f"{plane:9} {name:26} {seconds:7.1f} {cand['revolutions'].mean():8.2f} "
                f"{100 * c.agree:8.2f} {100 * c.adjudicated:8.2f} {len(c.disagreements):8d} "
                f"{c.flagged(Flag.SLOW):5d} {c.flagged(Flag.GRAZING):5d} "
                f"{c.dc_error_mean:10.1e} {c.dc_error_max:9.1e}",
                file=out,
                flush=True,
            )
            if audit and long_runs:
                misread = audit_doubled_periods(job, ref_job, ref, c, out)
                right = c.adjudicated * c.cells + misread
                print(
                    f"  audit: {misread} long-run verdicts are slow cycles of campar's period "
                    f"read as twice it; adjudicated with them {100 * right / c.cells:.2f} %",
                    file=out,
                    flush=True,
                )
    return results


QUICK = {"planes": ["mu_cn"], "size": 6, "candidates": ["default", "rtol 1e-6"], "ranks": 1}


def run(args) -> int:
    import sys
    import tempfile

    from .common import machine_line

    if args.quick:
        for key, value in QUICK.items():
            setattr(args, key, value)
    candidates = args.candidates or list(CANDIDATES)
    unknown = [c for c in candidates if c not in CANDIDATES]
    if unknown:
        print(f"unknown candidate {unknown[0]!r}; known: {', '.join(CANDIDATES)}", file=sys.stderr)
        return 2
    print(machine_line())
    with tempfile.TemporaryDirectory(prefix="campar-bench-map-") as tmp:
        directory = Path(tmp) if args.quick else Path(args.references)
        results = bench_map(
            args.planes,
            args.size,
            candidates,
            directory,
            ranks=args.ranks,
            long_runs=not args.no_adjudication,
            out=sys.stdout,
            audit=args.audit,
        )
    if args.list:
        for (plane, name), (c, _, _) in results.items():
            for i, j, ref, mine, verdict, flags in c.disagreements:
                print(
                    f"{plane} {name}: cell ({i}, {j}) reference {ref}, campar {mine}, "
                    f"long run {verdict}, flags {flags}"
                )
    return 0
