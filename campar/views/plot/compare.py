"""Two maps of one grid compared: side by side, or the cells whose labels differ.

``campar plot A B`` draws the same view of two stores next to each other (e.g. the clamp
against the paper's unclamped law, or two tolerances); ``campar plot A B --diff`` draws
one map of the grid marking the cells whose n-p labels differ (kinds, n or p), those that
agree, and those not computed in either store. Both stores must hold maps of the same
grid (the same ω values and the same second parameter and values).
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...core.codes import Kind
from .cells import draw_codes
from .maps import cell_edges, plot_map
from .requests import PlotError
from .stores import read_map
from .style import axis_label, figure_style, new_figure, save_figure

# The difference map's categories (code, legend text, colour).
SAME, DIFFERENT = 0, 1
DIFFERENCE_CATEGORIES = ((SAME, "same label", "0.85"), (DIFFERENT, "labels differ", "#c0392b"))
GRID_RTOL = 1e-12  # relative agreement of two grids' cell centres


@dataclass(frozen=True)
class Comparison:
    """What ``plot_compare`` drew: the figure's path; cells computed in both stores, and
    of those the cells whose labels differ (counted with ``difference`` only)."""

    figure: Path
    compared: int
    differ: int | None = None


def plot_compare(
    a,
    b,
    what: str = "labels",
    output=None,
    *,
    difference=False,
    omega=None,
    second=None,
    direction=None,
) -> Comparison:
    """Draw two stores' ``what`` maps side by side, or (``difference``) the cells whose
    labels differ, into an image file (default "A-vs-B-WHAT.png" or "A-vs-B-diff.png"
    here). ``omega``, ``second``: zoom ranges; ``direction``: of both-direction stores."""
    from ..output import figure_file

    if difference and what != "labels":
        raise PlotError(f"--diff compares the n-p labels of two maps, not their {what}")
    name = f"{Path(a).stem}-vs-{Path(b).stem}-{'diff' if difference else what}.png"
    output = figure_file(output or name)
    first, other = (
        read_map(
            path, "labels" if difference else what, omega=omega, second=second, direction=direction
        )
        for path in (a, b)
    )
    check_same_grid(a, b, first.grid, other.grid)
    both = first.arrays["computed"] & other.arrays["computed"]
    if difference:
        differ = label_difference(first.arrays, other.arrays) & both
        figure = plot_difference(first.grid, differ, both, f"{Path(a).name} against {Path(b).name}")
        return Comparison(save_figure(figure, output), int(both.sum()), int(differ.sum()))
    with figure_style():
        figure = new_figure(2 * (4.3 + 1.6), 3.6)
        left, right = figure.subplots(1, 2)
    for ax, path, drawn in ((left, a, first), (right, b, other)):
        plot_map(drawn.grid, drawn.arrays, what, ax=ax, title=Path(path).name)
    return Comparison(save_figure(figure, output), int(both.sum()))


def check_same_grid(a, b, first, other) -> None:
    """PlotError unless the two maps share their second parameter and cell centres."""
    same = first.second_name == other.second_name and all(
        len(x) == len(y) and np.allclose(x, y, rtol=GRID_RTOL, atol=0.0)
        for x, y in ((first.omega, other.omega), (first.second, other.second))
    )
    if not same:
        raise PlotError(
            f"{a} and {b} are maps of different grids ({describe(first)} against "
            f"{describe(other)}): compare maps of one grid"
        )


def describe(grid) -> str:
    return (
        f"{len(grid.second)} {grid.second_name} × {len(grid.omega)} omega, ω "
        f"{grid.omega[0]:g}…{grid.omega[-1]:g}"
    )


def label_difference(first: dict, other: dict) -> np.ndarray:
    """Cells whose n-p labels differ: another kind, or periodic with another n or p."""
    kind_a, kind_b = np.asarray(first["kind"]), np.asarray(other["kind"])
    periodic = kind_a == Kind.PERIODIC
    np_differ = (np.asarray(first["n"]) != np.asarray(other["n"])) | (
        np.asarray(first["p"]) != np.asarray(other["p"])
    )
    return (kind_a != kind_b) | (periodic & np_differ)


def plot_difference(grid, differ: np.ndarray, computed: np.ndarray, title: str):
    """One map of the grid: cells whose labels differ, cells that agree; cells not computed
    in both stores hatched."""
    codes = np.where(differ, DIFFERENT, SAME)
    with figure_style():
        ax = new_figure(4.3 + 1.6, 3.4).add_subplot()
        xe, ye = cell_edges(grid.omega), cell_edges(grid.second)
        draw_codes(
            ax, xe, ye, codes, computed, DIFFERENCE_CATEGORIES, legend=True, title="labels (cells)"
        )
        ax.set_xlim(xe.min(), xe.max())
        ax.set_ylim(ye.min(), ye.max())
        ax.set_xlabel(axis_label("omega"))
        ax.set_ylabel(axis_label(grid.second_name))
        share = differ.sum() / max(computed.sum(), 1)
        ax.set_title(
            f"{title}: {int(differ.sum())} of {int(computed.sum())} cells differ "
            f"({100 * share:.2g} %)",
            loc="left",
        )
    return ax.figure
