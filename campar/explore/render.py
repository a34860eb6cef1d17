"""A view's cells as an image, and its legend: the maps' palette, gaps hatched.

Categories take the colours of ``campar plot`` (``campar.views.plot.labels``): the
designed table, rare labels kept ΔE00 ≥ 10 apart by ``distinct_categories``, failed cells
cross-hatched in dark red and cells not computed (or masked as damaged) hatched light
grey on white. Numbers are drawn with viridis over the map's own range, NaN hatched as
not computed. The image is a PNG encoded here (zlib, no imaging library).
"""

import functools
import struct
import zlib

import numpy as np
from matplotlib import colormaps
from matplotlib.colors import to_rgba

from ..views.plot.labels import (
    DESIGNED,
    FAILED,
    GAP_STYLE,
    NOT_COMPUTED,
    POOL,
    CategoryMap,
    LegendEntry,
    distinct_categories,
    label_colour,
    order_key,
)
from .source import NO_CELL, PENDING_CELL

BACKGROUND = (0, 0, 0, 0)  # outside the grid: transparent, the page's own colour
HATCH_PERIOD = 6  # pixels between hatch lines
LEGEND_ROOM = 24  # categories named before the rarest are grouped as "other"
VIRIDIS = (colormaps["viridis"](np.linspace(0, 1, 256)) * 255).round().astype(np.uint8)


@functools.lru_cache(maxsize=1024)
def rgb255(colour) -> tuple[int, int, int, int]:
    return tuple(int(round(c * 255)) for c in to_rgba(colour))


@functools.lru_cache(maxsize=64)
def category_legend(names: tuple[str, ...], counts: tuple, sets: bool = False):
    """(legend rows, colours): rows {label, count, colour, members} in legend order over
    the map's counts ((category, cells) pairs), and the RGBA (uint8) of every category id
    of ``names``. Cached: a view of a map that is not growing reuses its legend.
    ``sets``: the categories are sets of coexisting attractors (``set_legend``)."""
    if sets:
        return set_legend(names, counts)
    counted = dict(counts)
    present = sorted(counted, key=order_key)
    cells = CategoryMap(
        np.arange(len(present)),
        tuple(LegendEntry(n, counted[n], label_colour(n)) for n in present),
    )
    shown = distinct_categories(cells, LEGEND_ROOM)
    colour_of = {}
    for name, code in zip(present, shown.codes.tolist(), strict=True):
        colour_of[name] = shown.entries[code].colour
    colours = np.array(
        [rgb255(colour_of[n] if n in colour_of else _colour(n)) for n in names] or np.zeros((0, 4)),
        np.uint8,
    ).reshape(-1, 4)
    rows = [
        {
            "label": e.label,
            "count": e.count,
            "colour": "#{:02x}{:02x}{:02x}".format(*rgb255(e.colour)[:3]),
            "members": list(e.members),
            "hatch": e.label in GAP_STYLE,
        }
        for e in shown.entries
    ]
    return rows, colours


def set_legend(names: tuple[str, ...], counts: tuple):
    """The legend of attractor sets as ``campar plot --what attractor_sets`` draws them:
    sets of several attractors a POOL colour each by cells, single attractors grey."""
    counted = dict(counts)
    several = sorted((n for n in counted if "+" in n), key=lambda n: -counted[n])
    colour_of = {n: POOL[k % len(POOL)] for k, n in enumerate(several)}
    rows = [
        {
            "label": n,
            "count": counted[n],
            "colour": "#{:02x}{:02x}{:02x}".format(*rgb255(_set_colour(n, colour_of))[:3]),
            "members": [],
            "hatch": n == NOT_COMPUTED,
        }
        for n in [*several, *sorted(n for n in counted if n not in colour_of)]
    ]
    colours = np.array(
        [rgb255(_set_colour(n, colour_of)) for n in names] or np.zeros((0, 4)), np.uint8
    ).reshape(-1, 4)
    return rows, colours


def _set_colour(name: str, colour_of: dict):
    if name in colour_of:
        return colour_of[name]
    return "white" if name in (NOT_COMPUTED, "none settled") else "0.82"


@functools.lru_cache(maxsize=1024)
def _colour(name: str):
    """A category's own colour (white for a name the palette does not know)."""
    try:
        return label_colour(name)
    except ValueError:
        return "white"


def draw_categories(values: np.ndarray, inside: np.ndarray, names, colours) -> np.ndarray:
    """RGBA (height, width, 4) of a categorical view (``MapSource.view``)."""
    # one lookup: ids shifted by 2 so that NO_CELL (-1) and PENDING_CELL (-2) index it too
    lut = np.zeros((len(colours) + 2, 4), np.uint8)
    lut[0] = rgb255(DESIGNED[NOT_COMPUTED])
    lut[1] = BACKGROUND
    lut[2:] = colours
    image = lut[values.astype(np.intp) + 2]
    gaps = [g for g in (FAILED, NOT_COMPUTED) if g in names]
    pending = inside & (values == PENDING_CELL)
    for gap in gaps:
        where = values == names.index(gap)
        _hatch(image, where | pending if gap == NOT_COMPUTED else where, gap)
    if NOT_COMPUTED not in gaps:
        _hatch(image, pending, NOT_COMPUTED)
    image[~inside] = BACKGROUND
    return image


def draw_numbers(values: np.ndarray, inside: np.ndarray, low: float, high: float) -> np.ndarray:
    """RGBA (height, width, 4) of a numeric view over [low, high] with viridis."""
    h, w = values.shape
    image = np.zeros((h, w, 4), np.uint8)
    finite = np.isfinite(values) & inside
    span = high - low if high > low else 1.0
    k = np.clip(((values[finite] - low) / span * 255).round(), 0, 255).astype(np.intp)
    image[finite] = VIRIDIS[k]
    _hatch(image, inside & ~finite, NOT_COMPUTED)
    image[~inside] = BACKGROUND
    return image


def _hatch(image: np.ndarray, where: np.ndarray, gap: str) -> None:
    """White with lines in the gap's colour: '/' for not computed, 'x' for failed."""
    y, x = np.nonzero(where)
    if not len(y):
        return
    line = (x + y) % HATCH_PERIOD == 0
    if gap == FAILED:
        line |= (x - y) % HATCH_PERIOD == 0
    image[y, x] = rgb255(DESIGNED[gap])
    image[y[line], x[line]] = rgb255(GAP_STYLE[gap]["edgecolor"])


def png(image: np.ndarray) -> bytes:
    """An RGBA uint8 image (height, width, 4) as PNG bytes (filter none, zlib level 1)."""
    h, w, _ = image.shape
    raw = np.zeros((h, 1 + 4 * w), np.uint8)
    raw[:, 1:] = image.reshape(h, 4 * w)

    def chunk(kind: bytes, data: bytes) -> bytes:
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(raw.tobytes(), 1))
        + chunk(b"IEND", b"")
    )


def value_range(grid: np.ndarray) -> tuple[float, float]:
    """The finite range of a numeric field (0, 1 when it has no finite value)."""
    finite = grid[np.isfinite(grid)]
    if finite.size == 0:
        return 0.0, 1.0
    return float(finite.min()), float(finite.max())


__all__ = ["NO_CELL", "category_legend", "draw_categories", "draw_numbers", "png", "value_range"]
