"""Pseudo-arclength continuation of a periodic orbit along one parameter.

The unknowns are u = (y, y', λ): a point of Pⁿ's section and the parameter. A branch is
the curve F(u) = Pⁿ(x; λ) − x = 0 in that 3-space, followed by predictor and corrector
(Keller 1977; as AUTO and BifurcationKit's ``PALC``): from a point u with unit tangent t
(the null vector of DF = [DPⁿ − I | ∂Pⁿ/∂λ], the cross product of its two rows), the
predictor u + Δs t is corrected by Newton's method on F(u) = 0, t·(u − u_pred) = 0. The
tangent's parameter component is free to change sign, so the branch runs through folds,
where it turns back in λ. The corrector recomputes DPⁿ exactly at every iterate and keeps
the parameter column of the last accepted point (a chord in that column only: one
integration an iterate instead of three, still converging to newton_tol in 2–4).

Step control: a step whose corrector fails, or whose tangent turns by more than
``max_turn``, is retried with half the step; a step that converged in ≤ 4 iterates lets
the next one grow by 1.5, up to ``max_step``, one that took more than 5 shrinks it by 0.7
(near grazing Pⁿ is only C¹ and Newton converges linearly: 4 iterates are normal there).
A corrector that moves farther from its predictor than the step itself is refused too: on
a strongly unstable branch (|μ| in the thousands) Newton's basin is narrow, and a long
step lands on another branch. Between consecutive points the test functions of
campar.continuation.special detect PD, SN, BP, NS and G points, which are then located on
the branch.

The branch ends where it leaves the parameter window, reaches ``max_points``, where the
step falls below ``min_step`` (no point found ahead), where its parameter leaves the
model's range, where a doubled branch returns onto the branch it was born from, or where
it closes on itself (an isola between two folds).
"""

import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import ContinuationError
from ..model.laws import LAW_PARAMETERS
from .branch_result import Branch, assemble
from .orbit import PeriodicOrbit, multipliers_of, newton, orbit_at
from .section_map import SectionMap, Shot, in_range
from .special import (
    LOCATE_TOL,
    PD,
    G,
    SpecialPoint,
    crossings,
    illinois,
    test_function,
)

GROW_ITERATIONS = 4  # a step whose corrector took at most this many iterates may grow
CHORD_RATE = 0.01  # a corrector iterate must cut the residual this much, or the column is renewed


@dataclass(frozen=True)
class BranchSettings:
    """Step control of a branch (arclength in (y, y', λ) units).

    step: the first step; min_step: below it the branch ends; max_step: the longest
    step; max_points: the branch's points at most; max_turn: the largest angle (radians)
    between consecutive tangents before a step is halved; max_newton: corrector iterates.
    """

    step: float = 0.01
    min_step: float = 1e-7
    max_step: float = 0.05
    max_points: int = 5000
    max_turn: float = 0.5
    max_newton: int = 8


@dataclass
class BranchPoint:
    """A converged point of a branch: u = (y, y', λ), its shot (at the fixed point, with
    DPⁿ), the parameter column ∂Pⁿ/∂λ and the unit tangent."""

    u: np.ndarray
    shot: Shot
    column: np.ndarray
    tangent: np.ndarray
    s: float = 0.0  # arclength from the branch's first point

    @property
    def jacobian(self) -> np.ndarray:
        return self.shot.jacobian

    @property
    def p(self) -> int:
        return self.shot.detachments

    @property
    def touch(self) -> float:
        return self.shot.touch


class Continuation:
    """The continuation of n-cycles along parameter ``name`` at fixed other parameters
    ``par`` (PARAMETER_ORDER vector), inside the window [lo, hi] of that parameter."""

    def __init__(
        self,
        smap: SectionMap,
        par: np.ndarray,
        name: str,
        n: int,
        window: tuple[float, float],
        settings: BranchSettings | None = None,
    ):
        self.smap = smap
        self.par = np.array(par, dtype=np.float64)
        self.name = name
        self.index = smap.index(name)
        self.n = n
        self.lo, self.hi = sorted(window)
        self.settings = settings or BranchSettings()
        self.returned = False  # the last run ended on the branch of period n/2
        self.closed = False  # the last run went round a closed loop

    # -- points ----------------------------------------------------------------------
    def parameters_at(self, lam: float) -> np.ndarray:
        par = self.par.copy()
        par[self.index] = lam
        return par

    def column(self, u: np.ndarray) -> np.ndarray:
        return self.smap.parameter_derivative(u[:2], self.parameters_at(u[2]), self.n, self.index)

    def tangent(self, shot: Shot, column: np.ndarray, reference: np.ndarray | None) -> np.ndarray:
        """The unit null vector of DF = [DPⁿ − I | ∂Pⁿ/∂λ], oriented along ``reference``."""
        a = np.column_stack([shot.jacobian - np.eye(2), column])
        t = np.cross(a[0], a[1])
        norm = np.linalg.norm(t)
        if not (norm > 0.0 and math.isfinite(norm)):
            raise ContinuationError(f"the branch is singular at {self.name}={shot_value(t)}")
        t /= norm
        if reference is not None and np.dot(t, reference) < 0.0:
            t = -t
        return t

    def point(
        self, u: np.ndarray, shot: Shot, reference: np.ndarray | None, s: float = 0.0
    ) -> BranchPoint:
        column = self.column(u)
        return BranchPoint(u, shot, column, self.tangent(shot, column, reference), s)

    def correct(
        self, guess: np.ndarray, normal: np.ndarray, anchor: np.ndarray, column: np.ndarray
    ) -> tuple[np.ndarray, Shot, int] | None:
        """Newton on Pⁿ(x; λ) − x = 0 with normal·(u − anchor) = 0, from ``guess``.

        The parameter column starts as ``column`` (the last point's) and is recomputed at
        the iterate whenever the residual fell by less than CHORD_RATE: near a strongly
        unstable cycle (|μ| ≫ 1) a stale column makes the iteration crawl.
        Returns (u, shot at u, iterates) or None when it does not converge, leaves the
        model's parameter range or the integration fails.
        """
        tol = self.smap.precision.newton_tol
        u = guess.copy()
        previous = math.inf
        for iteration in range(self.settings.max_newton + 1):
            if not in_range(self.name, u[2]):
                return None
            try:
                shot = self.smap.shoot(u[:2], self.parameters_at(u[2]), self.n)
                size = np.max(np.abs(shot.residual))
                if size <= tol:
                    return u, shot, iteration
                if iteration == self.settings.max_newton:
                    return None
                if size > CHORD_RATE * previous:
                    column = self.column(u)
            except ContinuationError:
                return None
            previous = size
            system = np.zeros((3, 3))
            system[:2, :2] = shot.jacobian - np.eye(2)
            system[:2, 2] = column
            system[2] = normal
            rhs = np.concatenate([-shot.residual, [-np.dot(normal, u - anchor)]])
            try:
                step = np.linalg.solve(system, rhs)
            except np.linalg.LinAlgError:
                return None
            if not np.all(np.isfinite(step)):
                return None
            u = u + step
        return None

    def first_point(
        self, orbit: PeriodicOrbit, direction: float, tangent: np.ndarray | None = None
    ) -> BranchPoint:
        """The branch point of a converged orbit; the tangent oriented so the parameter
        moves along ``direction`` (±1), or along ``tangent`` when given."""
        u = np.array([*orbit.state, orbit.parameters[self.name]])
        shot = self.smap.shoot(u[:2], self.parameters_at(u[2]), self.n)
        reference = tangent if tangent is not None else np.array([0.0, 0.0, direction])
        return self.point(u, shot, reference)

    # -- the branch --------------------------------------------------------------------
    def run(self, start: BranchPoint) -> tuple[list[BranchPoint], list[SpecialPoint], str]:
        """Follow the branch from ``start`` along its tangent; returns its points, its
        special points and why it ended."""
        cfg = self.settings
        points = [start]
        farthest = 0.0  # from the first point
        special: list[SpecialPoint] = []
        ds = min(cfg.step, cfg.max_step)
        end = f"reached {cfg.max_points} points (max_points)"
        while len(points) < cfg.max_points:
            a = points[-1]
            predicted = a.u + ds * a.tangent
            found = self.correct(predicted, a.tangent, predicted, a.column)
            b = None
            if found is not None and np.linalg.norm(found[0] - predicted) <= ds:
                u, shot, iterations = found
                try:
                    b = self.point(u, shot, a.tangent, a.s + ds)
                except ContinuationError:  # the parameter column's integration failed
                    b = None
                if b is not None and np.dot(a.tangent, b.tangent) < math.cos(cfg.max_turn):
                    b = None  # turned too sharply: a step this long may jump branches
            if b is None:
                ds *= 0.5
                if ds < cfg.min_step:
                    value = a.u[2]
                    if not in_range(self.name, value + a.tangent[2] * 2 * cfg.min_step):
                        end = f"left the model's range of {self.name} at {value:.10g}"
                    else:
                        end = f"no point found ahead of {self.name}={value:.10g} (step < min_step)"
                    break
                continue
            if self.halves_between(a, b):
                pt = self.vertex(a, b)
                if pt is not None:
                    points.append(pt)
                    self.returned = True
                    end = (
                        f"returned onto the {self.n // 2}-cycles at their PD point "
                        f"{self.name}={pt.u[2]:.10g}"
                    )
                    break
            for kind in crossings(a, b):
                located = self.locate(a, b, kind)
                if located is not None:
                    special.append(located[0])
            lam = b.u[2]
            if not self.lo <= lam <= self.hi:
                edge = self.hi if lam > self.hi else self.lo
                last = self.at_value(a, edge)
                if last is not None:
                    points.append(last)
                end = f"left the window at {self.name}={edge:.10g}"
                break
            points.append(b)
            # a closed loop (an isola): back within a step of the first point, after having
            # gone farther from it than four steps
            distance = float(np.linalg.norm(b.u - start.u))
            if farthest > 4.0 * ds and distance <= ds:
                self.closed = True
                end = "closed: the branch is a loop, back at its first point"
                break
            farthest = max(farthest, distance)
            if iterations <= GROW_ITERATIONS:
                ds = min(1.5 * ds, cfg.max_step)
            elif iterations > GROW_ITERATIONS + 1:
                ds *= 0.7
        special.sort(key=lambda sp: sp.arclength)
        return points, special, end

    def halves_between(self, a: BranchPoint, b: BranchPoint) -> bool:
        """True when an even-period branch passes a PD point of the n/2-cycles between a
        and b: its halves' difference P^{n/2}(x) − x reverses there (the doubled branch's
        two arms, x* ± a v, meet at the PD point, and a continuation that went on would
        follow the other arm: the same cycles, half a period shifted)."""
        if self.n % 2:
            return False
        return float(np.dot(half_difference(a), half_difference(b))) < 0.0

    def vertex(self, a: BranchPoint, b: BranchPoint) -> BranchPoint | None:
        """The PD point of the n/2-cycles where this branch, between a and b, meets them.

        The arclength plane of a and b cuts the n/2-cycles as well as the doubled branch,
        so the point is not sought on this branch: the n/2-cycle through a's state is
        solved for and its branch continued across [a, b] widened fourfold, with the PD
        point located there (to LOCATE_TOL). None when that fails.
        """
        half = Continuation(
            self.smap, self.par, self.name, self.n // 2, (self.lo, self.hi), self.settings
        )
        lam_a, lam_b = sorted((a.u[2], b.u[2]))
        width = 4.0 * max(lam_b - lam_a, 1e-4)
        window = (lam_a - width, lam_b + width)
        try:
            shot, _ = newton(self.smap, a.u[:2], self.parameters_at(a.u[2]), self.n // 2, 12)
            orbit = orbit_at(self.smap, shot, self.parameters_at(a.u[2]), self.n // 2)
            half.lo, half.hi = window
            half.settings = replace(
                self.settings, step=width / 8, max_step=width / 8, max_points=80
            )
            start = half.first_point(orbit, 1.0 if b.u[2] > a.u[2] else -1.0)
            _, special, _ = half.run(start)
            if not any(sp.type == PD for sp in special):
                start = half.first_point(orbit, -1.0 if b.u[2] > a.u[2] else 1.0)
                _, special, _ = half.run(start)
        except ContinuationError:
            return None
        pds = [sp for sp in special if sp.type == PD]
        if not pds:
            return None
        pd = min(pds, key=lambda sp: abs(sp.value - 0.5 * (lam_a + lam_b)))
        u = np.array([*pd.state, pd.value])
        try:
            end = self.smap.shoot(u[:2], self.parameters_at(u[2]), self.n)
        except ContinuationError:
            return None
        return self.point(u, end, a.tangent, b.s)

    def at_value(self, a: BranchPoint, value: float) -> BranchPoint | None:
        """The branch point at parameter ``value`` past a (corrected with λ fixed)."""
        if abs(a.tangent[2]) < 1e-12:
            return None
        ds = (value - a.u[2]) / a.tangent[2]
        guess = a.u + ds * a.tangent
        guess[2] = value
        return self.corrected(a, guess, np.array([0.0, 0.0, 1.0]), ds)

    def corrected(
        self, a: BranchPoint, guess: np.ndarray, normal: np.ndarray, s: float
    ) -> BranchPoint | None:
        """The branch point Newton finds from ``guess`` on the plane normal·(u − guess) = 0,
        with a's parameter column, oriented along a and at arclength s past it; None where
        the corrector or the new point's column fails."""
        found = self.correct(guess, normal, guess, a.column)
        if found is None:
            return None
        u, shot, _ = found
        try:
            return self.point(u, shot, a.tangent, a.s + s)
        except ContinuationError:
            return None

    # -- special points ---------------------------------------------------------------
    def along(self, a: BranchPoint, s: float) -> BranchPoint | None:
        """The corrected branch point at arclength s past a (on a's tangent's normal plane)."""
        return self.corrected(a, a.u + s * a.tangent, a.tangent, s)

    def locate(
        self, a: BranchPoint, b: BranchPoint, kind: str
    ) -> tuple[SpecialPoint, BranchPoint] | None:
        """The special point of ``kind`` between a and b, located to LOCATE_TOL in λ, and
        the branch point there."""
        span = b.s - a.s
        cache = {0.0: a, span: b}

        def at(s):
            if s not in cache:
                pt = self.along(a, s)
                if pt is None:
                    raise ContinuationError(f"no branch point at arclength {s} past {a.u}")
                cache[s] = pt
            return cache[s]

        def small(s0, s1):
            return abs(at(s0).u[2] - at(s1).u[2]) <= LOCATE_TOL and abs(s1 - s0) <= 1e-6

        psi = test_function(kind)
        try:
            fa, fb = psi(a), psi(b)
            if kind == G and np.sign(fa) == np.sign(fb):
                s = self.bisect_pattern(at, 0.0, span, a.p)
            else:
                s = illinois(lambda s: psi(at(s)), 0.0, span, fa, fb, small)
        except ContinuationError:
            return None
        pt = at(s)
        lo, hi = bracket_of(cache, s, kind, psi, a.p)
        return self.special_point(kind, pt, a, b, abs(at(hi).u[2] - at(lo).u[2])), pt

    def bisect_pattern(self, at, s0: float, s1: float, p0: int) -> float:
        """Where the detachment count changes from p0 between arclengths s0 and s1."""
        while abs(at(s1).u[2] - at(s0).u[2]) > LOCATE_TOL and s1 - s0 > 1e-12:
            mid = 0.5 * (s0 + s1)
            if at(mid).p == p0:
                s0 = mid
            else:
                s1 = mid
        return s1

    def special_point(
        self, kind: str, pt: BranchPoint, a: BranchPoint, b: BranchPoint, accuracy: float
    ) -> SpecialPoint:
        par = self.parameters_at(pt.u[2])
        vector = None
        if kind == PD:
            values, vectors = np.linalg.eig(pt.jacobian)
            i = int(np.argmin(np.abs(values + 1.0)))
            v = np.real(vectors[:, i])
            vector = tuple(float(c) for c in v / np.linalg.norm(v))
        stable_a = max(abs(m) for m in multipliers_of(a.jacobian)) < 1.0
        stable_b = max(abs(m) for m in multipliers_of(b.jacobian)) < 1.0
        return SpecialPoint(
            type=kind,
            parameter=self.name,
            value=float(pt.u[2]),
            state=(float(pt.u[0]), float(pt.u[1])),
            n=self.n,
            multipliers=multipliers_of(pt.jacobian),
            labels=(f"{self.n}-{a.p}", f"{self.n}-{b.p}"),
            stable=(stable_a, stable_b),
            accuracy=accuracy,
            parameters=dict(zip(self.smap.order, map(float, par), strict=True)),
            eigenvector=vector,
            arclength=float(pt.s),
        )


def half_difference(pt: BranchPoint) -> np.ndarray:
    """P^{n/2}(x) − x of an even-period branch point (zero on the n/2-cycles)."""
    n = len(pt.shot.points)
    return pt.shot.points[n // 2 - 1] - pt.u[:2]


def bracket_of(cache: dict, s: float, kind: str, psi, p0: int) -> tuple[float, float]:
    """The closest evaluated arclengths on either side of the root at s."""
    keys = sorted(cache)
    if kind == G:
        sides = [k for k in keys if cache[k].p == p0]
        others = [k for k in keys if cache[k].p != p0]
    else:
        sign = np.sign(psi(cache[keys[0]]))
        sides = [k for k in keys if np.sign(psi(cache[k])) == sign]
        others = [k for k in keys if np.sign(psi(cache[k])) != sign]
    lo = max((k for k in sides if k <= s), default=s)
    hi = min((k for k in others if k >= s), default=s)
    return lo, hi


def shot_value(t) -> str:
    return ", ".join(f"{v:.6g}" for v in t)


def continue_branch(
    orbit: PeriodicOrbit,
    parameter: str,
    window: tuple[float, float],
    *,
    direction: float | None = None,
    section_map: SectionMap | None = None,
    settings: BranchSettings | None = None,
) -> Branch:
    """Continue the branch of ``orbit`` along ``parameter`` inside ``window``.

    Parameters
    ----------
    orbit : PeriodicOrbit
        The branch's first point (``find_cycle``).
    parameter : str
        omega, f0, mu_kn, mu_cn or zeta.
    window : (float, float)
        The parameter's range; the branch ends where it leaves it.
    direction : float, optional
        +1 or −1: which way the parameter moves at the start; by default towards the far
        end of the window.
    section_map : SectionMap, optional
        Reused between calls; by default one for the orbit's force law.
    settings : BranchSettings, optional
        Step control.

    Returns
    -------
    Branch
        Its points, special points (PD, SN, BP, NS, G, located to 1e-10 in the
        parameter) and why it ended.

    Examples
    --------
    >>> from campar.continuation.orbit import find_cycle
    >>> from campar.continuation.branch import continue_branch
    >>> orbit = find_cycle(1, (0.6, -0.6), omega=4.0, mu_kn=0.91)
    >>> branch = continue_branch(orbit, "omega", (3.0, 4.0))
    >>> [(sp.type, round(sp.value, 6)) for sp in branch.special], branch.end
    ([('PD', 3.542608)], 'left the window at omega=3')
    """
    law = parameter if parameter in LAW_PARAMETERS else None
    smap = section_map or SectionMap(orbit.model, law_parameter=law)
    par = smap.vector(orbit.parameters)
    engine = Continuation(smap, par, parameter, orbit.n, window, settings)
    value = orbit.parameters[parameter]
    if direction is None:
        lo, hi = sorted(window)
        direction = 1.0 if hi - value >= value - lo else -1.0
    shots0 = smap.shots
    start = engine.first_point(orbit, direction)
    points, special, end = engine.run(start)
    return assemble(engine, points, special, end, shots=smap.shots - shots0)
