"""The basin figure: each start (y0, ydot0) coloured by the attractor it reached.

Draws a basin store (``campar.views.basins`` matches its attractors when
``campar.open`` reads it): one flat colour per attractor, ranked by basin fraction
(the legend gives each one's n-p label, kind and fraction), grey where a start
settled on none, hatched where not computed; each attractor's own σn points (its
cycle, or its section cloud) are drawn on top, in its colour with a black edge: the
starts lie at θ = 0, on the stroboscopic section itself, so a cycle's points lie in
its own basin.
"""

import logging
import warnings
from pathlib import Path

import numpy as np

from ...core.codes import Kind
from ...errors import StoreDamageWarning
from ...sweep.job import cell_edges
from .cells import draw_codes
from .style import axis_label, figure_style, new_figure, parameter_text, save_figure

# Attractors get these colours in rank order (qualitative, distinct; Okabe–Ito first);
# attractors beyond them share the last entry's "other" colour.
ATTRACTOR_COLOURS = (
    "#0072b2",
    "#e69f00",
    "#009e73",
    "#cc79a7",
    "#56b4e9",
    "#d55e00",
    "#f0e442",
    "#7f3c8d",
    "#11a579",
    "#3969ac",
    "#f2b701",
    "#e73f74",
)
OTHER = "#6b6b6b"
UNSETTLED = "0.85"
KIND_WORDS = {Kind.PERIODIC: "", Kind.QUASIPERIODIC: " quasi-periodic", Kind.CHAOTIC: " chaotic"}


def basin_categories(ds) -> list[tuple[int, str, str]]:
    """(code, legend text, colour) of every category the map draws: 0 none settled, then
    one per attractor (ATTRACTOR_COLOURS), the rest lumped as one last "other" code."""
    ranks = ds["attractor"].values
    shown = ranks[: len(ATTRACTOR_COLOURS)]
    categories = [(0, "settled on none", UNSETTLED)]
    for rank, colour in zip(shown, ATTRACTOR_COLOURS, strict=False):
        a = ds.sel(attractor=rank)
        label = str(a["attractor_label"].values)
        kind = KIND_WORDS.get(int(a["attractor_kind"].values), "")
        text = f"#{rank} {label}{kind}, {100 * float(a['attractor_fraction']):.1f} %"
        categories.append((int(rank), text, colour))
    if len(ranks) > len(shown):
        rest = float(ds["attractor_fraction"].values[len(shown) :].sum())
        text = f"{len(ranks) - len(shown)} other attractors, {100 * rest:.1f} %"
        categories.append((len(shown) + 1, text, OTHER))
    return categories


def plot_basin(ds, title: str | None = None):
    """The basin of ``ds`` (``campar.open`` of a basin store) as a Figure."""

    second, first = ds["basin"].dims  # (ydot0, y0): rows, columns
    basin = ds["basin"].values
    categories = basin_categories(ds)
    codes = np.minimum(basin, len(categories) - 1)
    computed = basin >= 0
    xe, ye = cell_edges(ds[first].values), cell_edges(ds[second].values)
    with figure_style():
        figure = new_figure(7.2, 4.6)
        ax = figure.add_subplot()
        draw_codes(
            ax,
            xe,
            ye,
            np.where(computed, codes, 0),
            computed,
            categories,
            legend=True,
            title="attractor reached (starts)",
            optional=(0,),
        )
        for (code, _, _), rank in zip(categories[1:], ds["attractor"].values, strict=False):
            if code > len(ATTRACTOR_COLOURS):
                break
            points = ds["attractor_sections"].sel(attractor=rank).values
            periodic = int(ds["attractor_kind"].sel(attractor=rank)) == Kind.PERIODIC
            ax.plot(
                points[:, 0],
                points[:, 1],
                linestyle="none",
                marker="o" if periodic else ".",
                markersize=6 if periodic else 2.5,
                markerfacecolor="white" if periodic else "black",
                markeredgecolor="black",
                markeredgewidth=0.8,
            )
            for x, y in points[np.isfinite(points[:, 0])][: 8 if periodic else 1]:
                ax.annotate(
                    f"#{rank}",
                    (x, y),
                    xytext=(4, 3),
                    textcoords="offset points",
                    fontsize=7,
                    fontweight="bold",
                )
        ax.set_xlim(xe.min(), xe.max())
        ax.set_ylim(ye.min(), ye.max())
        ax.set_xlabel(axis_label(first))
        ax.set_ylabel(axis_label(second))
        fixed = {n: float(ds[n]) for n in ("omega", "mu_kn", "mu_cn", "f0", "zeta") if n in ds}
        heading = f"basin of attraction: {parameter_text(fixed)}   (tensile: {ds.attrs['tensile']})"
        ax.set_title(heading if title is None else f"{heading}\n{title}", loc="left")
    return figure


def plot_basin_store(path, output=None) -> Path:
    """Draw the basin store at ``path`` into an image file (default
    "<store name>-basin.png" in the current directory); returns its path."""
    from ..dataset import open as open_store
    from ..output import figure_file

    output = figure_file(output or f"{Path(path).stem}-basin.png")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", StoreDamageWarning)
        ds = open_store(path)  # damaged tiles read as not computed: drawn so, said in one line
    for warning in caught:
        if issubclass(warning.category, StoreDamageWarning):
            logging.getLogger("campar.views").warning("%s", warning.message)
        else:
            warnings.warn(warning.message, warning.category, stacklevel=2)
    with ds:
        figure = plot_basin(ds)
    return save_figure(figure, output)
