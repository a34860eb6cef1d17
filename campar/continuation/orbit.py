"""A periodic orbit, stable or not, as a fixed point of Pⁿ found by Newton's method.

``find_cycle`` solves Pⁿ(x) = x from a guess with the exact Jacobian DPⁿ (the
variational equations), so it converges quadratically near the cycle whatever the
cycle's stability: it finds the unstable cycles a simulation cannot reach (the
period-1 cycle past a period doubling, the middle branch of a fold). The orbit it
returns carries its minimal period, its n-p label (detachments per period), its
Floquet multipliers and the contact statistics of one period.
"""

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ContinuationError
from ..model.laws import LAW_PARAMETERS
from .section_map import SectionMap, Shot, describe

NEWTON_START_ITERATIONS = 40  # from a rough guess, before giving up
MAX_NEWTON_STEP = 0.5  # longest Newton step from a rough guess (y units); damps the far ones
REPEAT_TOL = 1e-7  # section points this close are one point: the minimal period


@dataclass(frozen=True)
class PeriodicOrbit:
    """A fixed point of Pⁿ: the orbit's state at θ = 0 and what characterises it.

    n is the minimal period in revolutions, p the detachments per period; multipliers are
    the eigenvalues of DPⁿ (|μ0| ≥ |μ1|); sections the n points (y, y') of the orbit on
    the section θ = 0, starting with ``state``; residual ‖Pⁿ(state) − state‖∞.
    """

    parameters: dict
    model: dict
    n: int
    p: int
    state: tuple[float, float]
    sections: np.ndarray
    multipliers: tuple[complex, complex]
    residual: float
    iterations: int
    dc: float  # fraction of the period separated
    eps_min: float
    eps_max: float
    pn_max: float
    touch: float  # ε at the extremum of ε nearest 0, signed

    @property
    def label(self) -> str:
        return f"{self.n}-{self.p}"

    @property
    def stable(self) -> bool:
        return max(abs(m) for m in self.multipliers) < 1.0

    def to_dict(self) -> dict:
        return {
            "label": self.label,
            "n": self.n,
            "p": self.p,
            "stable": self.stable,
            "state": list(self.state),
            "sections": self.sections.tolist(),
            "multipliers": [[m.real, m.imag] for m in self.multipliers],
            "residual": self.residual,
            "iterations": self.iterations,
            "dc": self.dc,
            "eps_min": self.eps_min,
            "eps_max": self.eps_max,
            "pn_max": self.pn_max,
            "touch": self.touch,
            "parameters": self.parameters,
            "model": self.model,
        }


def multipliers_of(jacobian: np.ndarray) -> tuple[complex, complex]:
    """Eigenvalues of a 2×2 DPⁿ, the larger modulus first."""
    values = sorted(np.linalg.eigvals(jacobian).astype(complex), key=abs, reverse=True)
    return complex(values[0]), complex(values[1])


def find_cycle(
    n: int, guess, *, section_map: SectionMap | None = None, model: dict | None = None, **parameters
) -> PeriodicOrbit:
    """The periodic orbit of period n (or a divisor of it) through a state near ``guess``.

    Parameters
    ----------
    n : int
        The period of the map Pⁿ to solve, in revolutions (≥ 1).
    guess : (y, y')
        A state at θ = 0 near the cycle: a map cell's ``state``, a simulation's end state.
    section_map : SectionMap, optional
        Reused between calls (it holds the compiled entry); else built from ``model``.
    model : dict, optional
        The force law's options (tensile, duty_cycle, cam_velocity), defaults as a job's.
    **parameters : float
        omega (required), f0, mu_kn, mu_cn, zeta (the paper's base values by default);
        and a law parameter (``phi1`` … ``phi4``, ``n``, ``restitution``), which the
        section map then takes as a parameter of its own (``SectionMap.law_parameter``).

    Returns
    -------
    PeriodicOrbit
        With n the minimal period: a fixed point of Pⁿ that repeats after d | n
        revolutions is the d-cycle.

    Raises
    ------
    ContinuationError
        Newton did not converge to ‖Pⁿ(x) − x‖∞ ≤ newton_tol from this guess.
    JobError
        A parameter is unknown or out of range.

    Examples
    --------
    >>> from campar.continuation.orbit import find_cycle
    >>> orbit = find_cycle(1, (0.54, -0.72), omega=3.54, mu_kn=0.91)
    >>> orbit.label, orbit.stable, round(orbit.multipliers[0].real, 6)
    ('1-1', False, -1.003854)
    """
    return solve_cycle(n, guess, parameters, section_map=section_map, model=model)


def solve_cycle(
    n: int, guess, parameters: dict, *, section_map: SectionMap | None = None, model=None
) -> PeriodicOrbit:
    """``find_cycle`` with the parameters as one mapping (a law parameter may be named
    ``n``, the contact's exponent)."""
    if n < 1:
        raise ContinuationError(f"the period must be ≥ 1 revolution, got {n}")
    law = [name for name in parameters if name in LAW_PARAMETERS]
    smap = section_map or SectionMap(model, law_parameter=law[0] if law else None)
    par = smap.vector(parameters)
    x = np.array(guess, dtype=np.float64)
    shot, iterations = newton(smap, x, par, n, NEWTON_START_ITERATIONS, damped=True)
    return orbit_at(smap, shot, par, n, iterations)


def newton(
    smap: SectionMap,
    x: np.ndarray,
    par: np.ndarray,
    n: int,
    max_iterations: int,
    damped: bool = False,
) -> tuple[Shot, int]:
    """Newton's method on Pⁿ(x) − x = 0 at fixed parameters; returns the converged shot (at
    the fixed point, with DPⁿ) and the iterations taken."""
    tol = smap.precision.newton_tol
    for iteration in range(max_iterations + 1):
        shot = smap.shoot(x, par, n)
        residual = shot.residual
        if np.max(np.abs(residual)) <= tol:
            return shot, iteration
        try:
            step = np.linalg.solve(shot.jacobian - np.eye(2), -residual)
        except np.linalg.LinAlgError:
            break
        size = np.max(np.abs(step))
        if not math.isfinite(size):
            break
        if damped and size > MAX_NEWTON_STEP:
            step *= MAX_NEWTON_STEP / size
        x = x + step
    raise ContinuationError(
        f"Newton's method found no {n}-cycle from ({x[0]:.6g}, {x[1]:.6g}) at "
        f"{describe(par, smap.order)}: residual "
        f"{np.max(np.abs(residual)):.3g} after {iteration} iterations (try a closer guess, "
        f"another period, or a simulation's end state)"
    )


def minimal_period(points: np.ndarray, tol: float = REPEAT_TOL) -> int:
    """The smallest d dividing len(points) with points[i] ≈ points[i + d] around the cycle."""
    n = len(points)
    for d in range(1, n):
        if n % d == 0 and np.max(np.abs(points - np.roll(points, -d, axis=0))) <= tol:
            return d
    return n


def section_points(shot: Shot) -> np.ndarray:
    """The orbit's n points on the section θ = 0, from the shot's start: x, P(x), …, Pⁿ⁻¹(x)."""
    return np.vstack([shot.start[None, :], shot.points[:-1]])


def orbit_at(
    smap: SectionMap, shot: Shot, par: np.ndarray, n: int, iterations: int = 0
) -> PeriodicOrbit:
    """The PeriodicOrbit of a converged fixed point of Pⁿ (``shot`` starts on it)."""
    points = section_points(shot)
    d = minimal_period(points)
    if d < n:
        shot = smap.shoot(shot.start, par, d)
        points = points[:d]
        n = d
    return PeriodicOrbit(
        parameters=dict(zip(smap.order, map(float, par), strict=True)),
        model=dict(smap.model),
        n=n,
        p=shot.detachments,
        state=(float(shot.start[0]), float(shot.start[1])),
        sections=points,
        multipliers=multipliers_of(shot.jacobian),
        residual=float(np.max(np.abs(shot.residual))),
        iterations=iterations,
        dc=shot.time_free / (n * 2.0 * math.pi / par[0]),
        eps_min=shot.eps_min,
        eps_max=shot.eps_max,
        pn_max=shot.pn_max,
        touch=shot.touch,
    )
