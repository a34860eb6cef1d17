"""Composite figures in the layout of the paper: several orbits side by side.

- ``plot_phase_grid``: phase portraits with σn and detachment points, plus
  Poincaré sections of the non-periodic ones (the paper's Fig. 6);
- ``plot_gap_family``: ε(t) at several cam speeds, one curve per value of a
  parameter (Figs. 3 and 8);
- ``plot_force_row``: Pn(t) with yc(t), impacts and detachments, the clamp's
  intervals of Pn = 0 while ε > 0 shaded (Fig. 9).

Inputs are results with orbit traces (``simulate_point(..., trace=True)``);
nothing is computed here. Each panel states what campar found (its n-p
label), and, where the paper claims a label, the paper's too.
"""

import numpy as np
from matplotlib import colormaps

from .orbit import (
    SECTION_COLOUR,
    clamped_intervals,
    force_legend,
    phase_legend,
    plot_force,
    plot_gap,
    plot_phase,
)
from .style import SYMBOLS, V_LABEL, Y_LABEL, figure_style, new_figure

LETTERS = "abcdefghijklmnopqrstuvwxyz"


def family_colours(count: int) -> list:
    """Distinct, ordered colours for a parameter's values (low → high: light → dark)."""
    cmap = colormaps["viridis"]
    return [cmap(x) for x in np.linspace(0.85, 0.05, count)] if count > 1 else [cmap(0.3)]


def plot_phase_grid(panels, *, columns: int = 4, title: str | None = None):
    """Phase portraits and section clouds in a grid.

    panels: dicts with ``result`` (with trace), ``kind`` ("phase" or "section"),
    ``heading`` (the panel's title, up to two lines) and, for "section", ``cloud``
    ((m, 2) σn points).
    """
    rows = -(-len(panels) // columns)
    with figure_style():
        figure = new_figure(2.05 * columns, 2.25 * rows + 0.4)
        axes = figure.subplots(rows, columns, squeeze=False).ravel()
        for i, (ax, panel) in enumerate(zip(axes, panels, strict=False)):
            if panel["kind"] == "phase":
                plot_phase(panel["result"], ax, legend=False)
            else:
                draw_cloud(ax, panel["cloud"])
            ax.set_title(f"({LETTERS[i]}) {panel['heading']}", loc="left", fontsize=7.5)
            ax.xaxis.label.set_size(8)
            ax.yaxis.label.set_size(8)
        for ax in axes[len(panels) :]:
            ax.set_visible(False)
        figure.legend(handles=phase_legend_entries(), loc="outside lower center", ncols=3)
        if title:
            figure.suptitle(title, x=0.01, ha="left", fontsize=9)
    return figure


def phase_legend_entries():
    handles = phase_legend(0, 0)
    handles[0].set_label(r"$\sigma_n$ points (period $n$)")
    handles[1].set_label(r"detachment points $\sigma_p$ ($p$)")
    return handles


def draw_cloud(ax, cloud) -> None:
    """σn points of a long run (a Poincaré section), small when many."""
    cloud = np.asarray(cloud).reshape(-1, 2)
    size = 4.5 if len(cloud) <= 64 else 1.2
    ax.plot(cloud[:, 0], cloud[:, 1], "o", ms=size, color=SECTION_COLOUR, mew=0, ls="none")
    ax.set_xlabel(Y_LABEL)
    ax.set_ylabel(V_LABEL)
    ax.margins(0.15)


def plot_gap_family(rows, *, title: str | None = None):
    """ε(t) panels: one row per varied parameter, one column per cam speed.

    rows: list of (name, values, results) where ``results[j][i]`` is the orbit at
    speed j for value i of parameter ``name`` ("f0", "mu_kn", "mu_cn"). Each row has
    one legend of the values (light to dark); each panel's title lists the n-p
    labels campar found, in the same order.
    """
    columns = len(rows[0][2])
    with figure_style():
        figure = new_figure(2.3 * columns + 1.0, 2.05 * len(rows) + 0.3)
        axes = figure.subplots(len(rows), columns, squeeze=False)
        k = 0
        for r, (name, values, by_speed) in enumerate(rows):
            colours = family_colours(len(values))
            for j, results in enumerate(by_speed):
                ax = axes[r, j]
                revolutions = common_revolutions(results)
                for i, (value, result) in enumerate(zip(values, results, strict=True)):
                    plot_gap(
                        result,
                        ax,
                        colour=colours[i],
                        label=f"{SYMBOLS[name]} = {value:g}",
                        phases=i == 0,
                        revolutions=revolutions,
                        marks=False,
                    )
                omega = results[0].parameters["omega"]
                labels = ", ".join(result.label for result in results)
                ax.set_title(
                    f"({LETTERS[k]}) {SYMBOLS['omega']} = {omega:g}:  {labels}",
                    loc="left",
                    pad=11,
                    fontsize=8,
                )
                if j:
                    ax.set_ylabel("")
                k += 1
            axes[r, -1].legend(loc="center left", bbox_to_anchor=(1.03, 0.5))
        if title:
            figure.suptitle(title, x=0.01, ha="left", fontsize=9)
    return figure


def common_revolutions(results, cap: int = 4):
    """Revolutions on which all (periodic) orbits line up, or None (each drawn as traced)."""
    periods = [int(r.n) for r in results]
    if min(periods) < 1:
        return None
    total = int(np.lcm.reduce(periods))
    return total if total <= cap else None


def plot_force_row(results, *, title: str | None = None):
    """Pn(t) with yc(t) for several orbits side by side (the paper's Fig. 9); where the
    clamp holds Pn = 0 while ε > 0 the interval is shaded (said in the legend)."""
    with figure_style():
        figure = new_figure(2.6 * len(results), 2.5)
        axes = figure.subplots(1, len(results), squeeze=False)[0]
        for i, (ax, result) in enumerate(zip(axes, results, strict=True)):
            plot_force(result, ax, right_label=i == len(results) - 1)
            if i:
                ax.set_ylabel("")
            omega = result.parameters["omega"]
            ax.set_title(
                f"({LETTERS[i]}) {SYMBOLS['omega']} = {omega:g}: {result.label}", loc="left", pad=11
            )
        clamped = any(clamped_intervals(result.trace) for result in results)
        handles = force_legend(clamped)
        figure.legend(handles=handles, loc="outside lower center", ncols=len(handles))
        if title:
            figure.suptitle(title, x=0.01, ha="left", fontsize=9)
    return figure
