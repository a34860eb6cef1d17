"""Maps of result stores: a store's cells read tile by tile into the arrays a map draws
(``read_map``), drawn into an image file (``plot_store``).

Tiles not committed yet are drawn as "not computed", and so are tiles that fail their
checksum (with a warning). A store is read tile by tile and at most ``MAX_DRAWN`` cells
are drawn along each axis (every k-th, said in the title), so memory does not grow with
the grid.
"""

import logging
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from .hysteresis import HYSTERESIS_ARRAYS, drawn_layer, store_hysteresis
from .maps import MapGrid, arrays_for, centre_range, plot_map
from .requests import PlotError
from .style import parameter_text, save_figure

MAX_DRAWN = 1000  # cells per axis a map of a store draws at most (more do not show at 300 dpi)

log = logging.getLogger("campar.views")


@dataclass(frozen=True)
class StoredMap:
    """What a map of a store draws: the grid of the drawn cells, their arrays (with
    ``computed``), and the title (None: the fixed parameters)."""

    grid: MapGrid
    arrays: dict
    title: str | None


def plot_store(
    path,
    what: str = "labels",
    output=None,
    omega=None,
    second=None,
    curves=None,
    direction=None,
    continued=None,
) -> Path:
    """Draw a map of a result store into an image file; returns the file's path.

    direction: of a ``chains.direction: both`` store, the direction whose map is drawn
    ("down", the default, or "up"); its "hysteresis" map draws both (``hysteresis``).

    omega, second: (a, b) zoom ranges. output defaults to "<store name>-<what>.png"
    in the current directory; it is checked before the store's arrays are read (its
    job is read first: a basin store draws its basin, ``basin_view``). ``curves``: typed
    bifurcation edges to overlay (``campar.views.boundaries.store_boundaries``),
    computed on the full grid. ``continued``: continued curves to overlay
    (``campar.views.map_curves.read_curves``).
    """
    from ...sweep.store import read_store
    from ..output import figure_file

    with read_store(path) as store:
        basin = store.job.kind == "basin"
    if basin or what == "basin":
        return basin_view(path, what, output, basin, zoomed=(omega, second, curves, direction))
    output = figure_file(output or f"{Path(path).stem}-{what}.png")
    drawn = read_map(path, what, omega=omega, second=second, direction=direction)
    figure = plot_map(
        drawn.grid, drawn.arrays, what, title=drawn.title, curves=curves, continued=continued
    )
    return save_figure(figure, output)


def read_map(path, what: str = "labels", *, omega=None, second=None, direction=None) -> StoredMap:
    """The cells of a map store that a ``what`` map draws (zoomed to ``omega`` and
    ``second``, one direction of a both store), read tile by tile."""
    from ...sweep.arrays import array_spec
    from ...sweep.store import fill_value, read_store, verify_store  # only this view reads files

    needed = arrays_for(what)
    with read_store(path) as store:
        if store.job.kind == "basin":
            raise PlotError(f"{path} is a basin store: it draws --what basin, alone")
        layer = drawn_layer(store.job, what, direction)
        stored = HYSTERESIS_ARRAYS if what == "hysteresis" else needed
        missing = [name for name in stored if name not in store.names]
        if missing:
            raise PlotError(
                f"{path} holds no {', '.join(missing)} (it has {', '.join(store.names)}); "
                + (
                    "give the job an attractors key (attractors: {starts: 8}) and run it"
                    if what in ("multistability", "attractor_sets")
                    else "add the output to the job's outputs and run it"
                )
            )
        full = MapGrid.from_job(store.job)
        rows = drawn_indices(full.second, second, full.second_name)
        cols = drawn_indices(full.omega, omega, "omega")
        shape = (len(rows), len(cols))
        dtypes = {**store.array_dtypes, "hysteresis": np.dtype(bool)}
        tails = {n: array_spec(store.job, n)[1] if n in store.names else () for n in needed}
        arrays = {n: np.full((*shape, *tails[n]), fill_value(dtypes[n])) for n in needed}
        arrays["computed"] = np.zeros(shape, bool)
        slot = np.full(full.shape[0], -1)
        slot[rows] = np.arange(len(rows))

        def take(check):  # one verified tile (of the drawn direction): its drawn cells
            if check.tile.layer != layer or what == "hysteresis":
                return
            local = slot[check.tile.rows]
            keep = local >= 0
            for name in needed:
                arrays[name][local[keep]] = check.arrays[name][keep][:, cols]
            arrays["computed"][local[keep]] = True

        report = verify_store(store, take)
        if what == "hysteresis":
            arrays.update(store_hysteresis(store, report.verified, rows, cols))
    if report.variables:  # the map is drawn from the job's grid: the damage changes nothing here
        log.warning(
            "%s: damaged variables %s (`campar verify %s` says why); drawn from the job's grid",
            path,
            ", ".join(report.variables),
            path,
        )
    if report.damaged:
        log.warning(
            "%s: %d damaged tiles drawn as not computed (`campar verify %s` says why)",
            path,
            len(report.damaged),
            path,
        )
    grid = replace(full, omega=full.omega[cols], second=full.second[rows])
    step = (-(-full.shape[0] // len(rows)), -(-full.shape[1] // len(cols)))
    title = (
        None
        if step == (1, 1)
        else (f"{parameter_text(grid.fixed)}   (every {step[0]}th × {step[1]}th cell drawn)")
    )
    if layer is not None:  # one direction of a both store: say which
        title = f"{title or parameter_text(grid.fixed)}   (ω swept {direction or 'down'})"
    return StoredMap(grid, arrays, title)


def basin_view(path, what: str, output, basin: bool, zoomed) -> Path:
    """``plot_store`` of a basin store: its one view, the basin figure (``basin``)."""
    from .basin import plot_basin_store

    if not basin:
        raise PlotError(f"{path} is a map; --what basin draws a basin store (sweep y0, ydot0)")
    if what not in ("labels", "basin"):
        raise PlotError(f"{path} is a basin store: it draws --what basin (the default), not {what}")
    if any(option is not None for option in zoomed):
        raise PlotError(f"{path} is a basin store: zooms, curves and directions are for maps")
    return plot_basin_store(path, output)


def drawn_indices(centres: np.ndarray, bounds, name: str) -> np.ndarray:
    """Indices of the cells a map of a store draws along one axis: those in the zoom range,
    every k-th of them so that at most MAX_DRAWN remain."""
    inside = np.arange(len(centres))[centre_range(centres, bounds, name)]
    return inside[:: -(-len(inside) // MAX_DRAWN)]
