"""Single-parameter bifurcation diagrams: σn points y against ω, detachments p beneath.

The data is a ``campar.views.line.BifurcationLine`` (or any object with its
attributes): per cell ω, the σn points (NaN-padded), n, p, kind and the n-p
labels. Drawn as in the paper's Fig. 5 — (a) the section points y of the
steady motion against ω, (a1) the number of detachments p in one period —
with a thin strip between the two panels that colours each cell by its n-p
label, in the colours of the maps (``label_colour``), so a line reads against
the map row it belongs to.

Non-periodic cells (quasi-periodic, chaos) draw their last stored σn points
(a cloud) and no p, since their p counts a read window, not a period.

A line that carries ``transitions`` (``campar.views.transitions``) has each boundary
marked in the σn panel with its type (PD, SN, NS, G, jump), as in the paper's
Figs 2c–e and 5 (``transitions.mark_transitions``).
"""

import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.patches import Patch
from matplotlib.ticker import MaxNLocator

from ...sweep.job import MODEL_OPTION_DEFAULTS
from .cells import EDGE
from .labels import PERIODIC, category_of, label_colour, legend_text, order_key
from .maps import cell_edges
from .style import axis_label, figure_style, new_figure, parameter_text
from .transitions import mark_transitions

POINT_SIZE = 0.6  # marker area (pt²) of a σn point; thousands of cells stay legible
LINE_PARAMETERS = ("f0", "mu_kn", "mu_cn", "zeta")
STRIP_RATIO = 0.09  # height of the label strip relative to the σn panel


def line_title(line, *, parameters=LINE_PARAMETERS) -> str:
    par = line.parameters
    text = parameter_text({name: par[name] for name in parameters if name in par})
    notes = [] if par.get("tensile", "clamp") == "clamp" else ["tensile allowed"]
    notes += [
        f"{name.replace('_', ' ')} {par[name]}"
        for name, default in MODEL_OPTION_DEFAULTS.items()
        if par.get(name, default) != default
    ]
    return text + "".join(f",  {note}" for note in notes)


def section_points(line) -> tuple[np.ndarray, np.ndarray]:
    """(ω, y) of every stored σn point of the line, flattened."""
    y = np.asarray(line.sections)[:, :, 0]
    omega = np.broadcast_to(np.asarray(line.omega)[:, None], y.shape)
    keep = np.isfinite(y)
    return omega[keep], y[keep]


def detachment_counts(line) -> tuple[np.ndarray, np.ndarray]:
    """(ω, p) of the periodic cells."""
    periodic = np.asarray(line.kind) == 0
    return np.asarray(line.omega)[periodic], np.asarray(line.p)[periodic]


def draw_label_strip(ax, line) -> list[str]:
    """One coloured bar per cell (its n-p category); returns the categories in legend order."""
    categories = [category_of(label) for label in line.labels]
    present = sorted(set(categories), key=order_key)
    codes = np.array([present.index(c) for c in categories])[None, :]
    cmap = ListedColormap([label_colour(c) for c in present])
    ax.pcolormesh(
        cell_edges(line.omega),
        [0.0, 1.0],
        codes,
        cmap=cmap,
        vmin=-0.5,
        vmax=len(present) - 0.5,
        shading="flat",
        rasterized=True,
    )
    ax.set_yticks([])
    for side in ("top", "right", "left"):
        ax.spines[side].set_visible(False)
    return [c for c in present if c != PERIODIC]


def plot_line(
    line, axes=None, *, title: str | None = None, legend: bool = True, y_label: bool = True
):
    """Draw one line into three stacked axes (σn, label strip, p) or a new figure."""
    with figure_style():
        if axes is None:
            figure = new_figure(5.2, 4.2)
            axes = line_axes(figure, figure.add_gridspec(1, 1)[0])
        top, strip, bottom = axes
        omega, y = section_points(line)
        top.scatter(omega, y, s=POINT_SIZE, c="black", lw=0, rasterized=True)
        categories = draw_label_strip(strip, line)
        w_p, p = detachment_counts(line)
        bottom.scatter(w_p, p, s=2.0, c="black", lw=0, rasterized=True)
        edges = cell_edges(line.omega)
        for ax in axes:
            ax.set_xlim(edges.min(), edges.max())
        mark_transitions(top, getattr(line, "transitions", ()))
        top.tick_params(labelbottom=False)
        strip.tick_params(labelbottom=False, bottom=False)
        bottom.set_xlabel(axis_label("omega"))
        bottom.yaxis.set_major_locator(MaxNLocator(integer=True, nbins=5, min_n_ticks=2))
        bottom.set_ylim(-0.6, max(1, int(p.max()) if p.size else 1) + 0.6)
        if y_label:
            top.set_ylabel(r"$\sigma_n$: $y$ (units of $h$)")
            bottom.set_ylabel("$p$ (dimensionless)")
        if legend:
            top.figure.legend(
                handles=label_handles(categories),
                loc="outside lower center",
                ncols=min(len(categories), 8),
            )
        top.set_title(line_title(line) if title is None else title, loc="left")
    return top.figure


def label_handles(categories) -> list[Patch]:
    """Legend swatches of n-p categories, outlined like the maps' legends."""
    return [
        Patch(facecolor=label_colour(c), edgecolor=EDGE, linewidth=0.4, label=legend_text(c))
        for c in categories
    ]


def line_axes(figure, cell):
    """(σn, strip, p) axes sharing ω inside one gridspec cell."""
    inner = cell.subgridspec(3, 1, height_ratios=[1.0, STRIP_RATIO, 0.45], hspace=0.0)
    top = figure.add_subplot(inner[0])
    strip = figure.add_subplot(inner[1], sharex=top)
    bottom = figure.add_subplot(inner[2], sharex=top)
    return top, strip, bottom


def plot_lines(lines, titles=None, *, columns: int = 2):
    """Several lines (e.g. the paper's Fig. 5, one per μkn) in a grid, one shared legend
    of the n-p labels met; panels lettered (a, a1), (b, b1), … as in the paper."""
    rows = -(-len(lines) // columns)
    with figure_style():
        figure = new_figure(3.5 * columns, 3.0 * rows + 0.5)
        grid = figure.add_gridspec(rows, columns)
        met = set()
        for i, line in enumerate(lines):
            axes = line_axes(figure, grid[i // columns, i % columns])
            letter = "abcdefghijklmnopqrstuvwxyz"[i]
            title = f"({letter}, {letter}1)  {titles[i] if titles else line_title(line)}"
            plot_line(line, axes, title=title, legend=False, y_label=i % columns == 0)
            met.update(category_of(label) for label in line.labels)
        met.discard(PERIODIC)
        handles = label_handles(sorted(met, key=order_key))
        figure.legend(
            handles=handles,
            loc="outside lower center",
            ncols=min(len(handles), 10),
            title="n-p label (strip colours, as in the maps)",
        )
    return figure
