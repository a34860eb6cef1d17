"""One cell the way a researcher computes it today with SciPy: the peer of the benchmarks.

A fixed transient of whole revolutions, then a read window, every revolution
integrated by ``scipy_model.integrate`` (solve_ivp DOP853, piecewise between
cam phase boundaries, exact contact events). The window gives the period n
(smallest n ≤ n_max whose last n section points repeat the n before within
period_tol, ∞-norm), the detachments p in the last n revolutions and the duty
cycle DC (fraction of time with ε < 0) over them — the definitions of
docs/model.md, computed without any of campar's code.
"""

import math
from typing import NamedTuple

import numpy as np

from .scipy_model import integrate


class ScipyCell(NamedTuple):
    label: str  # "n-p", or "NP" (no period ≤ n_max in the window)
    n: int
    p: int
    dc: float
    sections: np.ndarray  # (window + 1, 2) section points, the transient's end first


def separated_time(x_start, events, period: float) -> tuple[float, int]:
    """Time with ε < 0 in one revolution and its detachments, from its event list.

    At θ = 0 the cam is on its base circle (yc = 0), so the follower starts
    separated when ε = −y ≤ 0.
    """
    separated = x_start[0] >= 0.0
    since = 0.0
    total = 0.0
    detachments = 0
    for t, kind in events:
        if kind == "detachment":
            detachments += 1
            separated = True
            since = t
        elif kind == "impact" and separated:
            total += t - since
            separated = False
    if separated:
        total += period - since
    return total, detachments


def period_of(sections: np.ndarray, n_max: int, tol: float) -> int:
    """Smallest n whose last n section points repeat the n before (0: none)."""
    m = len(sections)
    for n in range(1, min(n_max, m // 2) + 1):
        if np.all(np.abs(sections[m - n :] - sections[m - 2 * n : m - n]) <= tol):
            return n
    return 0


def scipy_cell(
    model,
    x0,
    transient: int,
    window: int,
    *,
    rtol: float = 1e-8,
    atol: float | None = None,
    n_max: int = 32,
    period_tol: float = 1e-6,
) -> ScipyCell:
    """Classify one cell from (y, y') = x0 at θ = 0 (see the module docstring)."""
    atol = rtol * 1e-2 if atol is None else atol
    period = 2 * math.pi / model.omega
    x = np.asarray(x0, float)
    if transient > 0:
        x, _, _ = integrate(model, x, transient, rtol=rtol, atol=atol)
    sections = [x]
    free, detach = [], []
    for _ in range(window):
        x_next, events, _ = integrate(model, x, 1, rtol=rtol, atol=atol)
        t_free, p = separated_time(x, events, period)
        free.append(t_free)
        detach.append(p)
        x = x_next
        sections.append(x)
    sections = np.array(sections)
    n = period_of(sections, n_max, period_tol)
    count = n if n else window
    p = sum(detach[-count:])
    dc = sum(free[-count:]) / (count * period)
    return ScipyCell(f"{n}-{p}" if n else "NP", n, p, dc, sections)
