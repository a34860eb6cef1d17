"""Continuation results: branches of periodic orbits and two-parameter bifurcation curves.

``plot_branches`` draws a branch and the branches switched from it (a
``campar.continuation.branch.Branch``, computed before) in the paper's style: the y of
each of an n-cycle's section points against the parameter, stable stretches solid,
unstable ones dashed, each special point marked with its type (PD, SN, BP, NS, G); over
the brute-force bifurcation diagram of the same line (``campar.views.line``) in grey
when one is given, so where the simulation's σn points leave a branch shows at once.
``draw_bifurcation_curves`` draws curves (``campar.continuation.curves``) on a plane's
axes: over a map, or alone (``plot_bifurcation_curves``).
"""

import numpy as np
from matplotlib.lines import Line2D

from .style import axis_label, figure_style, new_figure, parameter_text

# One colour per period, in the order periods appear (1, 2, 4, 8, …, then others).
PERIOD_COLOURS = ("#1f4e9c", "#c2410c", "#15803d", "#7e22ce", "#b91c1c", "#0e7490", "#a16207")
MARKERS = {"PD": "o", "SN": "s", "BP": "D", "NS": "^", "G": "v"}
CURVE_STYLES = {
    "PD": {"color": "#b91c1c", "linestyle": "-"},
    "SN": {"color": "#1d4ed8", "linestyle": "-"},
    "NS": {"color": "#7e22ce", "linestyle": "-."},
    "G": {"color": "#15803d", "linestyle": "--"},
}
LINE_GREY = "0.72"


def period_colour(n: int, periods: list[int]) -> str:
    if n not in periods:
        periods.append(n)
    return PERIOD_COLOURS[periods.index(n) % len(PERIOD_COLOURS)]


def stretches(stable: np.ndarray):
    """(start, stop, stable) of the runs of equal stability, overlapping by one point so
    the drawn pieces join."""
    start = 0
    for i in range(1, len(stable) + 1):
        if i == len(stable) or stable[i] != stable[start]:
            yield start, min(i + 1, len(stable)), bool(stable[start])
            start = i


def draw_branch(ax, branch, colour: str) -> None:
    """Every section point's y along the branch, solid where stable, dashed where not."""
    for start, stop, stable in stretches(branch.stable):
        for k in range(branch.n):
            ax.plot(
                branch.values[start:stop],
                branch.sections[start:stop, k, 0],
                color=colour,
                linewidth=1.0 if stable else 0.8,
                linestyle="-" if stable else (0, (3, 2)),
                zorder=3,
            )


def draw_special_points(ax, branch, colour: str) -> None:
    for sp in branch.special:
        ax.plot(
            [sp.value],
            [sp.state[0]],
            marker=MARKERS.get(sp.type, "x"),
            markersize=4.5,
            markerfacecolor="white",
            markeredgecolor=colour,
            markeredgewidth=1.0,
            linestyle="none",
            zorder=5,
        )
        ax.annotate(
            sp.type,
            (sp.value, sp.state[0]),
            xytext=(3, 4),
            textcoords="offset points",
            fontsize=6.5,
            color=colour,
            zorder=6,
        )


def plot_branches(roots, *, line=None, ax=None, title: str | None = None):
    """The branch ``roots`` (one Branch or a list) and every branch switched from each
    (``Branch.walk``), over the σn points of ``line`` (a ``BifurcationLine`` of the same
    parameters) if given."""
    roots = roots if isinstance(roots, (list, tuple)) else [roots]
    branches = [branch for root in roots for branch in root.walk()]
    with figure_style():
        if ax is None:
            ax = new_figure(5.6, 3.8).add_subplot()
        if line is not None:
            omega = np.broadcast_to(np.asarray(line.omega)[:, None], line.sections.shape[:2])
            y = np.asarray(line.sections)[:, :, 0]
            keep = np.isfinite(y)
            ax.scatter(omega[keep], y[keep], s=0.8, c=LINE_GREY, lw=0, rasterized=True, zorder=1)
        periods: list[int] = []
        for branch in sorted(branches, key=lambda b: b.n):
            colour = period_colour(branch.n, periods)
            draw_branch(ax, branch, colour)
            draw_special_points(ax, branch, colour)
        ax.set_xlabel(axis_label(roots[0].parameter))
        ax.set_ylabel(r"$\sigma_n$: $y$ at $\theta = 0$ (units of $h$)")
        handles = [
            Line2D([], [], color="black", linewidth=1.0, label="stable"),
            Line2D([], [], color="black", linewidth=0.8, linestyle=(0, (3, 2)), label="unstable"),
        ]
        handles += [
            Line2D([], [], color=period_colour(n, periods), linewidth=1.0, label=f"period {n}")
            for n in periods
        ]
        types = sorted({sp.type for b in branches for sp in b.special})
        handles += [
            Line2D(
                [],
                [],
                marker=MARKERS.get(t, "x"),
                markerfacecolor="white",
                markeredgecolor="black",
                linestyle="none",
                label=t,
            )
            for t in types
        ]
        if line is not None:
            handles.append(
                Line2D(
                    [], [], marker=".", color=LINE_GREY, linestyle="none", label="simulation (σn)"
                )
            )
        ax.legend(handles=handles, loc="best", fontsize=6.5, ncols=2)
        ax.set_title(parameter_text(roots[0].parameters) if title is None else title, loc="left")
    return ax.figure


def draw_bifurcation_curves(ax, curves, *, legend: bool = True) -> dict[str, int]:
    """Draw each curve in its type's style on axes whose x is the curves' first parameter
    and y their second; returns how many curves of each type were drawn."""
    counts: dict[str, int] = {}
    for curve in curves:
        style = CURVE_STYLES.get(curve.type, {"color": "black", "linestyle": ":"})
        ax.plot(curve.values[:, 0], curve.values[:, 1], linewidth=1.1, zorder=4, **style)
        counts[curve.type] = counts.get(curve.type, 0) + 1
    if legend and counts:
        handles = [
            Line2D([], [], linewidth=1.1, label=f"{t} ({counts[t]})", **CURVE_STYLES[t])
            for t in CURVE_STYLES
            if t in counts
        ]
        ax.legend(handles=handles, loc="upper left", fontsize=6.5, title="continued curves")
    return counts


def plot_bifurcation_curves(curves, *, window=None, title: str | None = None):
    """Curves alone in their plane (the first curve's parameters on the axes)."""
    with figure_style():
        ax = new_figure(5.0, 3.8).add_subplot()
        draw_bifurcation_curves(ax, curves)
        if curves:
            ax.set_xlabel(axis_label(curves[0].first))
            ax.set_ylabel(axis_label(curves[0].second))
            if title is None:
                title = parameter_text(curves[0].parameters)
        if window is not None:
            ax.set_xlim(*sorted(window[0]))
            ax.set_ylim(*sorted(window[1]))
        ax.set_title(title or "", loc="left")
    return ax.figure
