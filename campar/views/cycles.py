"""When two records of a periodic motion are one cycle: the σn points (stroboscopic
section, θ = 0 mod 2π) equal up to a cyclic shift within a tolerance derived from the
kernel's convergence test. One rule for ``campar point --attractors`` (coexisting
attractors of a cell) and a map's ``hysteresis`` (the two sweep directions of a cell).
numpy only: ``campar.open`` uses it without loading the kernel.
"""

import math

import numpy as np

from ..core.codes import Kind, Status

# Two records of one cycle agree within this many times the larger of twice the
# convergence window's tolerance, the kernel's period tolerance and the integrator's rtol.
CYCLE_FACTOR = 5.0


def match_tolerance(window_tol: float, period_tol: float, rtol: float = 0.0) -> float:
    """∞-norm distance within which the σn points of two converged records of one cycle
    agree (1e-5 with the default settings).

    A converged cell's cycle estimate lies within ``transient.conv_tol`` of its last
    section point and within ``transient.window_tol`` of the point n revolutions before
    (campar.core.analysis), and the kernel counts σn points within
    ``classify.period_tol`` as one; each stored σn point is thus within about
    window_tol of the cycle, two records of one cycle within about 2·window_tol. Two
    records reached from different starts (other initial states, the two sweep
    directions) differ also by the integrator's error of the cycle (rtol-level,
    amplified by 1/(1 − λ) for a multiplier λ near 1): CYCLE_FACTOR times the larger of
    these covers it. Measured: two records of one cycle ≤ 1.4e-7 apart over 2447 starts
    of 80 cells; distinct coexisting cycles ≥ 1.6 apart, five orders of magnitude beyond.
    """
    return CYCLE_FACTOR * max(2.0 * window_tol, period_tol, rtol)


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


def same_cycles(n_a, sections_a, n_b, sections_b, tol: float) -> np.ndarray:
    """Per cell: the cycles with σn points ``sections_a[..., :n_a, :]`` and
    ``sections_b[..., :n_b, :]`` (time order) are one, i.e. equal within ``tol``
    (∞-norm) after a cyclic shift. Cycles of different n are compared over lcm(n_a,
    n_b) revolutions, so a 2-cycle whose points coincide is the 1-cycle it repeats.
    Cells where either n < 1 are False; call it on ``settled_cycles`` cells."""
    n_a, n_b = np.asarray(n_a, np.int64), np.asarray(n_b, np.int64)
    sec_a, sec_b = np.asarray(sections_a, float), np.asarray(sections_b, float)
    shape = n_a.shape
    n_a, n_b = n_a.reshape(-1), n_b.reshape(-1)
    sec_a, sec_b = sec_a.reshape(-1, *sec_a.shape[-2:]), sec_b.reshape(-1, *sec_b.shape[-2:])
    same = np.zeros(n_a.size, bool)
    valid = (n_a >= 1) & (n_b >= 1)
    pairs = np.unique(np.stack([n_a[valid], n_b[valid]]), axis=1)
    for na, nb in pairs.T.tolist():  # one vectorised comparison per pair of periods
        cells = np.flatnonzero(valid & (n_a == na) & (n_b == nb))
        length = math.lcm(na, nb)
        a = sec_a[cells][:, np.arange(length) % na]  # (cells, L, 2)
        b = sec_b[cells][:, np.arange(length) % nb]
        for shift in range(nb):  # b is nb-periodic: shifts beyond repeat these
            gap = np.abs(a - np.roll(b, shift, axis=1)).max(axis=(1, 2))
            same[cells] |= gap <= tol
    return same.reshape(shape)


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
