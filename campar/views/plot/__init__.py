"""Figures of computed results: maps, bifurcation diagrams, phase portraits, time series.

Every view draws plain arrays that were computed before (a store, ``run_tile``,
a point simulation) and never recomputes them; nothing here imports the kernel.
Figures are headless (Agg) and returned, so a caller can adjust or save them.

- ``requests``: what can be asked for (``MAP_VIEWS``, ``parse_range``, ``PlotError``).
- ``labels``: n-p categories and their fixed colours (``label_colour``, ``map_labels``).
- ``cells``: grids of cells as flat colours, gaps hatched, legends with counts (the
  drawing every categorical view shares).
- ``maps``: two-parameter maps (``MapGrid``, ``plot_map``, ``select_cells``).
- ``stores``: maps of result stores (``plot_store``, ``read_map``).
- ``compare``: two maps side by side, and the cells whose labels differ (``plot_compare``).
- ``hysteresis``: maps of a two-direction store (which direction; down against up).
- ``multistability``: the number of attractors per cell of a census (job key ``attractors``),
  and which attractors coexist (their set).
- ``basin``: the basin of attraction of a basin store, starts coloured by attractor.
- ``style``: fonts, the field's notation, ``save_figure``.
- ``orbit``: one steady orbit (``plot_orbit``; ``plot_phase``, ``plot_gap``, ``plot_force``).
- ``bifurcation``: σn points and detachments along ω (``plot_line``, ``plot_lines``).
- ``transitions``: a line's typed boundaries drawn on its diagram (``mark_transitions``).
- ``curves``: a map's typed boundaries drawn as bifurcation curves (``draw_curves``).
- ``figures``: the paper's composite figures (phase-portrait grid, ε(t) families, Pn rows).

For developers: a new view (bifurcation diagram, phase portrait, time series) is
one module of pure ``plot_*(data, …, ax=None) -> Figure`` functions that create
artists inside ``style.figure_style()``, use ``style.new_figure`` when no axes is
given, and take their colours for n-p labels from ``labels.label_colour``.

Importing this package is cheap (matplotlib loads on first use of a view), so
the CLI can name the views without paying for matplotlib.
"""

import importlib

from .requests import MAP_VIEWS, STORE_VIEWS, PlotError, parse_range

_EXPORTS = {
    "label_colour": "labels",
    "map_labels": "labels",
    "map_kinds": "labels",
    "CategoryMap": "labels",
    "LegendEntry": "labels",
    "MapGrid": "maps",
    "QUANTITIES": "maps",
    "computed_mask": "maps",
    "plot_map": "maps",
    "plot_store": "stores",
    "read_map": "stores",
    "plot_compare": "compare",
    "select_cells": "maps",
    "save_figure": "style",
    "plot_orbit": "orbit",
    "plot_phase": "orbit",
    "plot_gap": "orbit",
    "plot_force": "orbit",
    "plot_line": "bifurcation",
    "plot_lines": "bifurcation",
    "mark_transitions": "transitions",
}

__all__ = ["MAP_VIEWS", "STORE_VIEWS", "PlotError", "parse_range", *_EXPORTS]


def __getattr__(name):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f".{module}", __name__), name)


def __dir__():
    return sorted(__all__)
