"""Views of one steady orbit: phase portrait, penetration ε(t), contact force Pn(t) with yc(t).

The data is a ``PointResult`` of ``simulate_point(..., trace=True)`` (or any
object with its attributes): ``trace`` holds dense samples t, y, y', yc, ε, Pn
over the steady orbit (its period, n revolutions, or 64 revolutions when not
periodic), with t = 0 at cam angle θ = 0, its events (impacts,
detachments) and the cam phases of a revolution. Nothing is recomputed here.

Marks follow the paper (its Figs. 6 and 9): σn points (the stroboscopic section
at θ = 0) blue, detachment points (the section σp, ε crossing 0 downwards)
red; in force plots impacts are open circles and detachments stars; Pn is red
on the left axis and the cam input yc blue on the right one. Where the force
law's clamp holds Pn = 0 while ε > 0 (the follower ahead of the cam without
force: contact mode 2 of the trace, between a "force zero" event and the next
"force resumes" or detachment) the force plot shades the interval. Units: y, yc,
ε in strokes h, ẏ in h·ωn, Pn in K1·h, t in 1/ωn (dimensionless, θ = ω t).
"""

import dataclasses
import math

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from .requests import PlotError
from .style import (
    EPS_LABEL,
    PN_LABEL,
    T_LABEL,
    V_LABEL,
    Y_LABEL,
    YC_LABEL,
    figure_style,
    new_figure,
    parameter_text,
)

SECTION_COLOUR = "#1f5fbf"  # σn points (blue, as in the paper)
DETACH_COLOUR = "#d62728"  # σp points, detachment instants (red)
FORCE_COLOUR = "#d62728"  # Pn(t): red, left axis (the paper's Fig. 9)
CAM_COLOUR = "#1f5fbf"  # yc(t): blue, right axis
ORBIT_COLOUR = "0.15"
PHASE_SHADE = "0.93"  # background of the cam's rise and fall (the dwells stay white)
CLAMP_SHADE = "#f6c27a"  # where the clamp holds Pn = 0 while ε > 0 (contact mode 2)
CLAMPED = 2  # the trace's contact mode "in contact without force"

# The cam phases come with the trace (``trace.cam_phases``: name, start and end angle θ,
# as the model defines them); these are drawn on PHASE_SHADE.
SHADED_PHASES = ("rise", "fall")
PHASE_ABBREVIATIONS = {"rise": "R", "far dwell": "FD", "fall": "F", "near dwell": "ND"}

MAX_NAMED_REVOLUTIONS = 3  # more revolutions on one axis leave no room for phase names
TIME_REVOLUTIONS = 6  # time panels of plot_orbit show at most the last 6 revolutions
TRACE_SAMPLES = ("t", "y", "v", "yc", "eps", "pn", "contact")

ORBIT_PARAMETERS = ("omega", "f0", "mu_kn", "mu_cn", "zeta")


def trace_of(result):
    """The orbit trace of a result; PlotError if it was simulated without one."""
    trace = getattr(result, "trace", None)
    if trace is None:
        raise PlotError(
            "this result has no orbit trace: simulate it with trace=True (a failed cell has none)"
        )
    return trace


def orbit_title(result, *, parameters=ORBIT_PARAMETERS) -> str:
    """ "2-2 (periodic), ω = 3, μkn = 0.91, …, clamp" in the field's notation."""
    par = result.parameters
    text = parameter_text({name: par[name] for name in parameters if name in par})
    law = "no tensile force" if par.get("tensile", "clamp") == "clamp" else "tensile allowed"
    return f"{result.label}   {text},  {law}"


def revolution_bounds(trace) -> tuple[float, int]:
    """(revolution period 2π/ω, number of whole revolutions the trace spans)."""
    period = float(trace.period)
    return period, max(1, round((trace.t[-1] - trace.t[0]) / period))


def shade_cam_phases(ax, trace, *, names: bool = False) -> None:
    """Grey bands where the cam rises or falls; with ``names``, the phases of the first
    revolution written above the axes (abbreviated R, FD, F, ND when it spans several)."""
    period, revolutions = revolution_bounds(trace)
    scale = period / (2 * math.pi)
    start = trace.t[0]  # at θ = 0
    for k in range(revolutions):
        for name, a, b in trace.cam_phases:
            t0 = start + (2 * math.pi * k + a) * scale
            t1 = start + (2 * math.pi * k + b) * scale
            if name in SHADED_PHASES:
                ax.axvspan(t0, t1, color=PHASE_SHADE, lw=0, zorder=0)
            if names and k == 0 and revolutions <= MAX_NAMED_REVOLUTIONS:
                text = name if revolutions == 1 else PHASE_ABBREVIATIONS[name]
                ax.text(
                    0.5 * (t0 + t1),
                    1.0,
                    text,
                    transform=ax.get_xaxis_transform(),
                    ha="center",
                    va="bottom",
                    fontsize=6.5,
                    color="0.4",
                )
    for k in range(revolutions + 1):
        ax.axvline(start + k * period, color="0.6", lw=0.5, ls=":", zorder=0.5)


def plot_phase(result, ax=None, *, legend: bool = True, title: str | None = None):
    """Phase portrait (y, y') of the steady orbit with σn and σp (detachment) points."""
    trace = trace_of(result)
    with figure_style():
        if ax is None:
            ax = new_figure(3.2, 2.8).add_subplot()
        ax.plot(trace.y, trace.v, color=ORBIT_COLOUR, lw=0.7, zorder=2)
        sections = np.asarray(result.sections).reshape(-1, 2)
        ax.plot(
            sections[:, 0],
            sections[:, 1],
            "o",
            ms=4.5,
            color=SECTION_COLOUR,
            mec="white",
            mew=0.5,
            zorder=4,
        )
        detach = trace.events_named("detachment")
        ax.plot(
            detach[:, 1],
            detach[:, 2],
            "o",
            ms=4.5,
            color=DETACH_COLOUR,
            mec="white",
            mew=0.5,
            zorder=5,
        )
        ax.set_xlabel(Y_LABEL)
        ax.set_ylabel(V_LABEL)
        if legend:
            ax.legend(handles=phase_legend(len(sections), len(detach)), loc="best")
        if title is not None:
            ax.set_title(title, loc="left")
    return ax.figure


def phase_legend(n_sections: int, n_detach: int) -> list:
    dot = dict(marker="o", ls="none", ms=4.5, mec="white", mew=0.5)
    return [
        Line2D([], [], color=SECTION_COLOUR, label=rf"$\sigma_n$ ({n_sections})", **dot),
        Line2D([], [], color=DETACH_COLOUR, label=rf"detachment $\sigma_p$ ({n_detach})", **dot),
    ]


def plot_gap(
    result,
    ax=None,
    *,
    colour=ORBIT_COLOUR,
    label=None,
    phases: bool = True,
    revolutions: int | None = None,
    marks: bool = True,
    last: int | None = None,
):
    """ε(t) over the steady orbit, ε = 0 dashed; detachments marked (red dots).

    ``revolutions``: repeat a periodic orbit to cover so many revolutions, so
    curves of different periods can share one axis. ``last``: show only the last
    so many revolutions of a longer trace.
    """
    trace = recent(trace_of(result), last)
    t, eps = repeated(trace, trace.eps, revolutions)
    with figure_style():
        if ax is None:
            ax = new_figure(3.6, 2.4).add_subplot()
        if phases:
            shade_cam_phases(ax, trace_span(trace, revolutions), names=True)
        ax.axhline(0.0, color="0.3", lw=0.6, ls="--", zorder=1)
        ax.plot(t, eps, color=colour, lw=0.9, label=label, zorder=3)
        if marks:
            detach = repeated_events(trace, "detachment", revolutions)
            ax.plot(detach, np.zeros_like(detach), "o", ms=3.2, color=DETACH_COLOUR, zorder=4)
        ax.set_xlim(t[0], t[-1])
        ax.set_xlabel(T_LABEL)
        ax.set_ylabel(EPS_LABEL)
    return ax.figure


def plot_force(
    result,
    ax=None,
    *,
    phases: bool = True,
    names: bool = True,
    right_label: bool = True,
    last: int | None = None,
):
    """Pn(t) (red, left axis) and yc(t) (blue, right axis) over the steady orbit,
    impacts as open circles and detachments as stars on the Pn curve (``last``: only the
    last so many revolutions). Returns the Figure; the right axis is ``ax.cam_axis``."""
    trace = recent(trace_of(result), last)
    with figure_style():
        if ax is None:
            ax = new_figure(3.6, 2.4).add_subplot()
        if phases:
            shade_cam_phases(ax, trace, names=names)
        for t0, t1 in clamped_intervals(trace):
            ax.axvspan(t0, t1, color=CLAMP_SHADE, alpha=0.55, lw=0, zorder=0.7)
        ax.plot(trace.t, trace.pn, color=FORCE_COLOUR, lw=0.9, zorder=3)
        ax.axhline(0.0, color="0.3", lw=0.5, zorder=1)
        impacts = trace.events_named("impact")[:, 0]
        detach = trace.events_named("detachment")[:, 0]
        ax.plot(
            impacts,
            np.zeros_like(impacts),
            "o",
            ms=4.5,
            mfc="white",
            mec="black",
            mew=0.8,
            zorder=5,
        )
        ax.plot(detach, np.zeros_like(detach), "*", ms=6.5, color="black", zorder=5)
        ax.set_xlim(trace.t[0], trace.t[-1])
        ax.set_xlabel(T_LABEL)
        ax.set_ylabel(PN_LABEL, color=FORCE_COLOUR)
        ax.tick_params(axis="y", colors=FORCE_COLOUR)
        cam = ax.twinx()
        cam.plot(trace.t, trace.yc, color=CAM_COLOUR, lw=0.9, zorder=2)
        cam.set_ylim(-0.05, 1.6)  # the cam input sits low, clear of the force peaks' labels
        cam.set_yticks([0.0, 0.5, 1.0])
        cam.tick_params(axis="y", colors=CAM_COLOUR)
        if right_label:
            cam.set_ylabel(YC_LABEL, color=CAM_COLOUR)
        ax.cam_axis = cam
    return ax.figure


def clamped_intervals(trace) -> list[tuple[float, float]]:
    """(t0, t1) of every interval in which the clamp holds Pn = 0 while ε > 0.

    From the trace's events: a "force zero" event (code 3: pushing → without force)
    opens one, the next "force resumes" (5) or detachment from that mode (4) closes
    it; a trace that starts (ends) in that mode opens (closes) one at its first
    (last) sample. Empty under the paper's literal law, where the force may pull.
    """
    intervals = []
    start = float(trace.t[0]) if len(trace.contact) and trace.contact[0] == CLAMPED else None
    for t, code in trace.events[:, [0, 3]]:
        if code == 3 and start is None:
            start = float(t)
        elif code in (4, 5) and start is not None:
            intervals.append((start, float(t)))
            start = None
    if start is not None:
        intervals.append((start, float(trace.t[-1])))
    return intervals


def force_legend(clamped: bool = False) -> list:
    """Legend of a force plot; ``clamped`` adds the shading of the clamp's intervals."""
    handles = [
        Line2D([], [], color=FORCE_COLOUR, lw=0.9, label=r"$P_n$"),
        Line2D([], [], color=CAM_COLOUR, lw=0.9, label=r"$y_c$"),
        Line2D([], [], marker="o", ls="none", mfc="white", mec="black", label="impact"),
        Line2D([], [], marker="*", ls="none", color="black", ms=6.5, label="detachment"),
    ]
    if clamped:
        handles.append(
            Patch(
                facecolor=CLAMP_SHADE,
                alpha=0.55,
                lw=0,
                label=r"clamp: $P_n = 0$ while $\varepsilon > 0$",
            )
        )
    return handles


def plot_orbit(result, *, title: str | None = None):
    """The steady orbit of one point: phase portrait (left), ε(t) and Pn(t) with yc(t)
    (right, sharing t). Returns a headless Figure."""
    trace_of(result)
    with figure_style():
        figure = new_figure(7.2, 3.9)
        grid = figure.add_gridspec(2, 2, width_ratios=[1.0, 1.35])
        phase = figure.add_subplot(grid[:, 0])
        gap = figure.add_subplot(grid[0, 1])
        force = figure.add_subplot(grid[1, 1], sharex=gap)
        plot_phase(result, phase)
        _, traced = revolution_bounds(result.trace)
        last = TIME_REVOLUTIONS if traced > TIME_REVOLUTIONS else None
        plot_gap(result, gap, last=last)
        plot_force(result, force, names=False, last=last)
        if last:
            gap.set_title(
                f"last {last} of {traced} revolutions traced", loc="right", fontsize=7, color="0.4"
            )
        gap.set_xlabel("")
        gap.tick_params(labelbottom=False)
        handles = force_legend(bool(clamped_intervals(force_trace(result, last))))
        figure.legend(handles=handles, loc="outside lower center", ncols=len(handles))
        for ax, letter in ((phase, "a"), (gap, "b"), (force, "c")):
            panel_letter(ax, letter)
        figure.suptitle(
            orbit_title(result) if title is None else title, x=0.01, ha="left", fontsize=9
        )
    return figure


def panel_letter(ax, letter: str) -> None:
    """ "(a)" at the top left corner, outside the axes, as journals set panel labels."""
    ax.text(
        -0.02,
        1.02,
        f"({letter})",
        transform=ax.transAxes,
        ha="right",
        va="bottom",
        fontsize=9,
        fontweight="bold",
    )


# -- parts of a trace ------------------------------------------------------------------


def force_trace(result, last: int | None = None):
    """The part of a result's trace a force plot draws (its last ``last`` revolutions)."""
    return recent(trace_of(result), last)


def recent(trace, revolutions: int | None):
    """The last ``revolutions`` whole revolutions of a trace (the trace itself if shorter)."""
    period, total = revolution_bounds(trace)
    if revolutions is None or total <= revolutions:
        return trace
    start = trace.t[0] + (total - revolutions) * period - 1e-9 * period
    keep = trace.t >= start
    fields = {name: getattr(trace, name)[keep] for name in TRACE_SAMPLES}
    events = trace.events[trace.events[:, 0] >= start]
    return dataclasses.replace(trace, events=events, **fields)


class _Span:
    """A trace's period, cam phases and time span, stretched to ``revolutions`` for shading."""

    def __init__(self, trace, revolutions):
        self.period = trace.period
        self.cam_phases = trace.cam_phases
        self.t = np.array([trace.t[0], trace.t[0] + revolutions * trace.period])


def trace_span(trace, revolutions):
    return trace if revolutions is None else _Span(trace, revolutions)


def repeated(trace, values, revolutions):
    """(t, values) of a periodic trace repeated to cover ``revolutions`` (None: as is)."""
    period, own = revolution_bounds(trace)
    if revolutions is None or revolutions <= own:
        return trace.t, values
    if revolutions % own:
        raise PlotError(f"cannot repeat a {own}-revolution orbit over {revolutions} revolutions")
    copies = revolutions // own
    t = np.concatenate([trace.t + k * own * period for k in range(copies)])
    return t, np.tile(values, copies)


def repeated_events(trace, name: str, revolutions) -> np.ndarray:
    times = trace.events_named(name)[:, 0]
    period, own = revolution_bounds(trace)
    if revolutions is None or revolutions <= own:
        return times
    return np.concatenate([times + k * own * period for k in range(revolutions // own)])
