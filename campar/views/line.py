"""Single-parameter bifurcation lines: σn points and detachments along ω by continuation.

A line is one continuation chain of the kernel: ω decreasing from its largest
value, each cell warm-started from the previous cell's final state, exactly
as one row of a two-parameter map (the paper's Fig. 5 is such a row, drawn as
σn points y against ω with the detachment count p beneath). It is computed
from a Model by ``campar.model.compute.run_cells``, the chain a map's row runs,
so a line and the map row with the same model give the same cells.

Every line also computes the Floquet multipliers of its periodic cells (the
kernel integrates the variational equations in the transient anyway, so they
cost one 2×2 eigenvalue problem a cell) and ε's extremes, from which
``campar.views.transitions`` types each boundary between labels (PD, SN, NS,
G, chaos, jump); ``compute_line`` attaches them as ``transitions``.

``continued_state`` uses a line to reach one ω the way the paper's maps reach
it (continuation from ω = 6.0), which is what the paper's point claims and
phase portraits refer to; ``simulate_point`` started from that state then
traces the same attractor.
"""

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..core.codes import Kind, cell_label
from ..errors import JobError
from ..model import Model
from ..model.sections import DEFAULT_CLASSIFY

PAPER_START = 6.0  # ω where the paper's continuations start (docs/model.md, sweeps)
CONTINUATION_STEP = 0.005  # ω step of ``continued_state``: a third of the paper's map step
DEFAULT_SECTIONS = 64  # σn points kept per non-periodic cell (periodic ones keep n)
DEFAULT_POINTS = 2000  # ω values of a line (campar line, campar.line)
LINE_OUTPUTS = ("label", "dc", "eps", "sections", "multipliers")


@dataclass(frozen=True)
class BifurcationLine:
    """Cells of one continuation chain, in the order computed (ω decreasing).

    Shapes: N = number of ω values, S = σn points stored per cell.

    Parameters
    ----------
    omega : numpy.ndarray
        (N,) cam speeds, decreasing.
    sections : numpy.ndarray
        (N, S, 2) σn points (y, y'), NaN-padded.
    n, p, kind : numpy.ndarray
        (N,) period, detachments and ``campar.core.codes.Kind`` code of every cell.
    dc : numpy.ndarray
        (N,) duty cycle.
    state : numpy.ndarray
        (N, 2) final (y, y') at θ = 0 of each cell.
    parameters : dict
        f0, μkn, μcn, ζ (floats), ``tensile``, ``duty_cycle`` and ``cam_velocity``.
    chatter_p, window : int
        p from which a label is chattering; the read window in revolutions.
    multipliers : numpy.ndarray or None
        (N, 2, 2): (re, im) of both Floquet multipliers; NaN where not periodic.
    flags : numpy.ndarray or None
        (N,) ``campar.core.codes.Flag`` bits.
    eps_min, eps_max : numpy.ndarray or None
        (N,) extremes of ε over the steady window.
    transitions : tuple of Transition
        The typed boundaries between labels (:func:`find_transitions`).
    model : Model or None
        The line's model (its ω: the line's first).

    Examples
    --------
    >>> from campar.views.line import bifurcation_line
    >>> line = bifurcation_line((2.0, 4.0), 50, mu_kn=0.91)
    >>> [label for label, first, last in line.runs()]
    ['2-1', '2-2', '1-1']
    """

    omega: np.ndarray  # (N,) cam speed, decreasing
    sections: np.ndarray  # (N, S, 2) σn points (y, y'), NaN-padded
    n: np.ndarray  # (N,) period in revolutions; 0 if not periodic
    p: np.ndarray  # (N,) detachments in n revolutions (non-periodic: in the read window)
    kind: np.ndarray  # (N,) campar.core.codes.Kind codes
    dc: np.ndarray  # (N,) duty cycle
    state: np.ndarray  # (N, 2) final (y, y') at θ = 0 of each cell
    parameters: dict  # f0, mu_kn, mu_cn, zeta (floats); tensile, duty_cycle, cam_velocity
    chatter_p: int = DEFAULT_CLASSIFY.chatter_p
    window: int = DEFAULT_CLASSIFY.window_revolutions  # read window (p of non-periodic cells)
    multipliers: np.ndarray | None = None  # (N, 2, 2) (re, im) of both; NaN if not periodic
    flags: np.ndarray | None = None  # (N,) campar.core.codes.Flag bits
    eps_min: np.ndarray | None = None  # (N,) min ε over the steady window (< 0: detached)
    eps_max: np.ndarray | None = None  # (N,) max ε (intrusion depth)
    transitions: tuple = ()  # campar.views.transitions.Transition per label boundary
    model: Model | None = field(default=None, repr=False, compare=False)  # the line's model

    @property
    def labels(self) -> list[str]:
        """n-p label of every cell ("2-2", "1-9~", "QP", "chaos", …)."""
        return [
            cell_label(Kind(int(k)), int(n), int(p), self.chatter_p)
            for k, n, p in zip(self.kind, self.n, self.p, strict=True)
        ]

    def runs(self) -> list[tuple[str, float, float]]:
        """Consecutive cells with one label: (label, first ω, last ω), in ω order computed."""
        out = []
        for label, w in zip(self.labels, self.omega, strict=True):
            if out and out[-1][0] == label:
                out[-1] = (label, out[-1][1], float(w))
            else:
                out.append((label, float(w), float(w)))
        return out

    def to_npz(self, path) -> None:
        """Save every array (and the parameters as 0-d entries) in one .npz file."""
        optional = {
            name: getattr(self, name)
            for name in ("multipliers", "flags", "eps_min", "eps_max")
            if getattr(self, name) is not None
        }
        np.savez_compressed(
            path,
            omega=self.omega,
            sections=self.sections,
            n=self.n,
            p=self.p,
            kind=self.kind,
            dc=self.dc,
            state=self.state,
            **optional,
            **{k: np.array(v) for k, v in self.parameters.items()},
        )

    def to_dict(self) -> dict:
        """JSON-ready summary: parameters, ω range, runs of labels and transitions."""
        return {
            "parameters": self.parameters,
            "cells": len(self.omega),
            "omega": [float(self.omega[0]), float(self.omega[-1])],
            "runs": [{"label": label, "from": a, "to": b} for label, a, b in self.runs()],
            "transitions": [t.to_dict() for t in self.transitions],
        }


@dataclass(frozen=True)
class LineSpec:
    """What a line computes: the model (its ω the line's first) and the ω values, in the
    order the chain runs (decreasing)."""

    model: Model
    omega: np.ndarray
    name: str = "line"

    def to_dict(self) -> dict:
        """The line as a mapping: its name, ω range and points, and its model's keys."""
        omega = {"from": float(self.omega[0]), "to": float(self.omega[-1])}
        return {
            "name": self.name,
            "omega": {**omega, "points": len(self.omega)},
            **self.model.to_dict(),
        }


def omega_range(omega, points: int) -> tuple[float, float]:
    """(larger, smaller) of a line's ω range: two finite numbers, different unless one point
    (JobError otherwise; NaN would pass max and min unnoticed)."""
    try:
        a, b = (float(value) for value in omega)
    except (TypeError, ValueError):
        raise JobError(f"omega: expected a range (A, B) of two numbers, got {omega!r}") from None
    if not (math.isfinite(a) and math.isfinite(b)):
        raise JobError(f"omega: expected two finite numbers, got {omega!r}")
    if a == b and points > 1:
        raise JobError(f"omega: expected A != B for {points} points, got {omega!r}")
    return max(a, b), min(a, b)


def line_spec(
    omega: tuple[float, float], points: int, model=None, *, name: str = "line", **fields
) -> LineSpec:
    """The line of ``points`` ω values from max(omega) down to min(omega).

    Parameters
    ----------
    omega : tuple of float
        The ω range, either order; the chain runs from the larger value down.
    points : int
        Number of ω values (1 to MAX_POINTS).
    model : Model or mapping, optional
        The line's model; ``fields`` change it (any key ``Model.build`` takes: ``f0``,
        ``mu_kn``, ``tensile``, ``rise``, ``rtol``, ``transient``, ``revolutions``,
        ``y0``, ``v0`` for the first cell's start, …). ``sections``, the σn points kept
        per non-periodic cell, defaults to DEFAULT_SECTIONS.
    name : str
        The line's name.
    **fields
        Keys of the model by name or dotted key (``Model.build``), changing ``model``.

    Returns
    -------
    LineSpec

    Raises
    ------
    campar.errors.JobError
        A key unknown or a value out of range.

    Examples
    --------
    >>> from campar.views.line import line_spec
    >>> spec = line_spec((2.0, 4.0), 50, mu_kn=0.91)
    >>> float(spec.omega[0]), float(spec.omega[-1]), spec.model.mu_kn
    (4.0, 2.0, 0.91)
    """
    from ..model.settings import MAX_POINTS, check_count

    try:
        check_count("points", points, 1, MAX_POINTS)
    except ValueError as exc:
        raise JobError(str(exc)) from None
    hi, lo = omega_range(omega, points)
    if "initial" in fields:  # the start as a pair (y, y')
        fields["y0"], fields["v0"] = fields.pop("initial")
    base = Model.build(model, omega=hi, **fields)
    if base.classify.sections is None:
        base = base.replace(sections=DEFAULT_SECTIONS)
    Model.build(base, omega=lo)  # both ends in range
    return LineSpec(base, np.linspace(hi, lo, points), name)


def compute_line(spec: LineSpec, *, transitions: bool = True) -> BifurcationLine:
    """Run the chain of a line (``line_spec``) and collect its cells.

    Parameters
    ----------
    spec : LineSpec
        The line's model and ω values (:func:`line_spec`).
    transitions : bool
        Type the line's label boundaries (:func:`campar.views.transitions.find_transitions`).

    Returns
    -------
    BifurcationLine
        The line's cells in the order computed.

    Examples
    --------
    >>> from campar.views.line import compute_line, line_spec
    >>> line = compute_line(line_spec((2.0, 4.0), 50, mu_kn=0.91))
    >>> [(t.type, t.before.label, t.after.label) for t in line.transitions]
    [('G', '2-1', '2-2'), ('PD', '2-2', '1-1')]
    """
    from ..model.compute import run_cells  # numba loads here: the CLI reads this module's defaults
    from .transitions import find_transitions

    model = spec.model
    out = run_cells(model, omega=spec.omega, outputs=LINE_OUTPUTS)
    parameters = {name: float(getattr(model, name)) for name in ("f0", "mu_kn", "mu_cn", "zeta")}
    options = model.model
    parameters.update(
        tensile=options.tensile, duty_cycle=options.duty_cycle, cam_velocity=options.cam_velocity
    )
    line = BifurcationLine(
        omega=spec.omega,
        sections=out.sections,
        n=out.n,
        p=out.p,
        kind=out.kind,
        dc=out.dc,
        state=out.state,
        parameters=parameters,
        chatter_p=model.classify.chatter_p,
        window=model.classify.window_revolutions,
        multipliers=out.multipliers,
        flags=out.flags,
        eps_min=out.eps_min,
        eps_max=out.eps_max,
        model=model,
    )
    return replace(line, transitions=find_transitions(line)) if transitions else line


def bifurcation_line(omega: tuple[float, float], points: int, **options) -> BifurcationLine:
    """A bifurcation line along ω with its typed transitions.

    ``compute_line(line_spec(omega, points, **options))``.

    Parameters
    ----------
    omega : tuple of float
        The ω range; the chain runs from the larger value down.
    points : int
        Number of ω values.
    **options
        The keywords of :func:`line_spec` (a ``model`` and any of its keys).

    Returns
    -------
    BifurcationLine
        The line's cells, labels and transitions.

    Raises
    ------
    campar.errors.JobError
        A parameter unknown or out of range.

    Examples
    --------
    >>> from campar.views.line import bifurcation_line
    >>> line = bifurcation_line((2.0, 4.0), 50, mu_kn=0.91)
    >>> len(line.omega), line.labels[0], line.labels[-1]
    (50, '2-1', '1-1')
    """
    return compute_line(line_spec(omega, points, **options))


def continuation_points(
    omega: float, start: float = PAPER_START, step: float = CONTINUATION_STEP
) -> int:
    """Cells of a chain from ``start`` down to ``omega`` with spacing at most ``step``."""
    return max(2, math.ceil(abs(start - omega) / step) + 1)


def continued_state(
    omega: float, *, start: float = PAPER_START, step: float = CONTINUATION_STEP, **options
) -> tuple[BifurcationLine, tuple[float, float]]:
    """Reach ``omega`` by continuation from ``start`` (ω decreasing, from (0, 0) at θ = 0).

    Returns the line and the last cell's final state: the attractor the paper's
    procedure lands on at this ω. ``options`` as for ``line_spec`` (sections 1).
    """
    options.setdefault("sections", 1)
    line = bifurcation_line((start, omega), continuation_points(omega, start, step), **options)
    return line, (float(line.state[-1, 0]), float(line.state[-1, 1]))


def compute_lines(specs: list[LineSpec], threads: int = 2) -> list[BifurcationLine]:
    """Several lines at once: the kernel releases the GIL, so threads use the cores."""
    if len(specs) == 1 or threads <= 1:
        return [compute_line(spec) for spec in specs]
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(min(threads, len(specs))) as pool:
        return list(pool.map(compute_line, specs))


def varied_parameters(values: dict[str, list[float]]) -> list[dict[str, float]]:
    """Parameter sets of the lines to draw: at most one parameter may list several values."""
    several = [name for name, vals in values.items() if len(vals) > 1]
    if len(several) > 1:
        raise JobError(f"only one parameter may take several values, got {', '.join(several)}")
    base = {name: vals[0] for name, vals in values.items()}
    if not several:
        return [base]
    return [{**base, several[0]: value} for value in values[several[0]]]


def describe_line(line: BifurcationLine) -> str:
    """One text line per run of equal labels, in the order computed (ω decreasing)."""
    par = ", ".join(
        f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in line.parameters.items()
    )
    rows = [f"line at {par}: {len(line.omega)} cells, ω {line.omega[0]:g} → {line.omega[-1]:g}"]
    rows += [f"  {label:>11}  ω {a:.5g} … {b:.5g}" for label, a, b in line.runs()]
    return "\n".join(rows)
