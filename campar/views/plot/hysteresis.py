"""Maps of a two-direction store: which direction a map draws, and the hysteresis map.

A ``chains.direction: both`` store holds every cell twice, swept down and up
(``campar.sweep.plan``). Its label, kind and quantity maps draw one direction
(``drawn_layer``: down unless asked). Its hysteresis map draws, per cell,
whether the two directions ended on different converged cycles
(``campar.views.cycles.hysteresis_cells``): hysteretic, one cycle both ways, or
not compared (either direction not periodic, unconverged or failed). The store
is read a pair of tiles (one row range, both directions) at a time, after the
whole store was verified, so memory does not grow with the map.
"""

import numpy as np

from ...sweep.job import DIRECTIONS, Job
from ...sweep.plan import plan_tiles
from ..cycles import hysteresis_cells, settled_cycles
from ..dataset import cycle_tolerance
from .cells import draw_codes
from .labels import computed_cells
from .requests import PlotError

# What the hysteresis of a cell is computed from (per direction).
HYSTERESIS_ARRAYS = ("kind", "status", "n", "sections")
# Categories of the hysteresis map: value, legend text, colour.
CATEGORIES = (
    (0, "not compared (not periodic both ways)", "white"),
    (1, "one cycle both ways", "0.78"),
    (2, "hysteresis: different cycles", "#c0392b"),
)


def drawn_layer(job: Job, what: str, direction: str | None) -> int | None:
    """Index along a ``both`` store's direction axis of the map to draw (None: a store
    without one, or the hysteresis map, which draws both); PlotError for a direction
    the store does not hold."""
    both = job.chains.direction == "both"
    if what == "hysteresis":
        if not both:
            raise PlotError(
                f"a hysteresis map needs a store of a chains.direction: both job; this one "
                f"ran {job.chains.direction} only"
            )
        if direction is not None:
            raise PlotError("a hysteresis map compares both directions: drop --direction")
        return None
    if direction is not None and direction not in DIRECTIONS:
        raise PlotError(f"direction must be one of {', '.join(DIRECTIONS)}, got {direction!r}")
    if not both:
        if direction not in (None, job.chains.direction):
            raise PlotError(
                f"this store's chains ran {job.chains.direction} only; it has no {direction} map"
            )
        return None
    return DIRECTIONS.index(direction or DIRECTIONS[0])


def store_hysteresis(store, verified: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> dict:
    """``hysteresis``, ``compared`` (both directions periodic) and ``computed`` (both
    tiles verified) of the drawn cells ``rows`` × ``cols`` of a ``both`` store; a pair of
    tiles read at a time. ``verified``: per tile, committed and intact (verify_store)."""
    job = store.job
    tol = cycle_tolerance(job)
    shape = (len(rows), len(cols))
    out = {name: np.zeros(shape, bool) for name in ("hysteresis", "compared", "computed")}
    slot = np.full(job.shape[0], -1)
    slot[rows] = np.arange(len(rows))
    tiles = plan_tiles(job)
    half = len(tiles) // 2  # tile i runs down what tile half + i runs up
    for down, up in zip(tiles[:half], tiles[half:], strict=True):
        local = slot[down.rows]
        keep = local >= 0
        if not keep.any() or not (verified[down.index] and verified[up.index]):
            continue
        sides = [
            {name: store.read_tile(name, tile)[keep][:, cols] for name in HYSTERESIS_ARRAYS}
            for tile in (down, up)
        ]
        out["hysteresis"][local[keep]] = hysteresis_cells(*sides, tol)
        out["compared"][local[keep]] = settled_cycles(**sides[0]) & settled_cycles(**sides[1])
        out["computed"][local[keep]] = True
    return out


def draw_hysteresis(ax, xe, ye, arrays, *, legend: bool) -> None:
    """Hysteretic, one cycle, not compared as flat colours; cells not computed hatched."""

    hysteretic = np.asarray(arrays["hysteresis"], bool)
    computed = computed_cells(arrays, hysteretic.shape)
    compared = np.asarray(arrays.get("compared", hysteretic), bool)
    codes = np.where(hysteretic, 2, np.where(compared, 1, 0))
    draw_codes(ax, xe, ye, codes, computed, CATEGORIES, legend=legend, title="down vs up (cells)")
