"""Bifurcation lines through a map: a row, a column, or a segment between two cells.

Each is one continuation chain of the kernel, as ``campar line`` runs one: every cell
warm-started from the one before, every σn point kept (DEFAULT_SECTIONS of a
non-periodic cell, n of an n-cycle), the label of every cell.

- a **row** (along the map's first axis, ω) is the map's own row run again, started as
  the map started it (the job's start, or with ``chains.start: continue`` the stored
  final state of the row before's first cell): its cells are the map's;
- a **column** (along the second parameter, at the column's ω) runs through the map's
  rows in the map's order;
- a **segment** runs from clicked cell A to clicked cell B, both parameters varying
  linearly between the cells' centres, at one cell a grid step of the longer side
  (or ``points`` cells).

A column and a segment start on the attractor the map holds at their first cell (its
stored final state, its tile verified), with that cell's model (``campar.cell``): the
chain follows the map's attractor, not a start from rest. A law parameter (φ1 …) as
the map's second parameter changes the compiled law from row to row, so a column or a
segment there is refused.
"""

import math

import numpy as np

from ..errors import CamparError

MAX_LINE_POINTS = 2000  # cells of a segment asked for with ``points``


def row_line(path, row: int) -> dict:
    """The bifurcation diagram of map row ``row``: its chain along the first axis run
    again with every σn point kept, started as the map started the row."""
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
    x = line.first_values
    values = {job.first: x, job.second: np.full(len(x), value)}
    diagram = _diagram(job.first, values, cells, line.classify.chatter_p)
    return {"along": "row", "row": row, job.second: value, **diagram}


def column_line(path, col: int) -> dict:
    """The bifurcation diagram of map column ``col``: a chain along the second parameter
    at the column's first-axis value, through the map's rows in the map's order, started
    on the attractor the map holds at the column's first cell."""
    from ..sweep.store import read_store

    with read_store(path) as reader:
        job = reader.job
    rows = len(job.second_values)
    diagram = _chain(path, (0, col), (rows - 1, col), rows, job.second)
    return {"along": "column", "col": col, job.first: float(job.first_values[col]), **diagram}


def segment_line(path, a: tuple[int, int], b: tuple[int, int], points: int | None = None) -> dict:
    """The bifurcation diagram of the segment from map cell ``a`` = (row, col) to cell
    ``b``: a chain through ``points`` cells evenly spaced between the two cells' centres
    (default one a grid step along the segment's longer side), started on the attractor
    the map holds at ``a``; drawn against the parameter that changes most in grid steps."""
    from ..sweep.store import read_store

    if tuple(a) == tuple(b):
        raise CamparError("a segment needs two different cells")
    rows, cols = abs(b[0] - a[0]), abs(b[1] - a[1])
    if points is None:
        points = max(rows, cols) + 1
    if not 2 <= points <= MAX_LINE_POINTS:
        raise CamparError(f"a segment has 2 to {MAX_LINE_POINTS} points, got {points}")
    with read_store(path) as reader:
        job = reader.job
    drawn = job.first if cols >= rows else job.second
    diagram = _chain(path, a, b, points, drawn)
    return {"along": "segment", "a": list(a), "b": list(b), **diagram}


def _chain(path, a, b, points: int, drawn: str) -> dict:
    """A chain of ``points`` cells from map cell ``a`` to ``b`` (their centres, linearly),
    with the model of cell ``a`` and started from its stored final state."""
    from ..model.compute import run_cells
    from ..model.laws import LAW_PARAMETERS
    from ..views.line import DEFAULT_SECTIONS, LINE_OUTPUTS
    from .cells import stored_model_cell

    stored = stored_model_cell(path, *a)
    job = stored.job
    if job.second in LAW_PARAMETERS:
        raise CamparError(
            f"{job.second} changes the compiled law from row to row: lines through this map "
            "run along its rows only"
        )
    t = np.linspace(0.0, 1.0, points)
    values = {}
    for name, axis, (i, j) in (
        (job.first, job.first_values, (a[1], b[1])),
        (job.second, job.second_values, (a[0], b[0])),
    ):
        values[name] = float(axis[i]) + t * (float(axis[j]) - float(axis[i]))
    model = stored.model
    if model.classify.sections is None:
        model = model.replace(sections=DEFAULT_SECTIONS)
    state = np.asarray(stored.state, float)
    start = state if np.all(np.isfinite(state)) else None  # a failed cell: the model's start
    columns = {k: v for k, v in values.items() if k != "omega"}
    omega = values.get("omega", np.full(points, model.omega))
    out = run_cells(model, omega=omega, start=start, outputs=LINE_OUTPUTS, **columns)
    cells = {name: getattr(out, name) for name in ("kind", "n", "p", "sections")}
    return _diagram(drawn, values, cells, model.classify.chatter_p)


def _diagram(drawn: str, values: dict, cells: dict, chatter: int) -> dict:
    """The page's line: σn points y against the parameter ``drawn``, every cell's label,
    and where the label changes (half-way between the cells, in ``drawn``)."""
    from ..core.codes import cell_label

    labels = [
        cell_label(int(k), int(n), int(p), chatter) if k >= 0 else ""
        for k, n, p in zip(cells["kind"], cells["n"], cells["p"], strict=True)
    ]
    x = np.asarray(values[drawn], float)
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
        "x": drawn,
        "points": points,
        "labels": labels,
        "first": x.tolist(),
        "values": {name: np.asarray(v, float).tolist() for name, v in values.items()},
        "changes": changes,
    }


def line_report(path, along: str, row: int, col: int, row2: int, col2: int, points) -> dict:
    """The worker's line action: a row, a column or a segment (``along``); with
    ``kernel_note`` where another kernel computed the store (a row's cells need not be
    the map's then)."""
    from .cells import kernel_note

    if along == "row":
        data = row_line(path, row)
    elif along == "column":
        data = column_line(path, col)
    else:
        data = segment_line(path, (row, col), (row2, col2), points)
    note = kernel_note(path)
    return data if note is None else {**data, "kernel_note": note}
