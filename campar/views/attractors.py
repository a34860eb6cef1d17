"""Coexisting attractors of one cell: many starts, each run to its steady motion, grouped.

``find_attractors`` runs K starts at one parameter point — rest, any starts given,
then a deterministic spread over a box of (y, y') at θ = 0 (``spread_starts``) —
each as its own one-cell job through ``simulate_point`` (``run_tile``): every start
takes the kernel path of ``campar point --y0 --v0``, with one setting changed:
chaos is only called at the end of the transient budget (CHAOS_AFTER). The
converged results are grouped into distinct attractors (as Attractors.jl maps
initial conditions for its ``basins_fractions``: each result compared with the
first member of every group found so far), and each attractor's basin fraction is
the fraction of the K starts that reached it (a given start counts as one of K, so
fractions estimate basin sizes in the box only without given starts).

Same attractor, decided by the motion itself, never by its label:

- periodic: the σn points of two cycles equal up to a cyclic shift within
  ``match_tolerance`` (∞-norm), which is the cycle's own accuracy, see there;
- quasi-periodic or chaotic: the same kind and overlapping section clouds
  (``clouds_overlap``: one cloud within the other at the clouds' own point spacing) —
  a weak test: two distinct attractors whose clouds interleave at that scale would be
  merged, and a cloud is 64 section points at the end of a 500-revolution budget, so a
  transient longer than that is taken for an attractor.

The spread and the grouping are ``campar.sweep.census``'s, which a map's census of every
cell (a job's ``attractors`` key, ``campar.sweep.multistable``) uses too: one rule.

Starts whose cell is unconverged (no period ≤ n_max and a negative Lyapunov
exponent: a stable motion not yet reached) or failed are never attractors; they
are kept apart as ``unsettled`` and count in the denominator of the fractions.
"""

import math
from dataclasses import dataclass

import numpy as np

from ..core.codes import KIND_NAMES, Kind
from ..sweep import census as rules
from ..sweep.census import (  # noqa: F401 — the rules' names, re-exported for this view's users
    BOX_Y,
    CAM_PEAK_SPEED,
    CHAOS_AFTER,
    CLOUD_FACTOR,
    CLOUD_POINTS,
    HALTON_BASES,
    clouds_overlap,
    group_records,
    halton,
    own_spacing,
    same_cycle,
    spread_starts,
)
from ..sweep.job import DEFAULT_CLASSIFY, DEFAULT_TRANSIENT
from .point import PointResult, simulate_point

DEFAULT_STARTS = 16
# Kinds of steady motion that are attractors (not unconverged, not failed), as text.
SETTLED_KINDS = frozenset(KIND_NAMES[Kind(k)] for k in rules.SETTLED_KINDS)
KIND_CODES = {name: int(code) for code, name in KIND_NAMES.items()}


@dataclass(frozen=True)
class Attractor:
    """One attractor of a cell and the starts that reached it.

    Parameters
    ----------
    result : PointResult
        The first start's cell (label, multipliers, σn points, …); ``state`` is a point
        of the attractor at θ = 0 (its final state), a start that lands on it.
    starts : tuple of int
        Indices into the census' starts that reached it, the first the representative.
    fraction : float
        ``len(starts) / K``: its basin fraction in the box of starts.

    Examples
    --------
    >>> from campar.views.attractors import find_attractors
    >>> first = find_attractors(5.8, count=16, mu_kn=0.86).attractors[0]
    >>> first.label, first.kind, len(first.starts)
    ('1-1', 'periodic', 9)
    """

    result: PointResult
    starts: tuple[int, ...]  # indices into the census' starts, first = representative
    fraction: float  # len(starts) / K

    @property
    def label(self) -> str:
        return self.result.label

    @property
    def kind(self) -> str:
        return self.result.kind

    @property
    def state(self) -> tuple[float, float]:
        return self.result.state

    def to_dict(self, starts: np.ndarray) -> dict:
        """The cell's summary (PointResult.to_dict, without the parameters) with the
        basin fraction and the starts (y, y') that reached it."""
        data = {**self.result.to_dict(), "fraction": self.fraction}
        del data["parameters"]
        data["starts"] = [[float(y), float(v)] for y, v in starts[list(self.starts)]]
        return data


@dataclass(frozen=True)
class AttractorCensus:
    """What K starts of one cell reached: distinct attractors, most frequent first.

    Parameters
    ----------
    parameters : dict
        ω, f0, μkn, μcn, ζ, the force law and its options.
    starts : numpy.ndarray
        The K starts (y, y') at θ = 0, shape (K, 2).
    attractors : tuple of Attractor
        The distinct attractors, most frequent first.
    basin : numpy.ndarray
        Shape (K,): the index into ``attractors`` each start reached; -1 unsettled.
    unsettled : tuple
        (start index, its PointResult) of the starts that settled on none.
    match_tol : float
        ∞-norm tolerance within which two cycles' σn points are one.

    Examples
    --------
    >>> from campar.views.attractors import find_attractors
    >>> census = find_attractors(5.8, count=16, mu_kn=0.86)
    >>> census.basin.tolist()
    [0, 0, 1, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1]
    """

    parameters: dict  # omega, f0, mu_kn, mu_cn, zeta, tensile
    starts: np.ndarray  # (K, 2) initial (y, y') at θ = 0
    attractors: tuple[Attractor, ...]
    basin: np.ndarray  # (K,) index into attractors of each start; -1: unsettled
    unsettled: tuple[tuple[int, PointResult], ...]  # (start index, its cell)
    match_tol: float  # ∞-norm tolerance used to match cycles

    def to_dict(self) -> dict:
        return {
            "parameters": self.parameters,
            "starts": len(self.starts),
            "match_tolerance": self.match_tol,
            "attractors": [a.to_dict(self.starts) for a in self.attractors],
            "unsettled": [
                {
                    "start": [float(v) for v in self.starts[i]],
                    "label": r.label,
                    "kind": r.kind,
                    "status": r.status,
                    "revolutions": r.revolutions,
                }
                for i, r in self.unsettled
            ],
        }


def match_tolerance(
    window_tol: float = DEFAULT_TRANSIENT.window_tol,
    period_tol: float = DEFAULT_CLASSIFY.period_tol,
) -> float:
    """∞-norm distance within which σn points of two converged cycles are one point
    (``cycles.match_tolerance``, the rule of a map's hysteresis too)."""
    return rules.match_tolerance(window_tol, period_tol)


def same_attractor(a: PointResult, b: PointResult, tol: float) -> bool:
    """Periodic: one cycle (``same_cycle``); otherwise one kind and overlapping clouds
    (``campar.sweep.census.same_record``)."""
    return rules.same_record(KIND_CODES[a.kind], a.sections, KIND_CODES[b.kind], b.sections, tol)


def find_attractors(
    model=None,
    *,
    count: int = DEFAULT_STARTS,
    starts=None,
    given=(),
    lyapunov: bool = False,
    **fields,
) -> AttractorCensus:
    """Run ``count`` starts at one cell and group them into distinct attractors.

    Two periodic results are one attractor when their σn points agree up to a cyclic
    shift within ``match_tolerance``; quasi-periodic and chaotic results are grouped
    by kind and by the overlap of their section clouds. Multipliers are always computed.

    Parameters
    ----------
    model : Model, mapping or float, optional
        The cell's model, or ω (``campar.simulate_point``'s first argument); ``fields``
        change it.
    count : int
        Number of starts K (2 to MAX_STARTS): rest, then ``given``, then Halton points
        over y ∈ [−1, 2], y' ∈ ±1.5 ω at θ = 0 (``spread_starts``).
    starts : array_like, optional
        (K, 2) starts (y, y') at θ = 0, replacing that spread.
    given : sequence of (float, float)
        Starts to try right after rest.
    lyapunov : bool
        Also compute each start's largest Lyapunov exponent.
    **fields
        Any key of the model (``campar.simulate_point``) but the start and ``sections``;
        ``chaos_after`` defaults to ``CHAOS_AFTER`` (a chaos verdict waits for the whole
        budget), as a map's census.

    Returns
    -------
    AttractorCensus
        The distinct attractors, most frequent first, each with its basin fraction.

    Raises
    ------
    campar.errors.JobError
        A key unknown, a value out of range, or ``count`` outside its bounds.

    Examples
    --------
    >>> from campar.views.attractors import find_attractors
    >>> census = find_attractors(5.8, count=16, mu_kn=0.86)
    >>> [(a.label, a.fraction) for a in census.attractors]
    [('1-1', 0.5625), ('3-2', 0.4375)]
    """
    from ..errors import JobError
    from ..model import Model
    from ..model.settings import MAX_STARTS, check_count

    fields.setdefault("chaos_after", CHAOS_AFTER)
    model = Model.build(model, sections=CLOUD_POINTS, **fields)
    if starts is None:
        try:
            check_count("count", count, 1, MAX_STARTS)
        except ValueError as exc:
            raise JobError(str(exc)) from None
        starts = spread_starts(count, model.omega, given)
    starts = np.asarray(starts, dtype=float).reshape(-1, 2)
    results = [
        simulate_point(model, state=(float(y), float(v)), multipliers=True, lyapunov=lyapunov)
        for y, v in starts
    ]
    tol = match_tolerance(model.transient.window_tol, model.classify.period_tol)
    # the grouping a map's census uses too (campar.sweep.multistable): one rule
    groups, basin = group_records(
        [KIND_CODES[r.kind] for r in results], [r.sections for r in results], tol
    )
    unsettled = [(i, r) for i, r in enumerate(results) if basin[i] < 0]
    attractors = tuple(Attractor(results[g[0]], tuple(g), len(g) / len(starts)) for g in groups)
    parameters = results[0].parameters if results else {"omega": model.omega}
    return AttractorCensus(parameters, starts, attractors, basin, tuple(unsettled), tol)


def describe_attractors(census: AttractorCensus) -> str:
    """A few text lines per attractor: label, kind, basin fraction, state, multipliers."""
    par = ", ".join(f"{k}={v}" for k, v in census.parameters.items())
    k = len(census.starts)
    rows = [f"{len(census.attractors)} attractor(s) from {k} starts at {par}"]
    for j, a in enumerate(census.attractors, 1):
        r = a.result
        share = f"{a.fraction:.3f} ± {fraction_error(a.fraction, k):.3f} ({len(a.starts)}/{k})"
        flags = f"  flags: {', '.join(r.flags)}" if r.flags else ""
        rows.append(f"  [{j}] {a.label:>6}  ({a.kind})  basin fraction {share}{flags}")
        first = census.starts[a.starts[0]]
        rows.append(
            f"      state ({r.state[0]:+.6f}, {r.state[1]:+.6f}), first reached from "
            f"({first[0]:+.6f}, {first[1]:+.6f})"
        )
        if r.n and r.multipliers is not None:
            mult = ", ".join(
                f"{m.real:+.6f}{m.imag:+.6f}j (|λ|={abs(m):.6f})" for m in r.multipliers
            )
            rows.append(f"      Floquet multipliers: {mult}")
    if census.unsettled:
        rows.append(f"  {len(census.unsettled)} start(s) settled on no attractor:")
        for i, r in census.unsettled:
            y, v = census.starts[i]
            rows.append(
                f"      from ({y:+.6f}, {v:+.6f}): {r.label} ({r.status}, "
                f"{r.revolutions} revolutions)"
            )
    rows.append(f"  (cycles matched within {census.match_tol:.0e}, ∞-norm of σn points)")
    return "\n".join(rows)


def fraction_error(fraction: float, count: int) -> float:
    """Binomial standard error of a basin fraction estimated from ``count`` starts."""
    return math.sqrt(max(fraction * (1.0 - fraction), 0.0) / max(count, 1))
