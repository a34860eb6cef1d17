"""When two records of a periodic motion are one cycle: the σn points (stroboscopic
section, θ = 0 mod 2π) equal up to a cyclic shift within a tolerance derived from the
kernel's convergence test. One rule for ``campar point --attractors`` (coexisting
attractors of a cell) and a map's ``hysteresis`` (the two sweep directions of a cell).
numpy only: ``campar.open`` uses it without loading the kernel.
"""

import numpy as np

from ..core.codes import Kind, Status

# The rule itself lives in the sweep layer, which a map's census of attractors uses too.
from ..sweep.census import CYCLE_FACTOR, match_tolerance, same_cycles

__all__ = ["CYCLE_FACTOR", "hysteresis_cells", "match_tolerance", "same_cycles", "settled_cycles"]


def settled_cycles(kind, status, n, sections) -> np.ndarray:
    """Cells whose motion is a converged periodic one with its whole cycle recorded: kind
    periodic, status ok, 1 ≤ n ≤ the section points stored, those n points finite.
    Not computed cells (kind −1), non-periodic, unconverged and failed ones are not."""
    kind, status, n = (np.asarray(a) for a in (kind, status, n))
    sections = np.asarray(sections, float)
    s = sections.shape[-2]
    ok = (kind == Kind.PERIODIC) & (status == Status.OK) & (n >= 1) & (n <= s)
    finite = np.isfinite(sections).all(axis=-1)  # (…, S): point j recorded
    first_n = np.arange(s) < np.clip(n, 0, s)[..., None]
    return ok & np.all(finite | ~first_n, axis=-1)


def hysteresis_cells(down: dict, up: dict, tol: float) -> np.ndarray:
    """True where the two directions end on different converged periodic attractors.

    ``down``, ``up``: arrays ``kind``, ``status``, ``n``, ``sections`` of the same cells.
    A cell is hysteretic when both directions settled on a cycle (``settled_cycles``)
    and the cycles are not one (``same_cycles`` within ``tol``); anywhere else —
    either direction quasi-periodic, chaotic, unconverged, failed or not computed — it
    is False: coexistence there is not decided by this test (never NaN).
    """
    both = settled_cycles(**_cycle_arrays(down)) & settled_cycles(**_cycle_arrays(up))
    out = np.zeros(both.shape, bool)
    if both.any():
        same = same_cycles(
            down["n"][both], down["sections"][both], up["n"][both], up["sections"][both], tol
        )
        out[both] = ~same
    return out


def _cycle_arrays(arrays: dict) -> dict:
    return {name: np.asarray(arrays[name]) for name in ("kind", "status", "n", "sections")}
