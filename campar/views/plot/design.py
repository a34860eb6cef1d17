"""The cam designer's figure: separation speed against a design parameter, one line per
cam (or contact) law, and the largest contact force held below it.

Draws ``campar.views.separation.SeparationCurve`` records computed before (stores of
jobs with the ``separation`` output); nothing here recomputes or imports the kernel.
"""

from .style import axis_label, figure_style, new_figure

MARKERS = ("o", "s", "^", "D", "v", "P", "X")


def plot_separation(curves, *, title: str | None = None):
    """Two panels over the curves' common second parameter: the separation speed ω_s, and
    the largest contact force below it."""
    parameters = {c.parameter for c in curves}
    if len(parameters) != 1:
        raise ValueError(f"the stores sweep different second parameters: {sorted(parameters)}")
    parameter = parameters.pop()
    with figure_style():
        figure = new_figure(6.6, 2.8)
        speed_ax, force_ax = figure.subplots(1, 2)
        for i, c in enumerate(curves):
            style = dict(
                marker=MARKERS[i % len(MARKERS)], markersize=2.5, linewidth=1.0, label=c.label
            )
            speed_ax.plot(c.values, c.speed, **style)
            force_ax.plot(c.values, c.pn_max, **style)
        speed_ax.set_xlabel(axis_label(parameter))
        force_ax.set_xlabel(axis_label(parameter))
        speed_ax.set_ylabel(r"separation speed $\omega_s$ (units of $\omega_n$)")
        force_ax.set_ylabel(r"largest $P_n$ below $\omega_s$ (units of $K_1 h$)")
        speed_ax.legend(loc="best")
        if title:
            figure.suptitle(title)
    return figure
