"""Jumps, tongues and irreversible transitions of a plane, counted from its stores.

Inputs are the stores of ``campar.paper.structure``: a ``both`` store (the plane swept
down along the paper's path and up from its mirror start; ``campar.open`` gives its
``direction`` layers and the derived ``hysteresis``) and a census store (``n_attractors``
per cell). Everything here is numpy on the opened arrays:

- jumps (``jump_summary``): the hysteretic cells (the two sweeps on different converged
  cycles), where along ω they lie, and the (down, up) label pairs there; besides, the
  cells whose labels differ but which the hysteresis test cannot compare (a sweep on a
  quasi-periodic, chaotic or unconverged motion);
- tongues (``regions``): connected regions (4-neighbours) of hysteretic cells, or of
  multistable census cells, their extent, their width (cells along ω) row by row, and
  whether they narrow to a tip at one end of the second parameter (tongue-shaped); for
  hysteresis regions also which sweep changes label at each ω end of each row of the
  region, and the type of that boundary (``campar.views.boundaries``, from the stored
  multipliers and orbits traced from the stored states);
- irreversible transitions (``irreversibility``): each label change of one sweep along
  ω (a cell edge with its label pair) is crossed back at the same edge by the other
  sweep (the reverse pair there), nearby, farther along the row, or not at all.
"""

import json
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

MIN_REGION = 10  # cells from which a connected region is described
TIP_SHARE = 0.25  # a region is tongue-shaped when an end row's width ≤ this × its widest
MIN_TONGUE_ROWS = 5  # … and it spans at least this many rows and its widest is ≥ 4 cells
NEAR = 2  # cell edges within which a crossing back counts as "near"


@dataclass
class BothMap:
    """A ``both`` store's two label maps and its hysteresis, in the job's axis order."""

    omega: np.ndarray  # (columns,) ω decreasing along a row (the plane's order)
    second: np.ndarray  # (rows,)
    name: str  # the second parameter
    down: np.ndarray  # (rows, columns) labels, "" not computed
    up: np.ndarray
    hysteresis: np.ndarray  # bool
    compared: np.ndarray  # bool: both sweeps on a converged cycle
    types: dict = field(default_factory=dict)  # sweep → {(row, left column): boundary type}
    edges: dict = field(default_factory=dict)  # sweep → [(cell, cell, type)] of every edge


def load_both(store, typed: bool = True) -> BothMap:
    """The two sweeps of a ``both`` store; ``typed``: type each sweep's ω edges too."""
    from ..views.cycles import settled_cycles
    from ..views.dataset import open as open_store

    with open_store(store) as ds:
        second = ds["label"].dims[1]
        layers = [
            {
                name: ds[name].isel(direction=k).values
                for name in ("label", "kind", "status", "n", "sections")
            }
            for k in (0, 1)
        ]
        both = BothMap(
            ds["omega"].values,
            ds[second].values,
            second,
            layers[0]["label"],
            layers[1]["label"],
            ds["hysteresis"].values.astype(bool),
            settled_cycles(*(layers[0][k] for k in ("kind", "status", "n", "sections")))
            & settled_cycles(*(layers[1][k] for k in ("kind", "status", "n", "sections"))),
        )
    if typed:
        from ..views.boundaries import store_boundaries

        for sweep in ("down", "up"):
            found = store_boundaries(store, direction=sweep, trace=True)
            both.types[sweep] = {
                (s.before[0], min(s.before[1], s.after[1])): s.type
                for s in found.segments
                if s.axis == "omega"
            }
            both.edges[sweep] = [(s.before, s.after, s.type) for s in found.segments]
    return both


def subharmonic(label: str) -> bool:
    """An n-p label (chattering n-p~ included) with n ≥ 2."""
    head = label.split("-", 1)[0]
    return "-" in label and head.isdigit() and int(head) >= 2


@dataclass(frozen=True)
class LabelRegion:
    """A connected region of one subharmonic label of a sweep's map, with its shape and
    the types of the typed edges on its boundary."""

    label: str
    region: "Region"
    types: Counter  # boundary edge type → edges (unknown included)

    @property
    def pd_and_g(self) -> bool:
        """PD and G both on its boundary and, together, most of its typed edges."""
        typed = sum(n for t, n in self.types.items() if t != "unknown")
        pd, g = self.types.get("PD", 0), self.types.get("G", 0)
        return bool(pd and g and pd + g >= 0.5 * typed)


def label_regions(m: BothMap, sweep: str = "down", min_cells: int = MIN_REGION) -> list:
    """Every connected region (≥ ``min_cells``) of a subharmonic label of ``sweep``'s map
    (``load_both`` with ``typed``), largest first."""
    labels = m.down if sweep == "down" else m.up
    out = []
    for label in sorted({x for x in np.unique(labels).tolist() if subharmonic(x)}):
        ids, count = components(labels == label)
        for k in range(1, count + 1):
            inside = ids == k
            if inside.sum() < min_cells:
                continue
            types = Counter(kind for a, b, kind in m.edges.get(sweep, ()) if inside[a] or inside[b])
            out.append(LabelRegion(label, describe(inside, m.omega, m.second), types))
    return sorted(out, key=lambda r: -r.region.cells)


# -- jumps ------------------------------------------------------------------------------


def column_intervals(columns: np.ndarray, omega: np.ndarray, counts: np.ndarray) -> list:
    """Runs of adjacent columns: [(ω low, ω high, cells)], most cells first."""
    runs, start = [], None
    cols = np.unique(columns)
    for k, c in enumerate(cols):
        if start is None:
            start = c
        if k + 1 == len(cols) or cols[k + 1] != c + 1:
            span = omega[start : c + 1]
            runs.append((float(span.min()), float(span.max()), int(counts[start : c + 1].sum())))
            start = None
    return sorted(runs, key=lambda r: -r[2])


@dataclass(frozen=True)
class Jumps:
    cells: int  # hysteretic cells
    compared: int  # cells where both sweeps settled on a cycle
    total: int
    omega_range: tuple[float, float] | None
    intervals: list  # (ω low, ω high, cells), most cells first
    pairs: list  # ((down label, up label), cells), most first
    same_label: int  # hysteretic cells whose two cycles carry the same n-p label
    uncompared_differ: int  # labels differ, a sweep not on a converged cycle
    uncompared_pairs: list


def jump_summary(m: BothMap) -> Jumps:
    h = m.hysteresis
    computed = (m.down != "") & (m.up != "")
    cols = np.nonzero(h)[1]
    per_column = h.sum(axis=0)
    pairs = Counter(zip(m.down[h].tolist(), m.up[h].tolist(), strict=True))
    differ = computed & (m.down != m.up) & ~m.compared
    other = Counter(zip(m.down[differ].tolist(), m.up[differ].tolist(), strict=True))
    w = np.broadcast_to(m.omega, h.shape)[h]
    return Jumps(
        int(h.sum()),
        int(m.compared.sum()),
        int(computed.sum()),
        (float(w.min()), float(w.max())) if w.size else None,
        column_intervals(cols, m.omega, per_column),
        pairs.most_common(),
        int(sum(c for (a, b), c in pairs.items() if a == b)),
        int(differ.sum()),
        other.most_common(),
    )


# -- regions (tongues) -------------------------------------------------------------------


def components(mask: np.ndarray) -> tuple[np.ndarray, int]:
    """Connected regions of a boolean map (4-neighbours): (labels 1…k, 0 outside; k)."""
    mask = np.asarray(mask, bool)
    labels = np.zeros(mask.shape, np.int64)
    count = 0
    rows, cols = mask.shape
    for i, j in zip(*np.nonzero(mask), strict=True):
        if labels[i, j]:
            continue
        count += 1
        labels[i, j] = count
        stack = [(i, j)]
        while stack:
            a, b = stack.pop()
            for c, d in ((a - 1, b), (a + 1, b), (a, b - 1), (a, b + 1)):
                if 0 <= c < rows and 0 <= d < cols and mask[c, d] and not labels[c, d]:
                    labels[c, d] = count
                    stack.append((c, d))
    return labels, count


@dataclass(frozen=True)
class Region:
    cells: int
    omega: tuple[float, float]
    second: tuple[float, float]
    rows: int
    widest: int  # cells along ω in its widest row
    ends: tuple[int, int]  # widths at its lowest and highest second value (rows' cells)
    tongue: bool
    tip: float | None  # second value at the tip (the narrow end) if tongue-shaped
    pairs: list  # ((down, up), cells) inside (hysteresis regions), most first
    bounds: Counter  # (high-ω end, low-ω end) → rows; an end is "sweep: type" or "map edge"


def region_shape(widths_by_row: np.ndarray, second: np.ndarray):
    """(tongue?, tip second value or None, end widths (low, high second)) of a region
    whose rows ``second`` (sorted ascending) have ``widths_by_row`` cells each."""
    lo, hi = widths_by_row[0], widths_by_row[-1]
    widest = widths_by_row.max()
    rows = len(widths_by_row)
    tongue, tip = False, None
    if rows >= MIN_TONGUE_ROWS and widest >= 4:
        if lo <= TIP_SHARE * widest and lo < hi:
            tongue, tip = True, float(second[0])
        elif hi <= TIP_SHARE * widest:
            tongue, tip = True, float(second[-1])
    return tongue, tip, (int(lo), int(hi))


def regions(
    mask, omega, second, both: BothMap | None = None, min_cells: int = MIN_REGION
) -> list[Region]:
    """The connected regions of ``mask`` with ≥ ``min_cells`` cells, largest first."""
    labels, count = components(mask)
    out = []
    for k in range(1, count + 1):
        inside = labels == k
        if inside.sum() >= min_cells:
            out.append(describe(inside, omega, second, both))
    return sorted(out, key=lambda g: -g.cells)


def describe(inside, omega, second, both: BothMap | None = None) -> Region:
    """A region (boolean map of its cells): extent, widths, shape; with ``both``, the
    (down, up) label pairs inside and the ends of its rows (``run_bounds``)."""
    r, c = np.nonzero(inside)
    rows = np.unique(r)
    widths = inside[rows].sum(axis=1)
    order = np.argsort(second[rows])
    tongue, tip, ends = region_shape(widths[order], second[rows][order])
    pairs, bounds = [], Counter()
    if both is not None:
        pairs = Counter(
            zip(both.down[inside].tolist(), both.up[inside].tolist(), strict=True)
        ).most_common()
        bounds = run_bounds(inside, both)
    return Region(
        int(inside.sum()),
        (float(omega[c].min()), float(omega[c].max())),
        (float(second[r].min()), float(second[r].max())),
        len(rows),
        int(widths.max()),
        ends,
        tongue,
        tip,
        pairs,
        bounds,
    )


def edge_text(both: BothMap, row: int, left: int) -> str:
    """Which sweep changes label across the ω edge (row, left | left + 1), with its type."""
    if left < 0 or left + 1 >= len(both.omega):
        return "map edge"
    found = []
    for sweep, labels in (("down", both.down), ("up", both.up)):
        if labels[row, left] != labels[row, left + 1]:
            kind = both.types.get(sweep, {}).get((row, left), "?")
            found.append(f"{sweep} {kind}")
    return " + ".join(found) or "no label change"


def run_bounds(inside: np.ndarray, both: BothMap) -> Counter:
    """For every run of a region's cells along a row: (its high-ω end, its low-ω end)."""
    out = Counter()
    for row in np.unique(np.nonzero(inside)[0]):
        line = np.concatenate([[0], inside[row].astype(np.int8), [0]])
        edges = np.flatnonzero(np.diff(line))
        for a, b in zip(edges[::2], edges[1::2] - 1, strict=True):  # columns a … b
            # columns run ω down: a − 1 | a is the high-ω end, b | b + 1 the low-ω end
            out[(edge_text(both, row, a - 1), edge_text(both, row, b))] += 1
    return out


# -- irreversible transitions -------------------------------------------------------------


@dataclass(frozen=True)
class Crossings:
    """The label changes of one sweep along ω and where the other sweep crosses them back."""

    sweep: str
    total: int
    same: int  # the other sweep has the same label pair at the same edge
    near: int  # … within NEAR edges (not the same)
    far: int  # … farther along the row
    never: int  # the reverse pair nowhere in the row
    far_omega: list  # |Δω| of the far ones
    irreversible: list  # ((from, to), edges), from → to in the sweep's own direction
    irreversible_omega: dict  # (from, to) → (ω low, ω high) of its edges


def irreversibility(m: BothMap, sweep: str = "down") -> Crossings:
    """Each label change of ``sweep`` along ω, and where the other sweep crosses it back."""
    own, other = (m.down, m.up) if sweep == "down" else (m.up, m.down)
    left, right = own[:, :-1], own[:, 1:]
    change = (left != right) & (left != "") & (right != "")
    same = change & (other[:, :-1] == left) & (other[:, 1:] == right)
    counts = Counter()
    far_omega, pairs, where = [], Counter(), {}
    step = np.abs(np.diff(m.omega))
    for i, j in zip(*np.nonzero(change & ~same), strict=True):
        a, b = str(left[i, j]), str(right[i, j])
        # the sweep runs ω down from column j to j + 1, or up from j + 1 to j
        pair = (a, b) if sweep == "down" else (b, a)
        match = np.flatnonzero((other[i, :-1] == a) & (other[i, 1:] == b))
        if match.size == 0:
            counts["never"] += 1
            pairs[pair] += 1
            lo, hi = where.get(pair, (np.inf, -np.inf))
            where[pair] = (min(lo, float(m.omega[j + 1])), max(hi, float(m.omega[j])))
            continue
        k = match[np.argmin(np.abs(match - j))]
        if abs(k - j) <= NEAR:
            counts["near"] += 1
        else:
            counts["far"] += 1
            far_omega.append(float(step[min(j, k) : max(j, k)].sum()))
    return Crossings(
        sweep,
        int(change.sum()),
        int(same.sum()),
        counts["near"],
        counts["far"],
        counts["never"],
        far_omega,
        pairs.most_common(),
        where,
    )


# -- the census ----------------------------------------------------------------------------


@dataclass
class Census:
    omega: np.ndarray
    second: np.ndarray
    name: str
    n_attractors: np.ndarray  # (rows, columns), −1 not computed
    labels: np.ndarray  # (rows, columns, cap) attractor labels
    unsettled: np.ndarray
    starts: int


def load_census(store) -> Census:
    from ..views.dataset import open as open_store

    with open_store(store) as ds:
        second = ds["n_attractors"].dims[0]
        starts = json.loads(ds.attrs["job"])["attractors"]["starts"]
        return Census(
            ds["omega"].values,
            ds[second].values,
            second,
            ds["n_attractors"].values.astype(np.int64),
            ds["attractor_label"].values,
            ds["unsettled_starts"].values,
            starts,
        )


def attractor_sets(c: Census, mask: np.ndarray) -> list:
    """((labels …), cells) of the multistable cells in ``mask``, most cells first (the
    attractors stored, most frequent first; at most the store's cap)."""
    sets = Counter()
    for i, j in zip(*np.nonzero(mask), strict=True):
        sets[tuple(sorted(x for x in c.labels[i, j].tolist() if x))] += 1
    return sets.most_common()


def nearest(centres: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, float]:
    """Index of the centre nearest each value, and the largest distance."""
    k = np.abs(centres[None, :] - values[:, None]).argmin(axis=1)
    return k, float(np.abs(centres[k] - values).max()) if len(values) else 0.0


def census_versus_hysteresis(c: Census, m: BothMap) -> dict:
    """At every census cell, the hysteresis map's nearest cell: hysteretic cells there, and
    how many of them the census finds multistable; exact when the grids coincide."""
    cols, dw = nearest(m.omega, c.omega)
    rows, ds = nearest(m.second, c.second)
    h = m.hysteresis[np.ix_(rows, cols)]
    computed = c.n_attractors >= 0
    multi = c.n_attractors >= 2
    return {
        "exact": dw < 1e-9 and ds < 1e-9,
        "hysteretic": int((h & computed).sum()),
        "confirmed": int((h & multi).sum()),
        "multistable": int((multi & computed).sum()),
        "multistable_hysteretic": int((multi & h).sum()),
    }
