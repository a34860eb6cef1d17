"""The multistability map: how many distinct attractors each cell's census found.

A job with the ``attractors`` key stores ``n_attractors`` per cell
(``campar.sweep.multistable``): the distinct attractors that its starts and its
chain's own end state reached. This map draws it as categories 1, 2, 3 and 4+ (and
0 where nothing settled), with cells not computed hatched as on every map.
"""

import numpy as np

from .labels import computed_cells

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
    from .maps import draw_codes  # maps imports this module

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
