"""Bifurcation curves on a map: the typed cell edges of ``campar.views.boundaries``.

Each boundary between neighbouring cells of different labels is one cell edge,
drawn where the figure draws it (between the cells' centres' midpoints), coloured
and dashed by its type, with a legend in the paper's names (its Figs 2c–e, 4c–e:
PD, SN, NS — the paper's "Hopf" point —, G, plus chaos and jump). Edges typed
unknown are not drawn (the colour change of the map shows them) but counted in
the legend. Every line has a thin white halo so that it reads over any label
colour, dark chaos included.

The data is computed before (``find_boundaries``/``store_boundaries``): anything
with ``segments`` whose items have ``type`` and ``edge`` (x0, y0, x1, y1) in (ω,
second) coordinates, and optionally ``notes``; nothing here recomputes or imports
the kernel.
"""

from matplotlib.collections import LineCollection
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.patheffects import withStroke

# type → (legend text, colour, line style, width in pt); drawn in this order, so the
# rarer and more telling types lie on top.
CURVE_STYLES = {
    "chaos": ("chaos (onset or end)", "#111111", "solid", 0.9),
    "jump": ("jump (both sides stable)", "#ff7f00", (0, (4, 1.5)), 1.0),
    "G": ("G grazing", "#00a651", (0, (1.2, 1.0)), 1.3),
    "SN": ("SN saddle-node (fold)", "#1f3fff", (0, (3, 1.2)), 1.2),
    "PD": ("PD period doubling", "#e8000b", "solid", 1.2),
    "NS": ("NS Neimark–Sacker (Hopf)", "#d600d6", "solid", 1.6),
}
LEGEND_ORDER = ("PD", "SN", "NS", "G", "chaos", "jump")  # the paper's first
UNDRAWN = "unknown"
HALO = "white"
HALO_WIDTH = 1.2  # pt added around each line


def curve_segments(found, kind: str) -> list:
    """[((x0, y0), (x1, y1)), …] of the segments of one type."""
    return [
        ((s.edge[0], s.edge[1]), (s.edge[2], s.edge[3])) for s in found.segments if s.type == kind
    ]


def draw_curves(ax, found, *, legend: bool = True) -> dict[str, int]:
    """Draw the typed edges of ``found`` on ``ax``; returns the segments drawn per type.

    The legend (types met, with their edge counts; the unknown ones and the notes of
    ``found`` as text lines) goes under the axes, so it never covers the map's own.
    """
    drawn, lines_of = {}, {}
    for kind, (text, colour, style, width) in CURVE_STYLES.items():
        lines = curve_segments(found, kind)
        if not lines:
            continue
        ax.add_collection(
            LineCollection(
                lines,
                colors=colour,
                linestyles=style,
                linewidths=width,
                zorder=3.0,
                capstyle="butt",
                path_effects=[withStroke(linewidth=width + HALO_WIDTH, foreground=HALO)],
            )
        )
        drawn[kind] = len(lines)
        lines_of[kind] = Line2D(
            [],
            [],
            color=colour,
            linestyle=style,
            linewidth=width,
            label=f"{text} ({len(lines)})",
            path_effects=[withStroke(linewidth=width + HALO_WIDTH, foreground=HALO)],
        )
    handles = [lines_of[kind] for kind in LEGEND_ORDER if kind in lines_of]
    unknown = sum(1 for s in found.segments if s.type == UNDRAWN)
    if legend:
        extra = [f"unknown ({unknown}), not drawn"] if unknown else []
        extra += list(getattr(found, "notes", ()))
        handles += [Patch(facecolor="none", edgecolor="none", label=wrap(t)) for t in extra]
        if not drawn and not extra:
            handles.append(
                Patch(facecolor="none", edgecolor="none", label="no boundary between labels")
            )
        if ax.get_legend() is not None:  # keep the map's own legend beside this one
            ax.add_artist(ax.get_legend())
        box = ax.legend(
            handles=handles,
            title="bifurcations (cell edges)",
            loc="upper left",
            bbox_to_anchor=(0.0, -0.16),
            ncols=1,
            handlelength=2.4,
            alignment="left",
        )
        box.set_zorder(4.0)
    return drawn


def wrap(text: str, width: int = 70) -> str:
    """A long note on several lines, broken at spaces."""
    lines, line = [], ""
    for word in text.split():
        if line and len(line) + 1 + len(word) > width:
            lines.append(line)
            line = word
        else:
            line = f"{line} {word}".strip()
    return "\n".join([*lines, line])
