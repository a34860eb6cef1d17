"""The multistability maps: how many distinct attractors each cell's census found, and
which (their set).

A job with the ``attractors`` key stores ``n_attractors`` per cell
(``campar.sweep.multistable``): the distinct attractors that its starts and its
chain's own end state reached, and the first ones' n, p and kind. The count map draws
categories 1, 2, 3 and 4+ (and 0 where nothing settled); the set map
(``draw_attractor_sets``) gives every set of two or more attractors ("1-1 + 3-2",
``campar.sweep.attractor_sets``) a colour of its own, the most frequent first, cells
with one attractor light grey. Cells not computed are hatched as on every map.
"""

import numpy as np

from ...sweep.attractor_sets import attractor_sets
from .cells import draw_codes
from .labels import OTHER_STYLE, POOL, computed_cells

MAX_SETS = 12  # sets with a colour of their own; rarer ones are grouped as "other sets"

# Categories: (lowest count, legend text, colour); a cell falls in the last whose count ≤ it.
CATEGORIES = (
    (0, "none settled", "white"),
    (1, "1 attractor", "0.82"),
    (2, "2 attractors", "#2e86c1"),
    (3, "3 attractors", "#e67e22"),
    (4, "4 or more", "#c0392b"),
)


def multistability_codes(n_attractors) -> np.ndarray:
    """Category index of every cell (CATEGORIES order); −1 where not computed (n < 0)."""
    n = np.asarray(n_attractors)
    n = np.where(np.isfinite(n), n, -1).astype(np.int64)
    return np.where(n < 0, -1, np.clip(n, 0, len(CATEGORIES) - 1))


def draw_multistability(ax, xe, ye, arrays, *, legend: bool) -> None:
    """n_attractors as flat colours by category; cells not computed hatched."""

    codes = multistability_codes(arrays["n_attractors"])
    computed = computed_cells(arrays, codes.shape) & (codes >= 0)
    draw_codes(
        ax,
        xe,
        ye,
        codes,
        computed,
        CATEGORIES,
        legend=legend,
        title="attractors (cells)",
        optional=(0,),
    )  # "none settled" only if it occurs


def draw_attractor_sets(ax, xe, ye, arrays, chatter_p: int, *, legend: bool) -> None:
    """Each cell coloured by its set of coexisting attractors (the MAX_SETS most frequent
    a colour each, from the label palette's distinct POOL), cells with one attractor grey."""

    count = np.asarray(arrays["n_attractors"])
    computed = computed_cells(arrays, count.shape) & (count >= 0)
    sets, names = attractor_sets(
        arrays["attractor_kind"], arrays["attractor_n"], arrays["attractor_p"], count, chatter_p
    )
    several = np.array(["+" in name for name in names])[sets] & computed
    cells = np.bincount(sets[several], minlength=len(names))
    ranked = [int(i) for i in np.argsort(-cells, kind="stable") if cells[i] > 0]
    codes = np.where(count > 0, 1, 0)
    categories = [(0, "none settled", "white"), (1, "1 attractor", "0.82")]
    for rank, index in enumerate(ranked[:MAX_SETS]):
        codes[sets == index] = 2 + rank
        categories.append((2 + rank, names[index], POOL[rank]))
    if len(ranked) > MAX_SETS:
        other = 2 + MAX_SETS
        codes[several & (codes == 1)] = other
        categories.append(
            (other, f"other sets ({len(ranked) - MAX_SETS})", OTHER_STYLE["facecolor"])
        )
    draw_codes(
        ax,
        xe,
        ye,
        codes,
        computed,
        categories,
        legend=legend,
        title="attractor sets (cells)",
        optional=(0,),
    )
