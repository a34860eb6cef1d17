"""Bifurcation structure of a map: every edge between neighbouring cells of different labels, typed.

A map (``campar run``) is a grid of continuation chains along ω; wherever two
neighbouring cells — along ω or along the second parameter — carry different
n-p labels, something happened between them. ``find_boundaries`` types each
such cell edge with the rules of ``campar.views.transitions`` (``classify_boundary``,
the same thresholds, the same precedence), from what the store holds on both sides:

- the Floquet **multipliers** of the last cell before the edge and of the next cell
  away with the same label give PD (→ −1), NS (a complex pair → |λ| = 1), SN (→ +1)
  and jump (both sides stable, nothing critical). A map stores them only if its job
  lists the ``multipliers`` output; without them those four types cannot be told
  and such edges are ``unknown`` (``MapBoundaries.notes`` says so) — never guessed;
- **grazing** (G) where the detachments per revolution change and an extremum of ε
  approaches 0. A store keeps only the global extrema ``eps_min`` and ``eps_max`` of
  each cell, which bound the distance of the nearest extremum from above: a bound
  → 0 is a grazing, but a bound far from 0 excludes nothing (a new shallow flight
  beside a deep one), so without ``trace`` such an edge is unknown, not a jump.
  ``trace=True`` traces both sides' steady orbits from their stored final states
  with the store's job (the kernel, ~ms a cell), exactly as a line does;
- **chaos** (onset or end) where one side is chaotic; a stored Lyapunov exponent
  must be > 0 there, else the edge is unknown.

"Before" is the cell computed first: along ω the earlier cell of the chain
(larger ω for chains running down, smaller for ``up``); along the second axis the
one nearer to the plane's starting corner (lower index, the first column's
continuation order). Evidence is always read at the last cell on its side, so a
segment's ``evidence`` names the multiplier (or ε extremum) that reaches its critical
value and the side it comes from.
"""

import math
from collections import Counter
from dataclasses import dataclass, field, replace

import numpy as np

from ..core.codes import KIND_NAMES, Kind, cell_label
from ..sweep.job import cell_edges
from .transitions import (
    PERIODIC_NAME,
    TRACE_PERIODS,
    Side,
    Transition,
    classify_boundary,
    graze_distance,
)

TYPES = ("PD", "SN", "NS", "G", "chaos", "jump", "unknown")  # in legend order
NOT_COMPUTED = -1  # kind of a cell not computed yet (campar.open's fill value)
NO_MULTIPLIERS = (
    "the store holds no Floquet multipliers (add `multipliers` to the "
    "job's outputs): PD, SN, NS and jump cannot be told, such edges are "
    "unknown"
)
BOUNDED_GRAZES = (
    "grazing judged from the stored global extrema of ε only: where the "
    "detachments change without them approaching 0 the edge is unknown "
    "(trace to tell)"
)


@dataclass(frozen=True)
class Segment:
    """One typed cell edge: between cells ``before`` and ``after`` (row, column) of the
    map, drawn from (x0, y0) to (x1, y1) in (ω, second) coordinates."""

    axis: str  # "omega": neighbours along ω (a vertical edge); else the second's name
    before: tuple[int, int]
    after: tuple[int, int]
    edge: tuple[float, float, float, float]  # x0, y0, x1, y1
    transition: Transition  # sides, type, reason, evidence

    @property
    def type(self) -> str:
        return self.transition.type

    def to_dict(self) -> dict:
        t = self.transition
        return {
            "axis": self.axis,
            "cells": [list(self.before), list(self.after)],
            "edge": list(self.edge),
            "type": t.type,
            "from": t.before.label,
            "to": t.after.label,
            "reason": t.reason,
            "evidence": None if t.evidence is None else t.evidence.to_dict(),
            "before": t.before.to_dict(),
            "after": t.after.to_dict(),
        }


@dataclass(frozen=True)
class MapBoundaries:
    """The typed boundaries of a map (or of its zoomed part).

    Parameters
    ----------
    segments : tuple of Segment
        Every typed edge between neighbouring cells of different labels.
    second_name : str
        The map's second parameter.
    multipliers : bool
        Whether the store held Floquet multipliers (without them PD, SN, NS and jump
        cannot be told).
    traced : bool
        Grazing judged from traced orbits (else from the stored ε extremes).
    notes : tuple of str
        What limited the typing, in words.

    Examples
    --------
    >>> from campar.views.boundaries import store_boundaries
    >>> found = store_boundaries("results/smoke.zarr")
    >>> found.counts()["PD"], found.counts()["G"] > 0
    (0, True)
    """

    segments: tuple[Segment, ...]
    second_name: str
    multipliers: bool  # the store held multipliers
    traced: bool  # grazing from traced orbits (else from the stored ε extrema)
    notes: tuple[str, ...] = field(default_factory=tuple)

    def counts(self) -> dict[str, int]:
        """Segments per type, every type listed (0 where none)."""
        found = Counter(s.type for s in self.segments)
        return {name: found.get(name, 0) for name in TYPES}

    def of_type(self, name: str) -> list[Segment]:
        return [s for s in self.segments if s.type == name]

    def to_dict(self, *, segments: bool = True) -> dict:
        data = {
            "second": self.second_name,
            "multipliers": self.multipliers,
            "grazing_from": "traced orbits" if self.traced else "stored ε extrema",
            "notes": list(self.notes),
            "counts": self.counts(),
        }
        if segments:
            data["segments"] = [s.to_dict() for s in self.segments]
        return data


def find_boundaries(
    arrays,
    omega,
    second,
    second_name: str,
    *,
    direction: str = "down",
    chatter_p: int = 7,
    trace=None,
) -> MapBoundaries:
    """Every edge between neighbouring computed cells of different labels, typed.

    arrays: name → array shaped (second, omega) in the job's order: "kind", "n", "p"
        (kind −1: not computed, such edges are skipped); optional "multipliers"
        (…, 2, 2) re/im, "eps_min", "eps_max", "lyapunov", "sections" (…, S, 2) or
        their "half_gap" (``half_gaps``).
    omega, second: the cell centres; direction: the chains' ("down" or "up").
    trace(row, col, revolutions) -> (t, ε) of a cell's steady orbit, or (None, None):
        grazing from every extremum of ε (else from the stored extrema, a bound).
    """
    kind = np.asarray(arrays["kind"])
    omega, second = np.asarray(omega, float), np.asarray(second, float)
    if kind.shape != (len(second), len(omega)):
        raise ValueError(f"arrays are {kind.shape}, the axes ({len(second)}, {len(omega)})")
    cells = MapCells(arrays, omega, second, second_name, chatter_p, trace)
    xe, ye = cell_edges(omega), cell_edges(second)
    segments = []
    # along ω: (i, j) | (i, j + 1); the chain computed the larger ω first when running down
    first_is_j = (omega[0] > omega[-1]) == (direction == "down") if len(omega) > 1 else True
    for i, j in zip(*np.nonzero(cells.differs(axis=1)), strict=True):
        a, b = ((i, j), (i, j + 1)) if first_is_j else ((i, j + 1), (i, j))
        x = xe[j + 1]
        segments.append(
            cells.segment(
                a,
                b,
                "omega",
                (x, ye[i], x, ye[i + 1]),
                direction_text(omega[a[1]], omega[b[1]], "ω"),
            )
        )
    # along the second axis: (i, j) | (i + 1, j), in the first column's continuation order
    for i, j in zip(*np.nonzero(cells.differs(axis=0)), strict=True):
        y = ye[i + 1]
        text = direction_text(second[i], second[i + 1], second_name)
        segments.append(
            cells.segment((i, j), (i + 1, j), second_name, (xe[j], y, xe[j + 1], y), text)
        )
    notes = [] if cells.multipliers is not None else [NO_MULTIPLIERS]
    if trace is None:
        notes.append(BOUNDED_GRAZES)
    return MapBoundaries(
        tuple(segments), second_name, cells.multipliers is not None, trace is not None, tuple(notes)
    )


def direction_text(first: float, then: float, name: str) -> str:
    return f"{name} {'decreasing' if then < first else 'increasing'}"


class MapCells:
    """Sides of a map's cells (``transitions.Side``), built on demand from its arrays."""

    def __init__(self, arrays, omega, second, second_name, chatter_p, trace):
        self.kind = np.asarray(arrays["kind"]).astype(np.int64)
        self.n = np.asarray(arrays["n"]).astype(np.int64)
        self.p = np.asarray(arrays["p"]).astype(np.int64)
        self.omega, self.second, self.second_name = omega, second, second_name
        self.chatter_p, self.trace = chatter_p, trace
        get = arrays.get
        self.multipliers = (
            None if get("multipliers") is None else np.asarray(get("multipliers"), float)
        )
        self.eps = [
            np.asarray(get(name), float) for name in ("eps_min", "eps_max") if get(name) is not None
        ]
        self.lyapunov = None if get("lyapunov") is None else np.asarray(get("lyapunov"), float)
        self.gaps = get("half_gap")
        if self.gaps is None and get("sections") is not None:
            self.gaps = half_gaps(get("sections"), self.n)
        self.label_codes = self._label_codes()

    def _label_codes(self) -> np.ndarray:
        """One integer per distinct label (−1: not computed), so edges compare as arrays;
        each distinct (kind, n, p) is labelled once."""
        triples = np.stack([self.kind, self.n, self.p]).reshape(3, -1)
        distinct, inverse = np.unique(triples, axis=1, return_inverse=True)
        labels, codes = {}, []
        for k, n, p in distinct.T.tolist():
            if k == NOT_COMPUTED:
                codes.append(-1)
            else:
                codes.append(labels.setdefault(self.label_of(k, n, p), len(labels)))
        return np.asarray(codes, np.int64)[inverse.ravel()].reshape(self.kind.shape)

    def label_of(self, k: int, n: int, p: int) -> str:
        try:
            return cell_label(Kind(k), n, p, self.chatter_p)
        except ValueError:  # a kind this campar does not know
            return f"kind {k}"

    def label(self, cell) -> str:
        return self.label_of(int(self.kind[cell]), int(self.n[cell]), int(self.p[cell]))

    def differs(self, axis: int) -> np.ndarray:
        """Edges (as the first cell's index) between computed cells of different labels."""
        c = self.label_codes
        a, b = (c[:, :-1], c[:, 1:]) if axis == 1 else (c[:-1], c[1:])
        return (a != b) & (a >= 0) & (b >= 0)

    def segment(self, before, after, axis, edge, direction) -> Segment:
        step = np.subtract(after, before)  # from before to after; farther cells lie beyond
        first = self.side(before, tuple(np.subtract(before, step)))
        then = self.side(after, tuple(np.add(after, step)))
        if self.trace is not None and self._detachments_change(first, then):
            first, then = self.traced(first, before, step, -1), self.traced(then, after, step, 1)
        transition = Transition(first, then, *classify_boundary(first, then, direction))
        return Segment(
            axis,
            tuple(map(int, before)),
            tuple(map(int, after)),
            tuple(float(v) for v in edge),
            transition,
        )

    @staticmethod
    def _detachments_change(a: Side, b: Side) -> bool:
        return a.kind == b.kind == PERIODIC_NAME and a.p * b.n != b.p * a.n

    def inside(self, cell) -> bool:
        return 0 <= cell[0] < self.kind.shape[0] and 0 <= cell[1] < self.kind.shape[1]

    def side(self, cell, farther) -> Side:
        """The side whose last cell is ``cell``; ``farther`` is used if inside, same label."""
        farther = (
            farther
            if self.inside(farther) and self.label_codes[farther] == self.label_codes[cell]
            else None
        )
        kind = Kind(int(self.kind[cell]))
        n = int(self.n[cell])
        graze, graze_farther = self.eps_bound(cell), None
        if farther is not None:
            graze_farther = self.eps_bound(farther)
        return Side(
            index=int(cell[1]),
            omega=float(self.omega[cell[1]]),
            label=self.label(cell),
            kind=KIND_NAMES[kind],
            n=n,
            p=int(self.p[cell]),
            multipliers=self.cell_multipliers(cell),
            farther=None if farther is None else self.cell_multipliers(farther),
            graze=graze if kind == Kind.PERIODIC else None,
            graze_farther=graze_farther if kind == Kind.PERIODIC else None,
            half_gap=self.gap(cell),
            half_gap_farther=None if farther is None else self.gap(farther),
            second=(self.second_name, float(self.second[cell[0]])),
            lyapunov=self.cell_lyapunov(cell),
            graze_bound=graze is not None,
        )

    def gap(self, cell) -> float | None:
        if self.gaps is None or not math.isfinite(self.gaps[cell]):
            return None
        return float(self.gaps[cell])

    def eps_bound(self, cell) -> float | None:
        """min(|eps_min|, |eps_max|): an extremum of ε is at least this close to 0."""
        values = [abs(float(e[cell])) for e in self.eps if math.isfinite(e[cell])]
        return min(values) if values else None

    def cell_multipliers(self, cell):
        if self.multipliers is None or int(self.kind[cell]) != Kind.PERIODIC:
            return None
        pairs = self.multipliers[cell]
        if not np.all(np.isfinite(pairs)):
            return None
        return tuple(complex(re, im) for re, im in pairs)

    def cell_lyapunov(self, cell) -> float | None:
        if self.lyapunov is None or not math.isfinite(self.lyapunov[cell]):
            return None
        return float(self.lyapunov[cell])

    def traced(self, side: Side, cell, step, sign: int) -> Side:
        """The side with graze distances from traced orbits (every extremum of ε)."""
        revolutions = TRACE_PERIODS * side.n
        graze = graze_distance(*self.trace(*cell, revolutions))
        farther = tuple(np.add(cell, sign * step))
        graze_farther = None
        if self.inside(farther) and self.label_codes[farther] == self.label_codes[cell]:
            graze_farther = graze_distance(*self.trace(*farther, revolutions))
        return replace(side, graze=graze, graze_farther=graze_farther, graze_bound=False)


def half_gaps(sections, n) -> np.ndarray:
    """``transitions.half_gap`` of every cell at once (NaN where it is None): sections
    (…, S, 2), n (…)."""
    sections, n = np.asarray(sections, float), np.asarray(n)
    out = np.full(n.shape, np.nan)
    for m in np.unique(n).tolist():
        if m < 2 or m % 2 or m > sections.shape[-2]:
            continue
        points = sections[n == m][:, :m]
        out[n == m] = np.abs(points[:, : m // 2] - points[:, m // 2 :]).max(axis=(1, 2))
    return out


def store_boundaries(
    path,
    *,
    omega=None,
    second=None,
    trace: bool = False,
    direction: str | None = None,
    shoot: bool = False,
) -> MapBoundaries:
    """``find_boundaries`` of a result store (the cells whose centres lie in the zoom
    ranges ``omega=(a, b)``, ``second=(c, d)``, either order; None: the whole axis).

    Tiles not committed (or failing their checksum) count as not computed. ``trace``:
    grazing from orbits traced from the stored states with the store's job (loads the
    kernel; an orbit per periodic cell on an edge where the detachments change).
    direction: of a ``chains.direction: both`` store, the sweep whose map is typed
    ("down", the default, or "up"); else None or the store's own direction. ``shoot``:
    the edges still unknown between periodic cells typed by shooting
    (``campar.views.shot_edges``; two cycles continued an edge).

    Parameters
    ----------
    path : str or pathlib.Path
        The store.
    omega, second : tuple of float, optional
        Zoom ranges ``(a, b)`` of ω and the second parameter, either order; None: the
        whole axis.
    trace : bool
        Judge grazing from orbits traced from the stored states with the store's job.
    direction : str, optional
        Of a ``chains.direction: both`` store, the sweep whose map is typed.
    shoot : bool
        Type the unknown edges between periodic cells by shooting: both cycles solved
        by Newton on Pⁿ and continued across the edge.

    Returns
    -------
    MapBoundaries
        The typed edges, and notes on what limited the typing.

    Raises
    ------
    campar.errors.StoreError
        The store cannot be read, or it is a basin store (no parameter plane).

    Examples
    --------
    >>> from campar.views.boundaries import store_boundaries
    >>> found = store_boundaries("results/smoke.zarr")
    >>> found.multipliers, found.second_name
    (False, 'mu_cn')
    """
    from ..sweep.store import read_store, verify_store
    from .plot import PlotError  # cheap: matplotlib is not loaded

    wanted = (
        "kind",
        "n",
        "p",
        "multipliers",
        "eps_min",
        "eps_max",
        "lyapunov",
        "sections",
        "state",
    )
    with read_store(path) as store:
        job = store.job
        if job.kind == "basin":
            raise PlotError(f"{path} is a basin store: bifurcation curves are for maps")
        ran = job.chains.direction
        held = ("down", "up") if ran == "both" else (ran,)
        if direction not in (None, *held):
            raise PlotError(f"{path}: its chains ran {ran}; there is no {direction} map to type")
        sweep = direction or ("down" if ran == "both" else ran)
        names = [name for name in wanted if name in store.names]
        arrays = {"half_gap" if name == "sections" else name: None for name in names}
        done = np.zeros(job.shape[0], bool)

        def take(check):  # one verified tile (of the typed sweep, in a store of both)
            if getattr(check.tile, "direction", None) not in (None, sweep):
                return
            tile = dict(check.arrays)
            if "sections" in tile:  # kept as one number a cell: memory stays per-cell scalars
                tile["half_gap"] = half_gaps(tile.pop("sections"), tile["n"])
            for name, values in tile.items():
                if name not in arrays:
                    continue
                if arrays[name] is None:
                    fill = -1 if values.dtype.kind in "iu" else np.nan
                    arrays[name] = np.full((*job.shape, *values.shape[2:]), fill, values.dtype)
                arrays[name][check.tile.rows] = values
            done[check.tile.rows] = True

        verify_store(store, take)
    if arrays.get("kind") is None:  # nothing committed yet
        return MapBoundaries((), job.second, "multipliers" in names, trace, ("nothing computed",))
    arrays["kind"][~done] = NOT_COMPUTED
    rows, cols = zoom(job.second_values, second, job.second), zoom(job.omega, omega, "omega")
    arrays = {name: values[rows][:, cols] for name, values in arrays.items()}
    tracer = store_tracer(job, arrays, job.omega[cols], job.second_values[rows]) if trace else None
    found = find_boundaries(
        arrays,
        job.omega[cols],
        job.second_values[rows],
        job.second,
        direction=sweep,
        chatter_p=job.classify.chatter_p,
        trace=tracer,
    )
    if not shoot:
        return found
    from .shot_edges import shoot_unknown

    return shoot_unknown(found, job, arrays["state"], job.omega[cols], job.second_values[rows])


def zoom(centres, bounds, name: str) -> slice:
    """Indices of the centres inside [min(bounds), max(bounds)]; the whole axis for None."""
    if bounds is None:
        return slice(None)
    lo, hi = sorted(float(b) for b in bounds)
    spacing = np.min(np.abs(np.diff(centres))) if len(centres) > 1 else 1.0
    inside = np.flatnonzero((centres >= lo - 1e-9 * spacing) & (centres <= hi + 1e-9 * spacing))
    if inside.size == 0:
        from .plot import PlotError  # cheap: matplotlib is not loaded

        raise PlotError(
            f"no cell centre of {name} lies in [{lo:g}, {hi:g}]; the map covers "
            f"{name} from {centres.min():g} to {centres.max():g}"
        )
    return slice(int(inside[0]), int(inside[-1]) + 1)


def store_tracer(job, arrays, omega, second):
    """trace(row, col, revolutions) -> (t, ε) of a stored cell's steady orbit, started from
    its stored final state with the job's integrator settings ((None, None) if it fails)."""
    from .point import trace_steady

    def trace(row: int, col: int, revolutions: int):
        model = job.model_at(omega[col], second[row])
        orbit = trace_steady(model, arrays["state"][row, col], max(revolutions, 1))
        return (None, None) if orbit is None else (orbit.t, orbit.eps)

    return trace


def describe_boundaries(found: MapBoundaries, limit: int = 20) -> str:
    """Counts per type, the notes, and the first ``limit`` typed (non-unknown) segments."""
    rows = ["  ".join(f"{name} {count}" for name, count in found.counts().items())]
    rows += [f"  note: {note}" for note in found.notes]
    typed = [s for s in found.segments if s.type != "unknown"][:limit]
    for s in typed:
        t = s.transition
        rows.append(
            f"  {s.type:>5}  {t.before.label:>6} → {t.after.label:<6} at "
            f"{t.before.where} | {t.after.where}: {t.reason}"
        )
    return "\n".join(rows)
