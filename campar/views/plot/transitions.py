"""Transitions on a bifurcation diagram: a thin line at each boundary, and its type.

The data is the ``transitions`` of a ``campar.views.line.BifurcationLine``
(``campar.views.transitions.Transition``: ``omega`` and ``type``), computed
before; nothing is recomputed here. Boundaries of the types the paper names in
its Figs 2c–e and 5 (PD, SN, NS, G) and jumps are labelled; chaos boundaries and
unknown ones get the line only, since a chaotic band has many of them and its
cloud of σn points already shows it.
"""

from matplotlib.transforms import blended_transform_factory

LABELLED = ("PD", "SN", "NS", "G", "jump")
LINE_STYLE = {"color": "0.55", "linewidth": 0.4, "linestyle": (0, (2, 2)), "zorder": 0}
LABEL_SIZE = 6.0  # pt
LABEL_BOX = {"facecolor": "white", "edgecolor": "none", "alpha": 0.7, "pad": 0.3}
MIN_GAP = 0.02  # labels closer than this (axis fraction) alternate between top and bottom


def mark_transitions(ax, transitions) -> int:
    """Mark every transition on ``ax`` (ω on x); returns how many got a text label."""
    transform = blended_transform_factory(ax.transData, ax.transAxes)
    lo, hi = sorted(ax.get_xlim())
    span = hi - lo or 1.0
    last_x, at_top, labelled = None, True, 0
    for t in sorted(transitions, key=lambda t: t.omega):
        ax.axvline(t.omega, **LINE_STYLE)
        if t.type not in LABELLED:
            continue
        x = (t.omega - lo) / span
        at_top = not at_top if last_x is not None and x - last_x < MIN_GAP else True
        ax.text(
            t.omega,
            0.99 if at_top else 0.01,
            t.type,
            transform=transform,
            rotation=90,
            fontsize=LABEL_SIZE,
            ha="center",
            va="top" if at_top else "bottom",
            bbox=LABEL_BOX,
        )
        last_x = x
        labelled += 1
    return labelled
