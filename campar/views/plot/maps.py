"""Two-parameter maps: n-p labels, kinds of motion and per-cell quantities over (ω, second).

Arrays are per cell, shaped (second, omega) in the job's order (ω decreasing
along a chain). A cell is drawn as the rectangle around its centre between the
midpoints to its neighbours, so the map is exact whatever the axes' directions;
figures always show ω increasing to the right and the second parameter
increasing upwards, as in the paper. Cells without a value are never blended
into the colour scale: they are left transparent over a hatch, dark red
cross-hatch for failed cells (NaN), light grey for tiles not computed yet.
"""

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from matplotlib import colormaps
from matplotlib.colors import ListedColormap, LogNorm, Normalize, TwoSlopeNorm
from matplotlib.ticker import FuncFormatter, MaxNLocator

from ...core.codes import Kind
from ...sweep.job import PARAMETERS, Job, cell_edges
from ...sweep.plan import plan_tiles
from .cells import draw_categories, draw_gaps, draw_legend, swatch
from .hysteresis import draw_hysteresis
from .labels import (
    FAILED,
    NOT_COMPUTED,
    computed_cells,
    distinct_categories,
    map_kinds,
    map_labels,
)
from .multistability import draw_attractor_sets, draw_multistability
from .requests import MAP_VIEWS, PlotError
from .style import axis_label, figure_style, new_figure, parameter_text

NICE_TICKS = MaxNLocator(4, steps=[1, 2, 2.5, 5, 10])
LEGEND_ROWS = 16  # entries per legend column before a new column starts
LEGEND_MAX = 32  # entries a legend shows; rarer n-p are grouped in "other" (listed)


@dataclass(frozen=True)
class Quantity:
    """How a per-cell quantity is drawn: colour-bar label (meaning and units) and scale."""

    label: str
    cmap: str
    # linear | auto: log if > 0 and spanning ≥ LOG_SPAN | diverging: white at 0
    scale: str = "linear"
    vmin: float | None = None
    vmax: float | None = None


PERIODIC_ONLY = ("n", "p")  # quantities of periodic cells: others have no value on their map
LOG_SPAN = 30.0  # max/min ratio from which an "auto" quantity is drawn on a log scale

# ε and y are in units of the stroke h, forces in units of K1·h, time in units of 1/ωn.
QUANTITIES = {
    "n": Quantity("period n (revolutions; no value: not periodic)", "viridis"),
    "p": Quantity("detachments p in n revolutions (no value: not periodic)", "magma"),
    "dc": Quantity(
        "duty cycle DC (dimensionless: fraction of time separated)", "viridis", vmin=0.0, vmax=1.0
    ),
    "eps_max": Quantity(r"intrusion depth max $\varepsilon$ (units of stroke $h$)", "plasma"),
    "eps_min": Quantity(
        r"min $\varepsilon$ (< 0: detachment height; units of stroke $h$)", "RdBu_r", "diverging"
    ),
    "pn_max": Quantity(r"max contact force $P_n$ (units of $K_1 h$)", "inferno", "auto"),
    "revolutions": Quantity("revolutions computed per cell (dimensionless)", "cividis", "auto"),
    "lyapunov": Quantity(
        r"largest Lyapunov exponent $\lambda_1$ (units of $\omega_n$)", "RdBu_r", "diverging"
    ),
}


@dataclass(frozen=True)
class MapGrid:
    """Axes of a map: cell centres in the job's order, and what the figure states about them."""

    omega: np.ndarray  # (n_omega,) ω of the cell centres
    second: np.ndarray  # (n_second,) second parameter of the cell centres
    second_name: str  # "f0", "mu_kn", "mu_cn" or "zeta"
    chatter_p: int = 7  # p from which a motion is chattering-impact (n-p̃)
    fixed: Mapping[str, float] = field(default_factory=dict)  # for the caption

    @classmethod
    def from_job(cls, job: Job) -> "MapGrid":
        fixed = {name: job.fixed[name] for name in PARAMETERS if name in job.fixed}
        return cls(job.omega, job.second_values, job.second, job.classify.chatter_p, fixed)

    @property
    def shape(self) -> tuple[int, int]:
        return len(self.second), len(self.omega)


def centre_range(centres: np.ndarray, bounds, name: str) -> slice:
    """Index range of the centres inside [min(bounds), max(bounds)] (ends included)."""
    if bounds is None:
        return slice(None)
    lo, hi = sorted(float(b) for b in bounds)
    spacing = np.min(np.abs(np.diff(centres))) if len(centres) > 1 else 1.0
    slack = 1e-9 * spacing  # a grid value typed as a bound is inside despite rounding
    inside = np.flatnonzero((centres >= lo - slack) & (centres <= hi + slack))
    if inside.size == 0:
        raise PlotError(
            f"no cell centre of {name} lies in [{lo:g}, {hi:g}]; the map covers "
            f"{name} from {centres.min():g} to {centres.max():g}"
        )
    return slice(int(inside[0]), int(inside[-1]) + 1)


def select_cells(grid: MapGrid, arrays: Mapping, omega=None, second=None):
    """Zoom: the grid and arrays of the cells whose centres lie in the given ranges.

    ``omega=(a, b)`` and ``second=(c, d)`` in either order, ends included; None keeps
    the whole axis. Arrays keep their trailing dimensions; returns (grid, arrays).
    """
    cols = centre_range(grid.omega, omega, "omega")
    rows = centre_range(grid.second, second, grid.second_name)
    sub = MapGrid(grid.omega[cols], grid.second[rows], grid.second_name, grid.chatter_p, grid.fixed)
    out = {}
    for name, values in arrays.items():
        values = np.asarray(values)
        if values.shape[:2] != grid.shape:
            raise PlotError(f"array {name!r} has shape {values.shape}, the map is {grid.shape}")
        out[name] = values[rows, cols]
    return sub, out


def computed_mask(job: Job, done) -> np.ndarray:
    """Cells (second, omega) of the tiles whose ``done`` flag is set."""
    tiles = plan_tiles(job)
    done = np.asarray(done, bool).reshape(-1)
    if done.shape != (len(tiles),):
        raise PlotError(f"done mask has {done.size} flags, the job has {len(tiles)} tiles")
    rows = np.zeros(job.shape[0], bool)
    for tile in tiles:
        rows[tile.rows] = done[tile.index]
    return np.repeat(rows[:, None], job.shape[1], axis=1)


def arrays_for(what: str) -> tuple[str, ...]:
    """Names of the per-cell arrays a view draws."""
    if what not in MAP_VIEWS:
        raise PlotError(f"cannot draw {what!r}; choose one of {', '.join(MAP_VIEWS)}")
    if what == "multistability":
        return ("n_attractors",)
    if what == "attractor_sets":
        return ("n_attractors", "attractor_kind", "attractor_n", "attractor_p")
    if what in PERIODIC_ONLY:
        return (what, "kind")
    return ("kind", "n", "p") if what == "labels" else ("kind",) if what == "kind" else (what,)


def plot_map(
    grid: MapGrid | Job,
    arrays: Mapping,
    what: str = "labels",
    *,
    omega=None,
    second=None,
    ax=None,
    title: str | None = None,
    legend: bool = True,
    log: bool | None = None,
    vmin: float | None = None,
    vmax: float | None = None,
    curves=None,
    continued=None,
):
    """Draw a map and return its Figure.

    grid: a MapGrid or the Job that made the arrays.
    arrays: name → array (second, omega): "kind", "n", "p" for labels and kind, the
        quantity itself otherwise; optional "computed" (bool) marks computed cells.
    what: "labels" (n-p), "kind", "n" or "p" (of the periodic cells; with "kind"),
        "multistability" (int "n_attractors": attractors per cell), "attractor_sets"
        (which attractors coexist: "n_attractors" and the census's "attractor_kind",
        "attractor_n", "attractor_p", shaped (second, omega, cap)), "hysteresis" (bool
        "hysteresis", optional bool "compared": both directions periodic), or a quantity
        of QUANTITIES.
    omega, second: (a, b) ranges to zoom into, like the paper's detail panels.
    ax: draw into this axes instead of a new figure.
    title: text above the map; None states the fixed parameters, "" none.
    log, vmin, vmax: colour scale of a quantity (log None: the quantity's default).
    curves: typed bifurcation edges to overlay (``campar.views.boundaries``; ``curves``).
    continued: continued bifurcation curves to overlay (BifurcationCurve objects in this
    map's plane, ``campar.views.map_curves.read_curves``).
    """
    if isinstance(grid, Job):
        grid = MapGrid.from_job(grid)
    needed = arrays_for(what)
    missing = [name for name in needed if name not in arrays]
    if missing:
        raise PlotError(f"a {what} map needs the arrays {', '.join(missing)}")
    keep = {name: arrays[name] for name in (*needed, "computed", "compared") if name in arrays}
    grid, arrays = select_cells(grid, keep, omega, second)
    # room for the curves' legend under the map
    height = 3.4 if curves is None and continued is None else 4.9
    with figure_style():
        xe, ye = cell_edges(grid.omega), cell_edges(grid.second)
        gaps_legend = False  # a one-line legend of the gaps above a quantity map
        if what in ("labels", "kind"):
            cells = map_labels(arrays, grid.chatter_p) if what == "labels" else map_kinds(arrays)
            cells = distinct_categories(cells, LEGEND_MAX if legend else None)
            lines = sum(1 + e.text.count("\n") for e in cells.entries)
            columns = -(-lines // LEGEND_ROWS)
            if ax is None:
                ax = new_figure(4.3 + 1.25 * columns, height).add_subplot()
            draw_categories(ax, xe, ye, cells)
            if legend:
                heading = "n-p (cells)" if what == "labels" else "kind (cells)"
                draw_legend(ax, cells.entries, heading, columns)
        elif what == "hysteresis":
            if ax is None:
                ax = new_figure(4.3 + 2.0 * legend, height).add_subplot()
            draw_hysteresis(ax, xe, ye, arrays, legend=legend)
        elif what == "multistability":
            if ax is None:
                ax = new_figure(4.3 + 1.6 * legend, height).add_subplot()
            draw_multistability(ax, xe, ye, arrays, legend=legend)
        elif what == "attractor_sets":
            if ax is None:
                ax = new_figure(4.3 + 2.4 * legend, height).add_subplot()
            draw_attractor_sets(ax, xe, ye, arrays, grid.chatter_p, legend=legend)
        else:
            if what in PERIODIC_ONLY:  # n and p of the periodic cells only
                periodic = np.asarray(arrays["kind"]) == Kind.PERIODIC
                arrays = {**arrays, what: np.where(periodic, arrays[what], np.nan)}
            if ax is None:
                ax = new_figure(4.9, height).add_subplot()
            gaps_legend = draw_quantity(
                ax, xe, ye, arrays, what, legend=legend, log=log, vmin=vmin, vmax=vmax
            )
        if curves is not None:
            from .curves import draw_curves

            draw_curves(ax, curves, legend=legend)
        if continued is not None:
            from .branches import draw_bifurcation_curves

            draw_bifurcation_curves(ax, continued, legend=legend)
        ax.set_xlim(xe.min(), xe.max())
        ax.set_ylim(ye.min(), ye.max())
        ax.set_xlabel(axis_label("omega"))
        ax.set_ylabel(axis_label(grid.second_name))
        pad = 16.0 if gaps_legend else 6.0  # room for the gaps' legend under the title
        ax.set_title(parameter_text(grid.fixed) if title is None else title, loc="left", pad=pad)
    return ax.figure


def draw_quantity(ax, xe, ye, arrays, what: str, *, legend: bool, log, vmin, vmax) -> bool:
    """A per-cell quantity with a colour bar; failed (NaN) and not computed cells as gaps,
    explained in a one-line legend just above the map. True if that legend was drawn."""
    quantity = QUANTITIES[what]
    values = np.asarray(arrays[what], float)
    computed = computed_cells(arrays, values.shape)
    values = np.where(computed, values, np.nan)
    missing = computed & ~np.isfinite(values)
    norm, cmap = quantity_scale(quantity, values, log, vmin, vmax)
    draw_gaps(ax, xe, ye, missing, ~computed)
    mesh = ax.pcolormesh(
        xe,
        ye,
        np.ma.masked_invalid(values),
        cmap=cmap,
        norm=norm,
        shading="flat",
        rasterized=True,
    )
    bar = ax.figure.colorbar(mesh, ax=ax, label=quantity.label, pad=0.02, aspect=30)
    if isinstance(norm, TwoSlopeNorm):
        bar.set_ticks(diverging_ticks(norm.vmin, norm.vmax))
        bar.ax.yaxis.set_major_formatter(FuncFormatter(short_number))
    handles = []
    if missing.any():
        handles.append(swatch(FAILED, f"no value ({int(missing.sum())})", "white"))
    if not computed.all():
        handles.append(swatch(NOT_COMPUTED, f"not computed ({int((~computed).sum())})", "white"))
    if legend and handles:
        ax.legend(handles=handles, loc="lower left", bbox_to_anchor=(0.0, 1.01), ncols=2)
    return bool(legend and handles)


def quantity_scale(quantity: Quantity, values: np.ndarray, log, vmin, vmax):
    """(norm, colormap) of a quantity map; a diverging one is white at 0 whatever signs occur."""
    finite = values[np.isfinite(values)]
    data_lo, data_hi = (finite.min(), finite.max()) if finite.size else (0.0, 1.0)
    lo = next(v for v in (vmin, quantity.vmin, data_lo) if v is not None)
    hi = next(v for v in (vmax, quantity.vmax, data_hi) if v is not None)
    if hi <= lo:  # a constant field still gets a readable colour bar
        lo, hi = lo - 0.5 * max(abs(lo), 1.0), hi + 0.5 * max(abs(hi), 1.0)
    cmap = colormaps[quantity.cmap]
    if log is None:
        log = quantity.scale == "auto" and lo > 0 and hi / lo >= LOG_SPAN
    if log:
        if lo <= 0:
            raise PlotError(f"{quantity.label}: a log scale needs values > 0, the map has {lo:g}")
        return LogNorm(lo, hi), cmap
    if quantity.scale != "diverging":
        return Normalize(lo, hi), cmap
    if lo < 0.0 < hi:
        return TwoSlopeNorm(0.0, lo, hi), cmap
    half = np.linspace(0.0, 0.5, 128) if hi <= 0.0 else np.linspace(0.5, 1.0, 128)
    return Normalize(min(lo, 0.0), max(hi, 0.0)), ListedColormap(cmap(half))


def diverging_ticks(lo: float, hi: float) -> np.ndarray:
    """Round ticks on both sides of 0 (a TwoSlopeNorm bar gives each side half its length)."""
    ticks = np.concatenate([NICE_TICKS.tick_values(lo, 0.0), NICE_TICKS.tick_values(0.0, hi)])
    ticks = np.unique(ticks)
    return ticks[(ticks >= lo) & (ticks <= hi)]


def short_number(value: float, _position=None) -> str:
    """Tick text without trailing zeros, with a true minus sign: "−1.5", "0", "0.25"."""
    return f"{value:g}".replace("-", "\N{MINUS SIGN}")
