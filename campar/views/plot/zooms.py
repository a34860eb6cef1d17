"""A map with its typed bifurcation curves and zoom panels, like the paper's Figs 2c–e, 4c–e.

The main panel is a label map with its typed cell edges (``curves``: PD, SN, NS, G,
chaos, jump) and a labelled rectangle per zoom window; each zoom panel is a map of
its own — computed on its own finer grid, never a crop of the main one — drawn over
its window with its own curves. Panels are laid out two per row (main first), each
with its label legend right of it and its curve legend below it. Nothing here reads a
store or computes: every panel's grid, arrays and curves are given.
"""

from dataclasses import dataclass, field

from matplotlib.patches import Rectangle

from .maps import MapGrid, plot_map
from .style import figure_style, new_figure

WINDOW_COLOUR = "#111111"
LEGEND_ROOM = 0.3  # width of the legend column, as a share of a map's


@dataclass(frozen=True)
class Panel:
    """One map panel: the grid and arrays of its job, its typed edges (or None), its
    heading, the window it shows (None: the whole grid), and its continued curves."""

    grid: MapGrid
    arrays: dict
    curves: object
    heading: str
    omega: tuple[float, float] | None = None
    second: tuple[float, float] | None = None
    key: str = ""  # the panel's letter, "c", "d", "e" ("": the main panel)
    windows: tuple = field(default_factory=tuple)  # (key, ω range, second range) to outline
    continued: list | None = None  # continued bifurcation curves (campar curves) to overlay


def outline(ax, key: str, omega, second) -> None:
    """A window of a zoom panel on the main panel: its rectangle and its letter."""
    x0, x1 = sorted(omega)
    y0, y1 = sorted(second)
    ax.add_patch(
        Rectangle(
            (x0, y0),
            x1 - x0,
            y1 - y0,
            fill=False,
            edgecolor=WINDOW_COLOUR,
            linewidth=1.1,
            zorder=5.0,
        )
    )
    ax.text(
        x0,
        y1,
        f" ({key})",
        ha="left",
        va="top",
        fontsize=9,
        fontweight="bold",
        color=WINDOW_COLOUR,
        zorder=5.0,
        bbox={"facecolor": "white", "edgecolor": "none", "pad": 0.6, "alpha": 0.8},
    )


def plot_zoom_set(main: Panel, zooms: list[Panel], *, title: str | None = None):
    """The main panel and its zoom panels in one figure (two panels per row)."""
    panels = [main, *zooms]
    rows = -(-len(panels) // 2)
    with figure_style():
        figure = new_figure(17.0, 7.2 * rows)
        # a spacer column right of each map: its label legend (which the layout engine
        # does not see once the curves' legend is added) goes there
        grid = figure.add_gridspec(rows, 4, width_ratios=(1.0, LEGEND_ROOM, 1.0, LEGEND_ROOM))
        for k, panel in enumerate(panels):
            ax = figure.add_subplot(grid[k // 2, 2 * (k % 2)])
            figure.add_subplot(grid[k // 2, 2 * (k % 2) + 1]).set_axis_off()  # the room
            plot_map(
                panel.grid,
                panel.arrays,
                "labels",
                omega=panel.omega,
                second=panel.second,
                ax=ax,
                title=panel.heading,
                curves=panel.curves,
                continued=panel.continued,
            )
            for key, omega, second in panel.windows:
                outline(ax, key, omega, second)
        if title:
            figure.suptitle(title, x=0.01, ha="left")
    return figure
