"""Which attractors coexist at a cell of a census map (job key ``attractors``): its set.

A cell's census stores the n, p and kind of its first ``attractors.cap`` attractors
(``campar.sweep.multistable``); its set is their labels, ordered (periodic ones first, by
n then p) and joined, e.g. "1-1 + 3-2", with " + …" when more attractors coexist than
the store keeps. Two cells with the same attractors have the same set whatever order
their basins ranked them in. ``campar plot --what attractor_sets`` draws the sets,
``campar status`` counts the cells of each.

May import core and this package's job (numpy only: ``campar status`` loads no kernel).
"""

import numpy as np

from ..core.codes import cell_label

BITS = 21  # of each field in a slot's key: n and p up to 2^21 − 2
MORE = " + …"  # more attractors coexist than the store keeps


def attractor_sets(kind, n, p, count, chatter_p: int = 7) -> tuple[np.ndarray, list[str]]:
    """(code of each cell's set, the sets' names): ``kind``, ``n``, ``p`` shaped
    (…, cap) — a slot without an attractor has kind −1 —, ``count`` (…) the attractors
    found (``n_attractors``). Names are "" for a cell with none, a label for one."""
    kind = np.asarray(kind, np.int64)
    cap = kind.shape[-1]
    shape = kind.shape[:-1]
    kind = kind.reshape(-1, cap)
    n = np.asarray(n, np.int64).reshape(-1, cap)
    p = np.asarray(p, np.int64).reshape(-1, cap)
    empty = kind < 0
    key = ((kind + 1) << (2 * BITS)) | ((n + 1) << BITS) | (p + 1)
    key = np.sort(np.where(empty, np.iinfo(np.int64).max, key), axis=1)  # order-free
    more = np.asarray(count).reshape(-1, 1) > cap
    rows, inverse = np.unique(np.hstack([key, more]), axis=0, return_inverse=True)
    names = [set_name(row[:-1], bool(row[-1]), chatter_p) for row in rows]
    return inverse.reshape(shape), names


def set_name(keys, more: bool, chatter_p: int) -> str:
    mask = (1 << BITS) - 1
    labels = [
        cell_label(
            int(k >> (2 * BITS)) - 1, int((k >> BITS) & mask) - 1, int(k & mask) - 1, chatter_p
        )
        for k in keys
        if k != np.iinfo(np.int64).max
    ]
    return " + ".join(labels) + (MORE if more else "")
