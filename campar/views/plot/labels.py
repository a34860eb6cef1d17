"""Categories of a map's cells (n-p labels, kinds of motion) and their colours.

Any two categories shown on one map differ by CIEDE2000 ΔE00 ≥ MIN_DELTA_E00 (10;
``colour.ciede2000``), and every category on a map is named in its legend:

- a designed table gives the common periodic labels (n ≤ 4, small p), the grouped
  chattering ones and the kinds one fixed colour each, the same in every figure;
  any two colours of the table (white included) are ≥ 10 apart;
- chattering-impact motions (p ≥ chatter_p, written n-p̃) are grouped per n, as in
  the paper: every n-p̃ with the same n is one category "n-p~";
- any other (rare) label has a preferred colour computed from (n, p) by a fixed
  rule (``fallback_colour``); on a map (``distinct_categories``) it keeps that colour
  when it is ≥ 10 from every colour already there, else it takes the first colour of
  POOL that is (POOL: colours ≥ 11.5 from the table and from each other); labels left
  without a colour, or beyond the legend's room, are grouped in one hatched class
  "other" whose members its legend entry lists;
- the non-periodic kinds are greys: quasi-periodic mid grey, chaos near-black,
  unconverged light grey; cells without a result are gaps, hatched on white
  (failed: dark red cross-hatch; not computed yet: light grey hatch).
"""

import functools
import re
from dataclasses import dataclass

import numpy as np
from matplotlib.colors import hsv_to_rgb, to_rgba

from ...core.codes import Kind
from .colour import ciede2000, srgb_to_lab

RGBA = tuple[float, float, float, float]

CHATTER = "p~"  # the p of a grouped chattering label "n-p~" (n-p̃)

# Categories that are not n-p labels, in legend order.
QUASIPERIODIC = "QP"
CHAOS = "chaos"
UNCONVERGED = "unconverged"
FAILED = "failed"
NOT_COMPUTED = "not computed"
PERIODIC = "periodic"  # only in kind maps, where n and p are not shown
OTHER = "other"  # the rare n-p labels of a map left without a colour of their own, hatched
NON_PERIODIC = (QUASIPERIODIC, CHAOS, UNCONVERGED, FAILED, NOT_COMPUTED)

KIND_CATEGORY = {
    Kind.PERIODIC: PERIODIC,
    Kind.QUASIPERIODIC: QUASIPERIODIC,
    Kind.CHAOTIC: CHAOS,
    Kind.UNCONVERGED: UNCONVERGED,
    Kind.FAILED: FAILED,
}

# Cells without a result are hatched on white, so they read as gaps, not as motions:
# failed cells cross-hatched in dark red, cells not computed yet in light grey.
GAP_STYLE = {
    "failed": {"facecolor": "white", "edgecolor": "#b2182b", "hatch": "xxxxx", "linewidth": 0.0},
    "not computed": {"facecolor": "white", "edgecolor": "0.7", "hatch": "////", "linewidth": 0.0},
}
OTHER_STYLE = {"facecolor": "#b1b1de", "edgecolor": "0.15", "hatch": "....", "linewidth": 0.0}

# fmt: off
DESIGNED = {
    # 1-p: the large regions; Tableau-like hues, 1-0 (no detachment) a pale sand.
    "1-0": "#e9dfb8", "1-1": "#4e79a7", "1-2": "#f28e2b", "1-3": "#59a14f",
    "1-4": "#e15759", "1-5": "#9c6fc0", "1-6": "#9c755f",
    # 2-2p is the period doubling of 1-p: a light version of its hue.
    "2-0": "#b9e0c9", "2-1": "#499894", "2-2": "#a0cbe8", "2-3": "#86bcb6",
    "2-4": "#ffbe7d", "2-5": "#f1ce63", "2-6": "#8cd17d",
    "3-0": "#f7d6e6", "3-1": "#d37295", "3-2": "#b6992d", "3-3": "#d4a6c8",
    "3-4": "#ff9d9a",
    "4-0": "#bca685", "4-1": "#35c2a0", "4-2": "#c45a3b", "4-3": "#2f7d4f",
    "4-4": "#7c8fcf",
    # chattering n-p̃, grouped per n: dark, but far from the black of chaos.
    "1-p~": "#6b2d5c", "2-p~": "#1f5f5b", "3-p~": "#7a4a12", "4-p~": "#2c3e78",
    QUASIPERIODIC: "#8f8f8f", CHAOS: "#1b1b1b", UNCONVERGED: "#cdcdcd",
    FAILED: "#ffffff", NOT_COMPUTED: "#ffffff", PERIODIC: "#a9b98a",
    OTHER: OTHER_STYLE["facecolor"],
}
# Colours a map gives its rare labels when their own one is too close to a colour already
# there: greedy max-min picks (most distinct first) from a 24-level sRGB grid with
# 30 < L* < 88 and 20 < C* < 80, each ≥ 12 ΔE00 from every DESIGNED colour and from the
# ones before it (≥ 11.5 once rounded to hex; tests/test_palette.py checks it).
POOL = (
    "#434e00", "#900b21", "#c80b6f", "#7a7a43", "#7a37bc", "#f47aff", "#00f4ff", "#855964",
    "#a6bc00", "#a66f0b", "#00a6d3", "#00597a", "#64597a", "#ff7a4e", "#de43bc", "#9b2c00",
    "#006400", "#2c9bff", "#43f4b1", "#6f4337", "#007a90", "#9b4e90", "#6f64e9", "#645937",
    "#b190ff", "#b1434e", "#7a9000", "#7a906f", "#375937", "#ffd3bc", "#7a6400",
)
# fmt: on
MIN_DELTA_E00 = 10.0  # CIEDE2000 distance between any two colours shown on one map

GOLDEN = 0.6180339887498949  # hue step of the fallback rule: successive n land far apart
MIN_DELTA_E = 15.0  # CIE76 distance a fallback colour keeps from every designed one
NEIGHBOUR_LIMIT = 64  # n, p up to which fallbacks also avoid their neighbours' (bounds recursion)

LABEL_PATTERN = re.compile(r"^(\d+)-(\d+|p)(~?)$")


def parse_label(label: str) -> tuple[int, int | None] | None:
    """(n, p) of an n-p label, p = None for a grouped or single chattering one; else None.

    "2-3" → (2, 3); "1-9~" and "1-p~" → (1, None); "chaos" → None.
    """
    match = LABEL_PATTERN.match(label)
    if match is None:
        return None
    n, p, tilde = match.groups()
    if p == "p" or tilde:
        return int(n), None
    return int(n), int(p)


def category_of(label: str) -> str:
    """The map category of a cell label: chattering "n-p~" labels grouped per n."""
    parsed = parse_label(label)
    if parsed is not None and parsed[1] is None:
        return label_name(parsed[0], None)
    return label


def label_colour(label: str) -> RGBA:
    """Fixed RGBA colour of a label or category, whatever map it appears in.

    Accepts cell labels ("2-2", "1-9~") and categories ("1-p~", "QP", "chaos",
    "unconverged", "failed", "not computed", "periodic").
    """
    category = category_of(label)
    if category in DESIGNED:
        return to_rgba(DESIGNED[category])
    parsed = parse_label(category)
    if parsed is None:
        raise ValueError(f"not a map label: {label!r}")
    return fallback_colour(*parsed)


@functools.lru_cache(maxsize=4096)
def fallback_colour(n: int, p: int | None) -> RGBA:
    """Deterministic colour of a rare label from (n, p); p = None for chattering n-p̃.

    Candidates walk the colour circle in golden-ratio steps of n, p and the attempt;
    the first one at least MIN_DELTA_E from every designed colour and from the
    fallback colours of the labels likely to border this one in a map (n−1 and
    n−2 with the same p, n with p−1) is taken. Saturation stays ≥ 0.45, so no
    label looks like a grey of the non-periodic kinds.
    """
    q = 0 if p is None else p
    neighbours = [(n - 1, p), (n - 2, p)] + ([] if p is None or p == 0 else [(n, p - 1)])
    avoid = [_designed_lab()] + [
        cielab(fallback_colour(*label))[None]
        for label in neighbours
        if 1 <= label[0] <= NEIGHBOUR_LIMIT
        and q <= NEIGHBOUR_LIMIT
        and label_name(*label) not in DESIGNED
    ]
    avoid = np.concatenate(avoid)
    for attempt in range(64):
        hue = (0.07 + GOLDEN * n + 0.29 * q + 0.5 * GOLDEN * attempt) % 1.0
        saturation = 0.45 + 0.3 * ((0.37 * n + GOLDEN * (q + attempt)) % 1.0)
        if p is None:  # chattering: dark like the designed n-p̃
            value = 0.35 + 0.15 * ((GOLDEN * attempt) % 1.0)
        else:
            value = 0.62 + 0.3 * ((GOLDEN * (n + 2 * q + attempt)) % 1.0)
        rgb = hsv_to_rgb((hue, saturation, value))
        if np.min(np.linalg.norm(avoid - cielab(rgb), axis=1)) >= MIN_DELTA_E:
            break
    return float(rgb[0]), float(rgb[1]), float(rgb[2]), 1.0


def label_name(n: int, p: int | None) -> str:
    """The category name of (n, p); p = None for chattering: (2, 3) → "2-3", (1, None) → "1-p~"."""
    return f"{n}-{CHATTER if p is None else p}"


cielab = srgb_to_lab  # CIE L*a*b* (D65) of sRGB colours in [0, 1], shape (..., 3) → (..., 3)


@functools.cache
def _designed_lab() -> np.ndarray:
    return cielab(np.array([to_rgba(c) for c in DESIGNED.values()]))


def legend_text(category: str) -> str:
    """Text of a category in a legend, in the paper's notation (n-p̃ for chattering)."""
    if category.endswith(CHATTER):
        return category.removesuffix(CHATTER) + r"$\tilde{p}$"
    if category == QUASIPERIODIC:
        return "quasi-periodic"
    return category


def members_text(members, per_line: int = 4) -> str:
    """The labels of an "other" class, a few per line, in the paper's notation."""
    texts = [legend_text(m) for m in members]
    return "\n".join(", ".join(texts[i : i + per_line]) for i in range(0, len(texts), per_line))


def order_key(category: str) -> tuple:
    """Legend order: n then p (n-p̃ after every n-p of its n), then the other kinds."""
    parsed = parse_label(category)
    if parsed is not None:
        n, p = parsed
        return (0, n, np.inf if p is None else p)
    if category == PERIODIC:
        return (0, 0, 0)
    if category == OTHER:
        return (0, np.inf, np.inf)
    return (1, NON_PERIODIC.index(category), 0)


@dataclass(frozen=True)
class LegendEntry:
    """One category of a map: its label, number of cells and colour."""

    label: str  # "2-2", "1-p~", "QP", "chaos", "other", …
    count: int
    colour: RGBA
    members: tuple[str, ...] = ()  # the labels grouped in "other"

    @property
    def text(self) -> str:
        if self.label == OTHER:
            return f"other, hatched:\n{members_text(self.members)}"
        return legend_text(self.label)


@dataclass(frozen=True)
class CategoryMap:
    """Cells of a map sorted into categories.

    ``codes`` (second, omega) indexes ``entries``; ``entries`` holds only the
    categories present, in legend order, with their cell counts.
    """

    codes: np.ndarray
    entries: tuple[LegendEntry, ...]

    @property
    def labels(self) -> np.ndarray:
        """The category of every cell as a string array, shaped like ``codes``."""
        names = np.array(self.labels_present or [""])
        return names[self.codes]

    @property
    def labels_present(self) -> list[str]:
        return [entry.label for entry in self.entries]


# Keys of the non-n-p categories in the integer encoding of map_labels (all < 0).
_NON_PERIODIC_KEYS = {name: -1 - i for i, name in enumerate(NON_PERIODIC)}
_P_CHATTER = 1 << 20  # stands for p̃ in the integer key n · 2^21 + p


def computed_cells(arrays, shape) -> np.ndarray:
    computed = arrays.get("computed")
    if computed is None:
        return np.ones(shape, bool)
    return np.asarray(computed, bool)


def map_labels(arrays, chatter_p: int = 7) -> CategoryMap:
    """n-p categories of every cell, with the legend of those present.

    ``arrays`` maps "kind", "n", "p" (and optionally "computed", a boolean mask
    of cells already computed) to arrays shaped (second, omega). Labels follow
    ``campar.core.codes.cell_label``; chattering ones are grouped per n ("1-p~").
    Cells holding a store's fill (kind −1) or zeros (a periodic cell with n < 1,
    which the kernel never writes) count as not computed.
    """
    kind = np.asarray(arrays["kind"])
    n = np.asarray(arrays["n"]).astype(np.int64)
    p = np.asarray(arrays["p"]).astype(np.int64)
    computed = computed_cells(arrays, kind.shape)
    key = n * (2 * _P_CHATTER) + np.where(p >= chatter_p, _P_CHATTER, np.clip(p, 0, None))
    periodic = kind == Kind.PERIODIC
    for value, name in KIND_CATEGORY.items():
        if value != Kind.PERIODIC:
            key = np.where(kind == value, _NON_PERIODIC_KEYS[name], key)
    unknown = ~np.isin(kind, list(KIND_CATEGORY))
    key = np.where(unknown, _NON_PERIODIC_KEYS[FAILED], key)
    pending = ~computed | (kind < 0) | (periodic & (n < 1))
    key = np.where(pending, _NON_PERIODIC_KEYS[NOT_COMPUTED], key)

    def category(k: int) -> str:
        if k < 0:
            return NON_PERIODIC[-1 - k]
        cell_n, cell_p = divmod(k, 2 * _P_CHATTER)
        return label_name(cell_n, None if cell_p == _P_CHATTER else cell_p)

    return categorise(key, category)


def map_kinds(arrays) -> CategoryMap:
    """Kind of motion of every cell (periodic, QP, chaos, unconverged, failed, not computed)."""
    kind = np.asarray(arrays["kind"]).astype(np.int64)
    computed = computed_cells(arrays, kind.shape)
    key = np.where(np.isin(kind, list(KIND_CATEGORY)), kind, int(Kind.FAILED))
    key = np.where(computed & (kind >= 0), key, -1)  # kind −1: a store's fill
    names = {int(k): v for k, v in KIND_CATEGORY.items()} | {-1: NOT_COMPUTED}
    return categorise(key, names.__getitem__)


def categorise(key: np.ndarray, category) -> CategoryMap:
    """Group integer cell keys into categories (named by ``category(key)``) in legend order."""
    unique, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    names = [category(int(k)) for k in unique]
    order = sorted(range(len(names)), key=lambda i: order_key(names[i]))
    rank = np.empty(len(order), np.intp)
    rank[order] = np.arange(len(order))
    entries = tuple(LegendEntry(names[i], int(counts[i]), label_colour(names[i])) for i in order)
    return CategoryMap(rank[inverse.reshape(key.shape)], entries)


def distinct_categories(cells: CategoryMap, max_entries: int | None = None) -> CategoryMap:
    """The map's categories with colours pairwise ≥ MIN_DELTA_E00 apart, every one named.

    Designed categories keep their colour. Rare labels, most cells first, keep their
    ``fallback_colour`` when it is ≥ MIN_DELTA_E00 from every colour taken so far, else
    take the first POOL colour that is; those left without one, and with
    ``max_entries`` (the legend's room) those beyond it, are merged into the hatched
    category OTHER, whose entry lists them (``members``).
    """
    entries = list(cells.entries)
    fixed = [e for e in entries if e.label in DESIGNED]
    rare = sorted(
        (e for e in entries if e.label not in DESIGNED),
        key=lambda e: (-e.count, order_key(e.label)),
    )
    if not rare:
        return cells
    room = len(rare)
    if max_entries is not None and len(fixed) + len(rare) > max_entries:
        room = max(max_entries - len(fixed) - 1, 0)  # one line for "other"
    used = srgb_to_lab(np.array([*(e.colour for e in fixed), to_rgba(DESIGNED[OTHER])]))
    pool = [to_rgba(c) for c in POOL]
    coloured, others = {}, []
    for entry in rare:
        colour = None
        if len(coloured) < room:
            candidates = [entry.colour, *pool]
            lab = srgb_to_lab(np.array(candidates))
            far = ciede2000(lab[:, None, :], used[None, :, :]).min(axis=1) >= MIN_DELTA_E00
            if far.any():
                k = int(np.argmax(far))
                colour = candidates[k]
                used = np.concatenate([used, lab[k : k + 1]])
        if colour is None:
            others.append(entry)
        else:
            coloured[entry.label] = colour
    kept = [e for e in entries if e.label in DESIGNED or e.label in coloured]
    new = [LegendEntry(e.label, e.count, coloured.get(e.label, e.colour)) for e in kept]
    if others:
        members = tuple(sorted((e.label for e in others), key=order_key))
        new.append(
            LegendEntry(OTHER, sum(e.count for e in others), to_rgba(DESIGNED[OTHER]), members)
        )
    new.sort(key=lambda e: order_key(e.label))
    index = {e.label: i for i, e in enumerate(new)}
    remap = np.array([index.get(e.label, index.get(OTHER, -1)) for e in entries], np.intp)
    return CategoryMap(remap[cells.codes], tuple(new))
