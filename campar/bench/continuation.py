"""``campar bench continuation``: how fast and how exact the continuation is, against what.

Four measurements, each printed with its command line's settings and the machine load:

- **speed**: the 1-1 branch at μkn = 0.91 from ω = 6 down to 0.5 with steps chosen for
  about ``--points`` points, in one process, warm: its wall and CPU
  seconds, the integrations of the section map it took, and the time of one branch
  point against one brute-force map cell (a warm-started cell of the same branch's
  line, ``campar line``'s kernel, timed in the same run);
- **accuracy**: a PD point and a fold located by campar against SciPy's shooting of the
  augmented system with difference Jacobians (campar.bench.scipy_shooting), and a
  cycle's state and multipliers against SciPy's Newton: the differences;
- **hysteresis**: on a map swept both ways (default jobs/mu_kn_both.yaml), every edge
  where the down sweep leaves a periodic cycle inside a band where the two sweeps
  differ: is there a fold, PD or grazing point of that cycle's branch within one cell?
  The share of rows where every such edge is explained;
- **map**: the curves of a map store (``--store``, e.g. results/mu_kn.zarr after
  ``campar run jobs/mu_kn.yaml``) computed in this process: their number and time, and,
  type by type, the agreement of the map's edges with the curves both ways
  (views.map_curves.agreement).
"""

import math
import tempfile
import time
from pathlib import Path

import numpy as np

from ..continuation.branch import BranchSettings, continue_branch
from ..continuation.orbit import find_cycle
from ..continuation.section_map import SectionMap
from .common import format_table, machine_line, timed

MU_KN = 0.91
SPAN = (6.0, 0.5)


def speed(points: int) -> dict:
    smap = SectionMap()
    orbit = find_cycle(1, (0.6, -0.6), section_map=smap, omega=SPAN[0], mu_kn=MU_KN)
    settings = BranchSettings(
        step=0.005, max_step=(SPAN[0] - SPAN[1]) / points, max_points=10 * points
    )
    continue_branch(orbit, "omega", (0.9, 6.0), section_map=smap, settings=settings)  # warm
    shots0 = smap.shots
    took, branch = timed(
        lambda: continue_branch(
            orbit, "omega", (SPAN[1], SPAN[0]), section_map=smap, settings=settings
        )
    )
    from ..views.line import compute_line, line_spec

    spec = line_spec(SPAN[::-1], len(branch.values), mu_kn=MU_KN)
    compute_line(spec, transitions=False)  # warm
    cells, _ = timed(lambda: compute_line(spec, transitions=False))
    per_point = took.cpu / len(branch.values)
    per_cell = cells.cpu / len(branch.values)
    return {
        "points": len(branch.values),
        "wall": took.wall,
        "cpu": took.cpu,
        "shots": smap.shots - shots0,
        "per_point": per_point,
        "per_cell": per_cell,
        "special": [(sp.type, sp.value) for sp in branch.special],
    }


def accuracy() -> list[tuple[str, float]]:
    from ..views.continuation import continue_from_cell
    from . import scipy_shooting

    rows = []
    smap = SectionMap()
    one = find_cycle(1, (0.54, -0.72), section_map=smap, omega=3.54, mu_kn=MU_KN)
    x, m = scipy_shooting.fixed_point({"omega": 3.54, "mu_kn": MU_KN}, (0.54, -0.72), 1)
    rows.append(("unstable 1-cycle state, ω 3.54", float(np.abs(x - np.array(one.state)).max())))
    difference = np.abs(np.array(one.multipliers) - scipy_shooting.multipliers(m)).max()
    rows.append(("its multipliers", float(difference)))
    branch = continue_branch(
        find_cycle(1, (0.6, -0.6), section_map=smap, omega=4.0, mu_kn=MU_KN),
        "omega",
        (3.0, 4.0),
        direction=-1.0,
        section_map=smap,
    )
    pd = branch.special[0]
    value, _ = scipy_shooting.bifurcation_point(
        "PD", {"omega": pd.value, "mu_kn": MU_KN}, "omega", pd.state, 1
    )
    rows.append((f"PD point ω = {pd.value:.8f}", abs(value - pd.value)))
    three = continue_from_cell("omega", (6.0, 5.0), {"mu_kn": MU_KN}, section_map=smap)
    fold = [sp for sp in three.root.special if sp.type == "SN"][0]
    value, _ = scipy_shooting.bifurcation_point(
        "SN", {"omega": fold.value, "mu_kn": MU_KN}, "omega", fold.state, fold.n
    )
    rows.append((f"fold of the 3-2 cycle ω = {fold.value:.8f}", abs(value - fold.value)))
    return rows


def hysteresis(job_path: Path) -> dict:
    """Rows of a both-directions map whose down sweep's jumps off a cycle (inside a
    hysteresis band) each lie within one cell of a special point of that cycle's branch."""
    from ..sweep.job import load_job
    from ..sweep.runner import run_job
    from ..views.dataset import open as open_store

    job = load_job(job_path)
    with tempfile.TemporaryDirectory(prefix="campar-bench-continuation-") as tmp:
        store = Path(tmp) / "both.zarr"
        run_job(job, store)
        with open_store(store) as ds:
            label = np.asarray(ds["label"].sel(direction="down").values)
            kind = np.asarray(ds["kind"].sel(direction="down").values)
            n = np.asarray(ds["n"].sel(direction="down").values)
            state = np.asarray(ds["state"].sel(direction="down").values)
            band = np.asarray(ds["hysteresis"].values)
            omega = np.asarray(ds["omega"].values)
            second = np.asarray(ds[job.second].values)
    smap = SectionMap(job.model.model_dump(mode="json"))
    h = abs(omega[1] - omega[0])
    explained_rows, rows, edges, explained = 0, 0, 0, 0
    kinds_found: dict[str, int] = {}
    for i in range(label.shape[0]):
        jumps = [
            j
            for j in range(len(omega) - 1)
            if kind[i, j] == 0 and label[i, j] != label[i, j + 1] and (band[i, j] or band[i, j + 1])
        ]
        if not jumps:
            continue
        rows += 1
        ok = True
        for j in jumps:
            edges += 1
            parameters = {**job.fixed, job.second: float(second[i])}
            try:
                orbit = find_cycle(
                    int(n[i, j]), state[i, j], section_map=smap, omega=float(omega[j]), **parameters
                )
                branch = continue_branch(
                    orbit,
                    "omega",
                    (omega[j + 1] - h, omega[j] + h),
                    direction=-1.0,
                    section_map=smap,
                    settings=BranchSettings(step=h / 4, max_step=h / 4, max_points=80),
                )
                near = [sp for sp in branch.special if sp.type in ("SN", "PD", "G", "BP")]
            except Exception:  # noqa: BLE001 (a failed seed counts as unexplained)
                near = []
            if near:
                explained += 1
                kinds_found[near[0].type] = kinds_found.get(near[0].type, 0) + 1
            else:
                ok = False
        explained_rows += ok
    return {
        "rows": rows,
        "explained_rows": explained_rows,
        "edges": edges,
        "explained": explained,
        "kinds": kinds_found,
    }


def map_agreement(store: Path) -> dict:
    """The curves of a map store (``campar curves`` in this process, into a store beside
    a copy of it) and their agreement with its typed edges, type by type."""
    import shutil

    from ..views.boundaries import store_boundaries
    from ..views.dataset import open as open_store
    from ..views.map_curves import agreement, curves_beside, curves_store_path

    with tempfile.TemporaryDirectory(prefix="campar-bench-curves-") as tmp:
        copy = Path(tmp) / Path(store).name
        shutil.copytree(store, copy) if Path(store).is_dir() else shutil.copy(store, copy)
        began = time.perf_counter()
        curves = curves_beside(copy)
        seconds = time.perf_counter() - began
        boundaries = store_boundaries(copy)
        with open_store(curves_store_path(copy)) as ds:
            tasks = ds.sizes["task"]
        with open_store(copy) as ds:
            grid = {
                "omega": ds["omega"].values,
                "second": ds[boundaries.second_name].values,
                "kind": ds["kind"].values,
                "n": ds["n"].values,
            }
    shares = {t: agreement(boundaries, curves, grid, t) for t in ("PD", "SN", "G")}
    return {"seconds": seconds, "curves": len(curves), "tasks": tasks, "agreement": shares}


def run(args) -> int:
    print(machine_line())
    s = speed(args.points)
    print(
        format_table(
            ["branch", "points", "wall s", "CPU s", "shots", "ms/point", "ms/map cell", "ratio"],
            [
                [
                    f"1-1, μkn {MU_KN}, ω {SPAN[0]} → {SPAN[1]}",
                    s["points"],
                    f"{s['wall']:.2f}",
                    f"{s['cpu']:.2f}",
                    s["shots"],
                    f"{1e3 * s['per_point']:.2f}",
                    f"{1e3 * s['per_cell']:.3f}",
                    f"{s['per_point'] / s['per_cell']:.1f}",
                ]
            ],
        )
    )
    print("special points:", ", ".join(f"{t} {v:.8f}" for t, v in s["special"]) or "none")
    if not args.quick:
        print(
            format_table(
                ["against SciPy shooting", "|difference|"],
                [[name, f"{d:.2e}"] for name, d in accuracy()],
            )
        )
        h = hysteresis(Path(args.hysteresis_job))
        share = h["explained_rows"] / h["rows"] if h["rows"] else math.nan
        print(
            f"hysteresis ({args.hysteresis_job}): {h['explained_rows']} of {h['rows']} rows "
            f"({100 * share:.1f} %) have every jump off a cycle inside a band within one "
            f"cell of a special point of its branch; edges {h['explained']}/{h['edges']}; "
            f"types {h['kinds']}"
        )
    if args.store:
        m = map_agreement(Path(args.store))
        print(
            f"curves of {args.store}: {m['curves']} curves from {m['tasks']} tasks in "
            f"{m['seconds']:.1f} s (one process)"
        )
        print(
            format_table(
                [
                    "type",
                    "edges",
                    "edges within a cell of a curve",
                    "curve points judged",
                    "with an edge beside them",
                ],
                [
                    [
                        t,
                        a.counts[0],
                        f"{100 * a.edges_near:.1f} %",
                        a.counts[1],
                        f"{100 * a.length_near:.1f} %",
                    ]
                    for t, a in m["agreement"].items()
                ],
            )
        )
    return 0
