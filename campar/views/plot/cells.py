"""Grids of cells drawn as flat colours: category codes, gaps hatched, legends with counts.

The drawing every categorical view shares (``maps``, ``compare``, ``hysteresis``,
``multistability``, ``basin``): a cell is the rectangle between its edges, cells
without a value are masked and left transparent over a hatch (``labels.GAP_STYLE``),
and a legend right of the axes counts each category's cells.
"""

import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.patches import Patch, Rectangle

from .labels import FAILED, GAP_STYLE, NOT_COMPUTED, OTHER, OTHER_STYLE, CategoryMap

EDGE = "0.45"  # outline of legend swatches, so white and pale ones show


def draw_categories(ax, xe, ye, cells: CategoryMap) -> None:
    """Categories as flat colours; failed and not computed cells as hatched gaps."""
    colours = [entry.colour for entry in cells.entries]
    gaps = {
        label: cells.codes == i
        for i, label in enumerate(cells.labels_present)
        if label in (FAILED, NOT_COMPUTED)
    }
    codes = np.ma.masked_array(cells.codes, np.zeros(cells.codes.shape, bool))
    for mask in gaps.values():
        codes[mask] = np.ma.masked
    draw_gaps(ax, xe, ye, gaps.get(FAILED), gaps.get(NOT_COMPUTED))
    ax.pcolormesh(
        xe,
        ye,
        codes,
        cmap=ListedColormap(colours),
        vmin=-0.5,
        vmax=len(colours) - 0.5,
        shading="flat",
        rasterized=True,
    )
    if OTHER in cells.labels_present:  # the hatch over the rare labels grouped in "other"
        hatch = {**OTHER_STYLE, "facecolor": "none"}
        for (c0, c1), (r0, r1) in cell_runs(cells.codes == cells.labels_present.index(OTHER)):
            x0, x1 = sorted((xe[c0], xe[c1]))
            y0, y1 = sorted((ye[r0], ye[r1]))
            ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, zorder=1.5, **hatch))


def draw_legend(ax, entries, title: str, columns: int) -> None:
    """Legend right of the map: every category with its cell count ("other" lists its
    labels)."""
    handles = [swatch(e.label, f"{e.text} ({e.count})", e.colour) for e in entries]
    ax.legend(
        handles=handles,
        title=title,
        loc="upper left",
        bbox_to_anchor=(1.03, 1.0),
        ncols=columns,
        alignment="left",
    )


def draw_codes(
    ax, xe, ye, codes, computed, categories, *, legend: bool, title: str, optional=()
) -> None:
    """A map of category codes as flat colours (``categories``: (code, text, colour) with
    codes 0, 1, … in order), cells not computed hatched, a legend counting each category's
    cells (the ``optional`` codes only where some cell has them)."""
    draw_gaps(ax, xe, ye, None, ~computed)
    ax.pcolormesh(
        xe,
        ye,
        np.ma.masked_array(codes, ~computed),
        cmap=ListedColormap([colour for _, _, colour in categories]),
        vmin=-0.5,
        vmax=len(categories) - 0.5,
        shading="flat",
        rasterized=True,
    )
    if not legend:
        return
    counts = {value: int(((codes == value) & computed).sum()) for value, _, _ in categories}
    handles = [
        swatch(text, f"{text} ({counts[value]})", colour)
        for value, text, colour in categories
        if counts[value] or value not in optional
    ]
    if not computed.all():
        handles.append(swatch(NOT_COMPUTED, f"not computed ({int((~computed).sum())})", "white"))
    ax.legend(
        handles=handles, title=title, loc="upper left", bbox_to_anchor=(1.03, 1.0), alignment="left"
    )


def draw_gaps(ax, xe, ye, failed=None, pending=None) -> None:
    """Hatches under the (masked, transparent) cells without a value.

    Failed cells: one cross-hatched rectangle under the whole map shows through
    them, however many there are. Cells not computed (whole tiles): one
    rectangle with a light hatch per run of such cells.
    """
    if failed is not None and failed.any():
        ax.add_patch(
            Rectangle(
                (xe.min(), ye.min()),
                np.ptp(xe),
                np.ptp(ye),
                zorder=0.5,
                **GAP_STYLE[FAILED],
            )
        )
    if pending is not None and pending.any():
        for (c0, c1), (r0, r1) in cell_runs(pending):
            x0, x1 = sorted((xe[c0], xe[c1]))
            y0, y1 = sorted((ye[r0], ye[r1]))
            ax.add_patch(
                Rectangle((x0, y0), x1 - x0, y1 - y0, zorder=0.6, **GAP_STYLE[NOT_COMPUTED])
            )


def cell_runs(mask: np.ndarray) -> list:
    """Rectangles [(c0, c1), (r0, r1)) covering the True cells of a 2-D mask: runs of
    columns per row, merged over consecutive rows with the same runs."""
    rectangles = []
    open_runs = {}  # (c0, c1) → first row
    for r in range(mask.shape[0] + 1):
        runs = set()
        if r < mask.shape[0]:
            edges = np.flatnonzero(np.diff(np.concatenate([[0], mask[r].astype(np.int8), [0]])))
            runs = set(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))
        for run in [run for run in open_runs if run not in runs]:
            rectangles.append((run, (open_runs.pop(run), r)))
        for run in runs:
            open_runs.setdefault(run, r)
    return rectangles


def swatch(category: str, text: str, colour) -> Patch:
    """Legend handle of a category (gaps hatched like the map)."""
    if category in GAP_STYLE:
        return Patch(label=text, **GAP_STYLE[category])
    if category == OTHER:
        return Patch(label=text, **{**OTHER_STYLE, "linewidth": 0.4})
    return Patch(facecolor=colour, edgecolor=EDGE, linewidth=0.4, label=text)
