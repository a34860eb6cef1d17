"""One map cell computed again, and the worker process that computes it within a time limit.

``cell_at(path, row, col)`` is the explorer's one way to a cell's motion: the store's job
at that cell, started from the cell's stored final state (a point of its attractor), as
``campar point`` simulates a cell — the same model, settings and label — with the
multipliers and the steady orbit traced densely. The other actions of the cell panel
(its attractors from K starts, its n-cycle by shooting) take the same cell's parameters.

Each is a plain function of plain arguments returning JSON-ready data (``ACTIONS``), run
by the server's worker process (``campar.explore.worker``).
"""

import math

import numpy as np

from ..errors import CamparError

TRACE_POINTS = 4000  # samples of an orbit sent to the page (every k-th of the trace)


def one_cell_job(path, row: int, col: int, layer: int = 0):
    """The store's job reduced to its cell (row, col) started from the stored final state:
    (job, stored cell arrays). StoreError when the cell has no verified stored result."""
    from ..sweep.job import Job
    from .source import stored_cell

    job, arrays = stored_cell(path, row, col, layer)
    y, v = (float(a) for a in arrays["state"])
    if not (math.isfinite(y) and math.isfinite(v)):
        raise CamparError(f"cell ({row}, {col}) failed in the map: no final state to start from")
    data = job.to_dict()
    x, s = float(job.first_values[col]), float(job.second_values[row])
    data.update(
        name=f"{job.name}-cell",
        sweep={
            job.first: {"from": x, "to": x, "points": 1},
            job.second: {"from": s, "to": s, "points": 1},
        },
        initial={"y": y, "v": v},
        outputs=sorted({*job.outputs, "label", "dc", "eps", "pn", "sections", "multipliers"}),
        tiles={"rows": 1},
        store=None,
    )
    data["chains"] = {**data["chains"], "direction": "down", "start": "rest"}
    for key in ("attractors", "curves"):
        data.pop(key, None)
    return Job.from_dict(data, source=f"cell ({row}, {col}) of {path}"), arrays


def cell_at(path, row: int, col: int, layer: int = 0):
    """The PointResult (with its dense trace) of map cell (row, col) of the store ``path``."""
    from ..sweep.plan import Tile
    from ..sweep.tile import compile_kernel, run_tile
    from ..views.point import MAX_TRACE_REVOLUTIONS, PointResult, point_result, trace_steady

    job, _ = one_cell_job(path, row, col, layer)
    compile_kernel(job, trace=True)
    cell = {name: arr[0, 0] for name, arr in run_tile(job, Tile(0, 0, 1)).items()}
    result = point_result(job, cell)
    if result.kind != "failed":
        n_revs = result.n or min(job.classify.window_revolutions, MAX_TRACE_REVOLUTIONS)
        orbit = trace_steady(job, result.parameters, result.state, n_revs, result.steps)
        if orbit is not None:
            result = PointResult(**{**result.__dict__, "trace": orbit})
    return result


def cell_report(path, row: int, col: int, layer: int = 0) -> dict:
    """What the page's cell panel shows: ``cell_at``'s numbers and its orbit, JSON-ready."""
    result = cell_at(path, row, col, layer)
    data = result.to_dict()
    trace = result.trace
    if trace is not None:
        k = max(1, len(trace.t) // TRACE_POINTS)
        data["trace"] = {
            name: _finite(getattr(trace, name)[::k]) for name in ("t", "y", "v", "yc", "eps", "pn")
        }
        data["trace"]["period"] = trace.period
        data["trace"]["events"] = {
            name: _finite(trace.events_named(name)) for name in ("impact", "detachment")
        }
    data["cell"] = {"row": row, "col": col, "layer": layer}
    return data


def attractors_report(path, row: int, col: int, count: int) -> dict:
    """The cell's attractors from ``count`` starts (``campar point --attractors``)."""
    from ..views.attractors import find_attractors

    job, _ = one_cell_job(path, row, col)
    census = find_attractors(job.omega[0], count=count, **_point_settings(job))
    return census.to_dict()


def cycle_report(path, row: int, col: int, n: int) -> dict:
    """The cell's n-cycle by shooting from its stored state, stable or not."""
    from ..continuation.orbit import find_cycle

    job, arrays = one_cell_job(path, row, col)
    settings = _point_settings(job)
    model = {k: settings.pop(k) for k in ("tensile", "duty_cycle", "cam_velocity")}
    params = {k: settings[k] for k in ("f0", "mu_kn", "mu_cn", "zeta")}
    guess = tuple(float(a) for a in arrays["state"])
    return find_cycle(n, guess, model=model, omega=float(job.omega[0]), **params).to_dict()


def line_report(path, row: int) -> dict:
    """The bifurcation diagram of map row ``row``: its chain along the first axis run
    again with every σn point kept (as ``campar line`` runs one), started as the map
    started the row (from the job's start, or with ``chains.start: continue`` from the
    stored final state of the row before's first cell); the label of every cell."""
    from ..core.codes import cell_label
    from ..sweep.job import Job
    from ..sweep.plan import Tile
    from ..sweep.tile import compile_kernel, run_tile
    from ..views.line import DEFAULT_SECTIONS
    from .source import stored_cell

    job, _ = stored_cell(path, row, 0)
    data = job.to_dict()
    start = data["initial"]
    if job.chains.start == "continue" and row > 0:
        _, before = stored_cell(path, row - 1, 0)
        start = {"y": float(before["state"][0]), "v": float(before["state"][1])}
    value = float(job.second_values[row])
    data.update(
        name=f"{job.name}-row",
        sweep={
            job.first: data["sweep"][job.first],
            job.second: {"from": value, "to": value, "points": 1},
        },
        initial=start,
        outputs=sorted({*job.outputs, "label", "sections"}),
        classify={**data["classify"], "sections": job.classify.sections or DEFAULT_SECTIONS},
        tiles={"rows": 1},
        store=None,
    )
    data["chains"] = {**data["chains"], "direction": "down", "start": "rest"}
    for key in ("attractors", "curves"):
        data.pop(key, None)
    line = Job.from_dict(data, source=f"row {row} of {path}")
    compile_kernel(line)
    cells = {name: values[0] for name, values in run_tile(line, Tile(0, 0, 1)).items()}
    chatter = line.classify.chatter_p
    labels = [
        cell_label(int(k), int(n), int(p), chatter) if k >= 0 else ""
        for k, n, p in zip(cells["kind"], cells["n"], cells["p"], strict=True)
    ]
    x = line.first_values
    points = [
        [float(x[i]), float(y)]
        for i in range(len(x))
        for y in cells["sections"][i, : int(cells["n"][i]) or None, 0]
        if math.isfinite(y)
    ]
    changes = [
        {"at": float(0.5 * (x[i] + x[i + 1])), "from": labels[i], "to": labels[i + 1]}
        for i in range(len(x) - 1)
        if labels[i] != labels[i + 1]
    ]
    return {
        "row": row,
        job.second: value,
        "x": job.first,
        "points": points,
        "labels": labels,
        "first": x.tolist(),
        "changes": changes,
    }


def branch_report(path, row: int, col: int) -> dict:
    """The branches through the cell's cycle along the map's first axis, both ways to the
    map's ends (``campar continue``), with one level of period doubling followed: each
    branch's σn points y with their stability, and its special points (PD, SN, NS, G)."""
    from ..views.continuation import continue_from_cell

    job, arrays = one_cell_job(path, row, col)
    if int(arrays["kind"]) != 0 or int(arrays["n"]) < 1:
        raise CamparError(f"cell ({row}, {col}) is not periodic: no cycle to continue")
    settings = _point_settings(job)
    model = {k: settings.pop(k) for k in ("tensile", "duty_cycle", "cam_velocity")}
    from ..sweep.store import read_store

    with read_store(path) as reader:  # the map's own range along its first axis
        axis = reader.job.sweep[job.first]
    here = float(job.first_values[0])
    ends = [float(axis.start), float(axis.stop)]
    branches, special = [], []
    y0, v0 = (float(a) for a in arrays["state"])
    for end in sorted(set(ends)):
        if end == here:
            continue
        result = continue_from_cell(
            job.first,
            (here, end),
            settings,
            y0=y0,
            v0=v0,
            cycle=int(arrays["n"]),
            switch=1,
            model=model,
        )
        for branch in result.root.walk():
            points = [
                [float(x), float(y), bool(stable)]
                for x, sec, stable in zip(
                    branch.values, branch.sections, branch.stable, strict=True
                )
                for y in sec[:, 0]
                if math.isfinite(y)
            ]
            branches.append({"n": branch.n, "points": points})
        special += [
            {"type": sp.type, "value": float(sp.value), "y": float(sp.state[0]), "n": b.n}
            for b, sp in result.special_points()
        ]
    return {"branches": branches, "special": special, "parameter": job.first}


def _point_settings(job) -> dict:
    from ..views.point import point_parameters

    par = point_parameters(job)
    par.pop("omega")
    return par


def _finite(a) -> list:
    a = np.asarray(a, float)
    return np.where(np.isfinite(a), a, None).tolist()


MAX_SEGMENTS = 50_000  # typed edges sent to the page


def edges_report(path, box) -> dict:
    """The typed bifurcation edges of the map's cells in ``box`` = (x0, x1, y0, y1)
    (``campar plot --bifurcations``, ``store_boundaries``), with their types' colours."""
    from ..views.boundaries import store_boundaries
    from ..views.plot.curves import CURVE_STYLES

    x0, x1, y0, y1 = box
    found = store_boundaries(path, omega=(x0, x1), second=(y0, y1))
    drawn = [s for s in found.segments if s.type in CURVE_STYLES]
    counts = {}
    for segment in found.segments:
        counts[segment.type] = counts.get(segment.type, 0) + 1
    return {
        "segments": [[*map(float, s.edge), s.type] for s in drawn[:MAX_SEGMENTS]],
        "counts": counts,
        "styles": {k: {"text": v[0], "colour": v[1]} for k, v in CURVE_STYLES.items()},
        "multipliers": bool(found.multipliers),
    }


def curves_report(path) -> dict:
    """The map's continued bifurcation curves (``campar curves``, ``MAP-curves.zarr``
    beside it), each a polyline in the map's plane with its type and period."""
    from ..views.map_curves import read_curves
    from ..views.plot.curves import CURVE_STYLES

    curves = read_curves(path)
    return {
        "curves": [{"type": c.type, "n": int(c.n), "points": _finite(c.values)} for c in curves],
        "styles": {k: {"text": v[0], "colour": v[1]} for k, v in CURVE_STYLES.items()},
    }


def hysteresis_report(path) -> dict:
    """Where the two sweep directions of a ``both`` store end on different cycles
    (``campar.open``'s ``hysteresis``): the cells (row, column)."""
    from ..views.dataset import open as open_store

    with open_store(path) as ds:
        rows, cols = np.nonzero(ds["hysteresis"].values)
    return {"cells": np.stack([rows, cols], axis=1).tolist()}


def warm_up() -> dict:
    """Compile (or load) the kernel and the tracer, so the first click is answered warm."""
    from ..views.point import simulate_point

    simulate_point(3.0, multipliers=True, trace=True)
    return {}


ACTIONS = {
    "cell": cell_report,
    "attractors": attractors_report,
    "cycle": cycle_report,
    "line": line_report,
    "edges": edges_report,
    "branch": branch_report,
    "curves": curves_report,
    "hysteresis": hysteresis_report,
    "warm_up": warm_up,
}
