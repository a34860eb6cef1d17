"""Categories of a map's cells (n-p labels, kinds of motion) and their fixed colours.

The colour of a label depends on the label alone, never on which other labels a
map holds, so one motion has one colour in every figure of a paper:

- a designed table for the common periodic labels (n ≤ 4, small p), chosen so that
  any two of them and the greys below differ by CIE76 ΔE ≥ 15;
- chattering-impact motions (p ≥ chatter_p, written n-p̃) are grouped per n, as in
  the paper: every n-p̃ with the same n is one category "n-p~" with one dark colour;
- any other label gets a colour computed from (n, p) by a fixed rule that keeps it
  ΔE ≥ 15 from every designed colour (two rare labels may still look alike);
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

RGBA = tuple[float, float, float, float]

CHATTER = "p~"  # the p of a grouped chattering label "n-p~" (n-p̃)

# Categories that are not n-p labels, in legend order.
QUASIPERIODIC = "QP"
CHAOS = "chaos"
UNCONVERGED = "unconverged"
FAILED = "failed"
NOT_COMPUTED = "not computed"
PERIODIC = "periodic"  # only in kind maps, where n and p are not shown
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

# fmt: off
DESIGNED = {
    # 1-p: the large regions; Tableau-like hues, 1-0 (no detachment) a pale sand.
    "1-0": "#e9dfb8", "1-1": "#4e79a7", "1-2": "#f28e2b", "1-3": "#59a14f",
    "1-4": "#e15759", "1-5": "#b07aa1", "1-6": "#9c755f",
    # 2-2p is the period doubling of 1-p: a light version of its hue.
    "2-0": "#b9e0c9", "2-1": "#499894", "2-2": "#a0cbe8", "2-3": "#86bcb6",
    "2-4": "#ffbe7d", "2-5": "#f1ce63", "2-6": "#8cd17d",
    "3-0": "#f7d6e6", "3-1": "#d37295", "3-2": "#b6992d", "3-3": "#d4a6c8",
    "3-4": "#ff9d9a",
    "4-0": "#e0c27a", "4-1": "#35c2a0", "4-2": "#c45a3b", "4-3": "#3f8f5f",
    "4-4": "#7c8fcf",
    # chattering n-p̃, grouped per n: dark, but far from the black of chaos.
    "1-p~": "#6b2d5c", "2-p~": "#1f5f5b", "3-p~": "#7a4a12", "4-p~": "#2c3e78",
    QUASIPERIODIC: "#8f8f8f", CHAOS: "#1b1b1b", UNCONVERGED: "#cdcdcd",
    FAILED: "#ffffff", NOT_COMPUTED: "#ffffff", PERIODIC: "#a9b98a",
}
# fmt: on

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


def cielab(rgb) -> np.ndarray:
    """CIE L*a*b* (D65) of sRGB colours in [0, 1], shape (..., 3) → (..., 3)."""
    rgb = np.asarray(rgb, float)[..., :3]
    linear = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    xyz = linear @ _SRGB_TO_XYZ.T / _D65_WHITE
    f = np.where(xyz > 0.008856, np.cbrt(xyz), 7.787 * xyz + 16 / 116)
    return np.stack(
        [116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])],
        axis=-1,
    )


def delta_e(colour_a, colour_b) -> float:
    """CIE76 colour difference ΔE*ab of two colours (≈ 2.3: just noticeable)."""
    return float(np.linalg.norm(cielab(to_rgba(colour_a)) - cielab(to_rgba(colour_b))))


_SRGB_TO_XYZ = np.array(
    [[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]
)
_D65_WHITE = np.array([0.95047, 1.0, 1.08883])


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


def order_key(category: str) -> tuple:
    """Legend order: n then p (n-p̃ after every n-p of its n), then the other kinds."""
    parsed = parse_label(category)
    if parsed is not None:
        n, p = parsed
        return (0, n, np.inf if p is None else p)
    if category == PERIODIC:
        return (0, 0, 0)
    return (1, NON_PERIODIC.index(category), 0)


@dataclass(frozen=True)
class LegendEntry:
    """One category of a map: its label, number of cells and colour."""

    label: str  # "2-2", "1-p~", "QP", "chaos", …
    count: int
    colour: RGBA

    @property
    def text(self) -> str:
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
