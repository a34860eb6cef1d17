"""One map cell computed again, and the page's other computations.

``cell_at(path, row, col)`` is the explorer's one way to a cell's motion: ``campar.cell``
of the map cell (its model and stored values, its tile verified first) simulated as
``campar point --from`` simulates it — its chain replayed, so every stored value comes
back bit for bit — with the steady orbit traced densely. The other actions of the cell
panel (its attractors from K starts, its n-cycle by shooting, the branches through its
cycle) start from the same StoredCell; its lines (a row, a column, a segment) are
``campar.explore.lines``.

Each is a plain function of plain arguments returning JSON-ready data (``ACTIONS``), run
by the server's worker process (``campar.explore.worker``).
"""

import math

import numpy as np

from ..core.version import KERNEL_VERSION
from ..errors import CamparError

TRACE_POINTS = 4000  # samples of an orbit sent to the page (every k-th of the trace)


def stored_model_cell(path, row: int, col: int, layer: int = 0):
    """``campar.cell`` of map cell (row, col) — its model and stored values — once its
    tile has verified against its checksum (``stored_cell``)."""
    from ..views.cell import cell
    from .source import stored_cell

    job, _ = stored_cell(path, row, col, layer)
    direction = job.directions[layer] if job.chains.direction == "both" else None
    at = {job.first: float(job.first_values[col]), job.second: float(job.second_values[row])}
    return cell(path, direction=direction, **at)


def cell_at(path, row: int, col: int, layer: int = 0):
    """The PointResult (with its dense trace) of map cell (row, col) of the store ``path``,
    as ``campar point --from`` computes it (``StoredCell.simulate``)."""
    return stored_model_cell(path, row, col, layer).simulate(trace=True)


def cell_report(path, row: int, col: int, layer: int = 0) -> dict:
    """What the page's cell panel shows: ``cell_at``'s numbers and its orbit, JSON-ready;
    ``kernel_note`` where another kernel computed the store (its values need not come back)."""
    stored = stored_model_cell(path, row, col, layer)
    result = stored.simulate(trace=True)
    data = result.to_dict()
    if not stored.current_kernel:
        data["kernel_note"] = _kernel_note(stored.kernel)
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
    data["cell"] = {"row": row, "col": col, "layer": layer, "kernel": stored.kernel}
    return data


def kernel_note(path) -> str | None:
    """What the page says of a store another kernel version computed (its cells computed
    again need not come back bit for bit); None for one this campar's kernel computed."""
    from ..sweep.store import other_kernel, read_store, stored_kernel

    with read_store(path) as reader:
        attrs = reader.attrs
    return None if other_kernel(attrs) is None else _kernel_note(stored_kernel(attrs))


def _kernel_note(kernel: str | None) -> str:
    return (
        f"computed with kernel version {KERNEL_VERSION}; the store was computed by "
        f"{kernel or 'an earlier one'}: its values need not come back bit for bit"
    )


def attractors_report(path, row: int, col: int, count: int) -> dict:
    """The cell's attractors from ``count`` starts (``campar point --from --attractors``)."""
    return stored_model_cell(path, row, col).attractors(count).to_dict()


def cycle_report(path, row: int, col: int, n: int) -> dict:
    """The cell's n-cycle by shooting from its stored state, stable or not."""
    return stored_model_cell(path, row, col).cycle(n).to_dict()


def branch_report(path, row: int, col: int, along: str = "row") -> dict:
    """The branches through the cell's cycle along the map's row (its first axis) or its
    column (``along``: the second axis), both ways to the map's ends (``campar
    continue``), with one level of period doubling followed: each branch's σn points y
    with their stability, and its special points (PD, SN, NS, G)."""
    from ..sweep.store import read_store
    from ..views.continuation import continue_from_cell

    stored = stored_model_cell(path, row, col)
    arrays = stored.stored
    if int(arrays["kind"]) != 0 or int(arrays["n"]) < 1:
        raise CamparError(f"cell ({row}, {col}) is not periodic: no cycle to continue")
    with read_store(path) as reader:  # the map's own range along the line's axis
        job = reader.job
        first = job.first if along == "row" else job.second
        axis = job.sweep[first]
    here = float(stored.coordinates[first])
    # the cell's parameters, said again: those not given take the paper's values
    fixed = {k: v for k, v in stored.model.parameters.items() if k != first}
    branches, special = [], []
    y0, v0 = stored.state
    for end in sorted({float(axis.start), float(axis.stop)}):
        if end == here:
            continue
        result = continue_from_cell(
            first,
            (here, end),
            fixed,
            y0=y0,
            v0=v0,
            cycle=int(arrays["n"]),
            switch=1,
            model=stored.model,
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
    return {"branches": branches, "special": special, "parameter": first}


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
    "edges": edges_report,
    "branch": branch_report,
    "curves": curves_report,
    "hysteresis": hysteresis_report,
    "warm_up": warm_up,
}
