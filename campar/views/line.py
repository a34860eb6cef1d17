"""Single-parameter bifurcation lines: σn points and detachments along ω by continuation.

A line is one continuation chain of the kernel: ω decreasing from its largest
value, each cell warm-started from the previous cell's final state, exactly
as one row of a two-parameter map (the paper's Fig. 5 is such a row, drawn as
σn points y against ω with the detachment count p beneath). It is computed
as a one-row job with the ``sections`` output through ``run_tile``, so a line
and the map row with the same parameters give the same cells.

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
from ..sweep.job import (
    DEFAULT_CLASSIFY,
    DEFAULT_INITIAL,
    DEFAULT_INTEGRATOR,
    DEFAULT_MODEL,
    DEFAULT_TRANSIENT,
    Job,
    with_paper_values,
)
from ..sweep.plan import Tile

# Second parameter of the one-row job (any swept parameter would do; its one value
# is the line's μkn).
ROW_PARAMETER = "mu_kn"
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
        f0, μkn, μcn, ζ (floats) and ``tensile``.
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
    job : Job or None
        The line's job.

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
    job: Job | None = field(default=None, repr=False, compare=False)  # the line's job

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


def line_job(
    omega: tuple[float, float],
    points: int,
    *,
    tensile: str = DEFAULT_MODEL.tensile,
    duty_cycle: str = DEFAULT_MODEL.duty_cycle,
    cam_velocity: str = DEFAULT_MODEL.cam_velocity,
    sections: int = DEFAULT_SECTIONS,
    transient: str = DEFAULT_TRANSIENT.mode,
    revolutions: int = DEFAULT_TRANSIENT.max_revolutions,
    initial: tuple[float, float] = (DEFAULT_INITIAL.y, DEFAULT_INITIAL.v),
    rtol: float = DEFAULT_INTEGRATOR.rtol,
    name: str = "line",
    **parameters: float,
) -> Job:
    """The one-row job of a line: ``points`` ω values from max(omega) down to min(omega).

    Parameters
    ----------
    omega : tuple of float
        The ω range, either order; the chain runs from the larger value down.
    points : int
        Number of ω values.
    tensile, duty_cycle, cam_velocity : str
        The job's ``model:`` section: the force law (``"clamp"`` or ``"allow"``) and its
        options (docs/model.md).
    sections : int
        σn points stored per non-periodic cell (chaos, quasi-periodic clouds).
    transient : str
        ``"converged"`` or ``"fixed"``, as in a job's ``transient.mode``.
    revolutions : int
        The transient's budget (converged) or length (fixed).
    initial : tuple of float
        The start (y, y') at θ = 0 of the line's first cell.
    rtol : float
        The integrator's relative tolerance.
    name : str
        The job's name.
    **parameters : float
        f0, mu_kn, mu_cn, zeta; those not given take the paper's base values.

    Returns
    -------
    Job
        A validated one-row job with the outputs a line needs.

    Raises
    ------
    campar.errors.JobError
        A parameter unknown or out of range.

    Examples
    --------
    >>> from campar.views.line import line_job
    >>> job = line_job((2.0, 4.0), 50, mu_kn=0.91)
    >>> float(job.omega[0]), float(job.omega[-1]), job.shape
    (4.0, 2.0, (1, 50))
    """
    hi, lo = max(omega), min(omega)
    values = with_paper_values(parameters)
    row = values.pop(ROW_PARAMETER)
    data = {
        "name": name,
        "sweep": {
            "omega": {"from": hi, "to": lo, "points": points},
            ROW_PARAMETER: {"from": row, "to": row, "points": 1},
        },
        "fixed": values,
        "model": {"tensile": tensile, "duty_cycle": duty_cycle, "cam_velocity": cam_velocity},
        "initial": {"y": initial[0], "v": initial[1]},
        "integrator": {"rtol": rtol},
        "transient": {"mode": transient, "max_revolutions": revolutions},
        "classify": {"sections": sections},
        "outputs": list(LINE_OUTPUTS),
        "tiles": {"rows": 1},
    }
    return Job.from_dict(data, source=f"line {name}")


def compute_line(job: Job, *, transitions: bool = True) -> BifurcationLine:
    """Run the chain of a one-row job (``line_job``) and collect its cells.

    Parameters
    ----------
    job : Job
        A one-row job with the ``sections`` output (:func:`line_job`).
    transitions : bool
        Type the line's label boundaries (:func:`campar.views.transitions.find_transitions`).

    Returns
    -------
    BifurcationLine
        The line's cells in the order computed.

    Raises
    ------
    ValueError
        The job has more than one row or no ``sections`` output.

    Examples
    --------
    >>> from campar.views.line import compute_line, line_job
    >>> line = compute_line(line_job((2.0, 4.0), 50, mu_kn=0.91))
    >>> [(t.type, t.before.label, t.after.label) for t in line.transitions]
    [('G', '2-1', '2-2'), ('PD', '2-2', '1-1')]
    """
    if job.shape[0] != 1 or not job.wants("sections"):
        raise ValueError("compute_line needs a one-row job with the 'sections' output")
    from ..sweep.tile import run_tile  # numba loads here: the CLI reads this module's defaults
    from .transitions import find_transitions

    cells = {name: values[0] for name, values in run_tile(job, Tile(0, 0, 1)).items()}
    parameters = {name: float(job.parameter(name)) for name in ("f0", "mu_cn", "zeta")}
    parameters[ROW_PARAMETER] = float(job.second_values[0])
    parameters.update(job.model.model_dump())  # tensile, duty_cycle, cam_velocity
    line = BifurcationLine(
        omega=job.omega,
        sections=cells["sections"],
        n=cells["n"],
        p=cells["p"],
        kind=cells["kind"],
        dc=cells["dc"],
        state=cells["state"],
        parameters=parameters,
        chatter_p=job.classify.chatter_p,
        window=job.classify.window_revolutions,
        multipliers=cells.get("multipliers"),
        flags=cells["flags"],
        eps_min=cells.get("eps_min"),
        eps_max=cells.get("eps_max"),
        job=job,
    )
    return replace(line, transitions=find_transitions(line)) if transitions else line


def bifurcation_line(omega: tuple[float, float], points: int, **options) -> BifurcationLine:
    """A bifurcation line along ω with its typed transitions.

    ``compute_line(line_job(omega, points, **options))``.

    Parameters
    ----------
    omega : tuple of float
        The ω range; the chain runs from the larger value down.
    points : int
        Number of ω values.
    **options
        The keywords of :func:`line_job`.

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
    return compute_line(line_job(omega, points, **options))


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
    procedure lands on at this ω. ``options`` as for ``line_job`` (sections 1).
    """
    options.setdefault("sections", 1)
    line = bifurcation_line((start, omega), continuation_points(omega, start, step), **options)
    return line, (float(line.state[-1, 0]), float(line.state[-1, 1]))


def compute_lines(jobs: list[Job], threads: int = 2) -> list[BifurcationLine]:
    """Several lines at once: the kernel releases the GIL, so threads use the cores."""
    if len(jobs) == 1 or threads <= 1:
        return [compute_line(job) for job in jobs]
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(min(threads, len(jobs))) as pool:
        return list(pool.map(compute_line, jobs))


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
