"""Two-parameter curves of PD, SN, NS and G points: augmented systems, continued by arclength.

A codimension-one point of a branch (campar.continuation.special) continues as a curve in
a plane of two parameters (λ1, λ2). The unknowns are u = (y, y', λ1, λ2) and the curve is
the solution set of the three equations

    Pⁿ(x; λ) − x = 0,   ψ(x; λ) = 0,

with ψ the point's test function: det(DPⁿ + I) for PD, det(DPⁿ − I) for SN, det DPⁿ − 1
for NS, and for G the signed extremum of ε nearest 0 (``touch``). The state has two
components, so the determinant is itself a regular defining function — the bordered
test functions of MatCont and BifurcationKit reduce to it up to a nonzero factor for a
2×2 DPⁿ — and the system stays three equations in four unknowns: a curve, followed by
the same predictor–corrector as a branch (campar.continuation.branch). DPⁿ is exact
(variational equations); the derivatives of ψ and the parameter columns are central
differences of it, taken at every accepted point and kept through the corrector's
iterates (each iterate recomputes Pⁿ − x, DPⁿ and ψ exactly, so the curve's points are
exact to newton_tol whatever the differences' error). The parameters are scaled to the
window of the plane, so a step has the same meaning along either axis.

A curve ends where it leaves the window, returns to its first point (a closed curve),
at ``max_points`` points (both directions from its seed together), or where no point is
found ahead.
"""

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import ContinuationError
from ..model.laws import LAW_PARAMETERS
from ..sweep.curves_job import CURVE_TYPES as CURVE_CODES
from .section_map import SectionMap, in_range
from .special import NS, PD, SN, G, SpecialPoint, psi_ns, psi_pd, psi_sn

CURVE_TYPES = CURVE_CODES  # the types a curve can have, in the order of their codes
STATE_STEP = 1e-6  # central differences of ψ in (y, y')
PARAMETER_STEP = 1e-6  # … and in a scaled parameter (a millionth of the window)
CLOSE_TOL = 0.2  # a curve back within this many steps of its first point is closed


@dataclass(frozen=True)
class CurveSettings:
    """Step control of a curve, in the window's scaled units (each parameter's range is 1)."""

    step: float = 0.005
    min_step: float = 1e-6
    max_step: float = 0.02
    max_points: int = 4000
    max_turn: float = 0.6
    max_newton: int = 8


@dataclass
class BifurcationCurve:
    """A curve of PD, SN, NS or G points of n-cycles in the (first, second) plane.

    first, second: the plane's parameters; values (N, 2) their values along the curve;
    states (N, 2) the n-cycle's (y, y') at θ = 0 there; multipliers (N, 2) complex; p the
    detachments per period (for G: on the side where ``touch`` > 0); end: why it stopped;
    seed: the special point it was started from.
    """

    type: str
    n: int
    first: str
    second: str
    parameters: dict  # the other parameters (fixed)
    model: dict
    values: np.ndarray
    states: np.ndarray
    multipliers: np.ndarray
    p: np.ndarray
    end: str
    seed: SpecialPoint | None = None
    shots: int = 0
    closed: bool = False
    extra: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {
            "type": self.type,
            "n": self.n,
            "first": self.first,
            "second": self.second,
            "parameters": self.parameters,
            "model": self.model,
            "end": self.end,
            "closed": self.closed,
            "points": [
                {
                    self.first: float(v[0]),
                    self.second: float(v[1]),
                    "state": s.tolist(),
                    "multipliers": [[float(m.real), float(m.imag)] for m in mu],
                    "p": int(p),
                }
                for v, s, mu, p in zip(
                    self.values, self.states, self.multipliers, self.p, strict=True
                )
            ],
            "seed": self.seed.to_dict() if self.seed else None,
        }


def defining_function(kind: str, shot) -> float:
    """ψ of a shot (campar.continuation.section_map.Shot) for a curve of ``kind``."""
    if kind == PD:
        return psi_pd(shot.jacobian)
    if kind == SN:
        return psi_sn(shot.jacobian)
    if kind == NS:
        return psi_ns(shot.jacobian)
    if kind == G:
        return shot.touch
    raise ContinuationError(f"no curve of {kind} points; one of {', '.join(CURVE_TYPES)}")


class CurveContinuation:
    """The curve of ``kind`` points of n-cycles in the plane of parameters ``names`` within
    ``window`` ((lo1, hi1), (lo2, hi2)), the other parameters as in ``par``."""

    def __init__(
        self,
        smap: SectionMap,
        kind: str,
        n: int,
        par: np.ndarray,
        names,
        window,
        settings: CurveSettings | None = None,
    ):
        if kind not in CURVE_TYPES:
            raise ContinuationError(f"no curve of {kind} points; one of {', '.join(CURVE_TYPES)}")
        if names[0] == names[1]:
            raise ContinuationError("a curve needs two different parameters")
        for name in names:
            if name in LAW_PARAMETERS and name not in smap.order:
                raise ContinuationError(
                    f"a curve in {name} needs a section map that continues it "
                    f"(SectionMap(law_parameter={name!r}))"
                )
        self.smap = smap
        self.kind = kind
        self.n = n
        self.par = np.array(par, dtype=np.float64)
        self.names = tuple(names)
        self.index = tuple(smap.index(name) for name in names)  # a law parameter: its own
        self.lo = np.array([min(w) for w in window], dtype=float)
        self.hi = np.array([max(w) for w in window], dtype=float)
        if np.any(self.hi <= self.lo):
            raise ContinuationError(f"the window of {names[0]} and {names[1]} is empty")
        self.settings = settings or CurveSettings()

    # scaled parameters: 0 … 1 across the window
    def scaled(self, values) -> np.ndarray:
        return (np.asarray(values, dtype=float) - self.lo) / (self.hi - self.lo)

    def unscaled(self, s) -> np.ndarray:
        return self.lo + np.asarray(s) * (self.hi - self.lo)

    def parameters_at(self, u: np.ndarray) -> np.ndarray:
        par = self.par.copy()
        values = self.unscaled(u[2:])
        par[self.index[0]] = values[0]
        par[self.index[1]] = values[1]
        return par

    def valid(self, u: np.ndarray) -> bool:
        values = self.unscaled(u[2:])
        return all(in_range(name, v) for name, v in zip(self.names, values, strict=True))

    def residual(self, u: np.ndarray, jacobian: bool = True):
        """(G(u), shot at u): Pⁿ − x and ψ; the shot with DPⁿ unless ``jacobian`` is False
        (ψ of a G curve needs none)."""
        shot = self.smap.shoot(u[:2], self.parameters_at(u), self.n, jacobian)
        return np.array([*shot.residual, defining_function(self.kind, shot)]), shot

    def jacobian(self, u: np.ndarray, shot) -> np.ndarray:
        """The 3×4 Jacobian of G at u: exact DPⁿ − I, central differences for the rest."""
        jac = np.zeros((3, 4))
        jac[:2, :2] = shot.jacobian - np.eye(2)
        for j in range(4):
            h = STATE_STEP if j < 2 else PARAMETER_STEP
            e = np.zeros(4)
            e[j] = h
            plus, _ = self.residual(u + e, self.kind != G)
            minus, _ = self.residual(u - e, self.kind != G)
            column = (plus - minus) / (2.0 * h)
            if j < 2:
                jac[2, j] = column[2]
            else:
                jac[:, j] = column
        return jac

    def tangent(self, jac: np.ndarray, reference: np.ndarray | None) -> np.ndarray:
        """The unit null vector of the 3×4 Jacobian, oriented along ``reference``."""
        _, _, vt = np.linalg.svd(jac)
        t = vt[-1]
        if reference is not None and np.dot(t, reference) < 0.0:
            t = -t
        return t

    def correct(self, guess: np.ndarray, normal: np.ndarray, anchor: np.ndarray, jac: np.ndarray):
        """Newton on G(u) = 0, normal·(u − anchor) = 0 from ``guess`` (the Jacobian's
        difference parts kept from ``jac``); (u, shot, iterates) or None."""
        tol = self.smap.precision.newton_tol
        u = guess.copy()
        for iteration in range(self.settings.max_newton + 1):
            if not self.valid(u):
                return None
            try:
                value, shot = self.residual(u)
            except ContinuationError:
                return None
            psi_scale = max(1.0, np.max(np.abs(jac[2])))
            if np.max(np.abs(value[:2])) <= tol and abs(value[2]) <= tol * psi_scale:
                return u, shot, iteration
            if iteration == self.settings.max_newton or not math.isfinite(value[2]):
                return None
            system = np.vstack([jac, normal])
            system[:2, :2] = shot.jacobian - np.eye(2)
            rhs = np.concatenate([-value, [-np.dot(normal, u - anchor)]])
            try:
                step = np.linalg.solve(system, rhs)
            except np.linalg.LinAlgError:
                return None
            if not np.all(np.isfinite(step)):
                return None
            u = u + step
        return None

    def start(self, sp: SpecialPoint):
        """The curve's first point from a special point of a branch (corrected onto the
        augmented system at the seed's parameters)."""
        values = [sp.parameters[name] for name in self.names]
        u = np.array([*sp.state, *self.scaled(values)])
        value, shot = self.residual(u)
        jac = self.jacobian(u, shot)
        found = self.correct(u, np.array([0.0, 0.0, 0.0, 1.0]), u, jac)  # λ2 fixed
        if found is None:
            raise ContinuationError(
                f"the {sp.type} point at {sp.parameter}={sp.value:.10g} "
                "does not solve its augmented system"
            )
        u, shot, _ = found
        return u, shot, self.jacobian(u, shot)

    def run(self, u0, shot0, jac0, direction: float, max_points: int):
        """At most ``max_points`` points (u, shot) of the curve from u0 along the tangent
        whose λ2 component has the sign of ``direction``; and why it ended."""
        cfg = self.settings
        t = self.tangent(jac0, np.array([0.0, 0.0, 0.0, direction]))
        points = [(u0, shot0)]
        u, jac, ds = u0, jac0, cfg.step
        end = f"reached {cfg.max_points} points (max_points)"
        closed = False
        while len(points) < max_points:
            predicted = u + ds * t
            found = self.correct(predicted, t, predicted, jac)
            accepted = None
            if found is not None:
                u1, shot1, iterations = found
                jac1 = self.jacobian(u1, shot1)
                t1 = self.tangent(jac1, t)
                if np.dot(t, t1) >= math.cos(cfg.max_turn):
                    accepted = (u1, shot1, jac1, t1)
            if accepted is None:
                ds *= 0.5
                if ds < cfg.min_step:
                    end = f"no point found ahead of {self.describe(u)} (step < min_step)"
                    break
                continue
            u1, shot1, jac1, t1 = accepted
            if np.any(u1[2:] < 0.0) or np.any(u1[2:] > 1.0):
                edge = self.edge_point(u, t, jac, u1)
                if edge is not None:
                    points.append(edge)
                end = f"left the window at {self.describe(points[-1][0])}"
                break
            points.append((u1, shot1))
            if len(points) > 3 and np.linalg.norm(u1 - u0) < CLOSE_TOL * ds:
                end = "closed: returned to its first point"
                closed = True
                break
            u, jac, t = u1, jac1, t1
            if iterations <= 2:
                ds = min(1.5 * ds, cfg.max_step)
            elif iterations >= 5:
                ds *= 0.7
        return points, end, closed

    def edge_point(self, u, t, jac, outside):
        """The curve's point on the window's edge between u (inside) and ``outside``."""
        s = u[2:]
        d = outside[2:] - s
        fractions = []
        for i in range(2):
            for bound in (0.0, 1.0):
                if d[i] != 0.0 and (bound - s[i]) / d[i] > 0.0:
                    fractions.append((bound - s[i]) / d[i])
        if not fractions:
            return None
        f = min(min(fractions), 1.0)
        guess = u + f * (outside - u)
        i = int(np.argmin([abs(guess[2] - round(guess[2])), abs(guess[3] - round(guess[3]))]))
        normal = np.zeros(4)
        normal[2 + i] = 1.0
        guess[2 + i] = round(guess[2 + i])
        found = self.correct(guess, normal, guess, jac)
        return None if found is None else found[:2]

    def describe(self, u) -> str:
        values = self.unscaled(u[2:])
        return ", ".join(f"{n}={v:.10g}" for n, v in zip(self.names, values, strict=True))


def continue_curve(
    sp: SpecialPoint,
    second: str,
    window,
    *,
    section_map: SectionMap | None = None,
    settings: CurveSettings | None = None,
) -> BifurcationCurve:
    """The curve of the special point ``sp``'s type through it, in the plane of its branch's
    parameter and ``second``, both ways from it, inside ``window``.

    Parameters
    ----------
    sp : SpecialPoint
        A PD, SN, NS or G point of a branch (``Branch.special``).
    second : str
        The plane's second parameter (omega, f0, mu_kn, mu_cn or zeta; not sp's), or the
        law parameter ``section_map`` continues (``SectionMap.law_parameter``).
    window : ((float, float), (float, float))
        The ranges of sp.parameter and of ``second``; the curve ends where it leaves them.
    section_map, settings
        Reused between calls; step control.

    Returns
    -------
    BifurcationCurve
        Its points in order along the curve (through the seed).

    Examples
    --------
    >>> from campar.continuation.orbit import find_cycle
    >>> from campar.continuation.branch import continue_branch
    >>> from campar.continuation.curves import continue_curve
    >>> orbit = find_cycle(1, (0.6, -0.6), omega=4.0, mu_kn=0.91)
    >>> pd = continue_branch(orbit, "omega", (3.0, 4.0)).special[0]
    >>> curve = continue_curve(pd, "mu_kn", ((3.0, 4.0), (0.9, 0.92)))
    >>> curve.type, curve.values[0].round(4).tolist(), curve.values[-1].round(4).tolist()
    ('PD', [3.4248, 0.9], [3.6649, 0.92])
    """
    if sp.type not in CURVE_TYPES:
        raise ContinuationError(f"no curve of {sp.type} points; one of {', '.join(CURVE_TYPES)}")
    smap = section_map or SectionMap(law_parameter=second if second in LAW_PARAMETERS else None)
    par = smap.vector(sp.parameters)  # a law parameter not in sp's: the model's value
    names = (sp.parameter, second)
    engine = CurveContinuation(smap, sp.type, sp.n, par, names, window, settings)
    shots0 = smap.shots
    u0, shot0, jac0 = engine.start(sp)
    limit = engine.settings.max_points
    ahead, end_ahead, closed = engine.run(u0, shot0, jac0, +1.0, limit)
    behind, end_behind = [], ""
    if not closed:  # the seed is the first point of both halves
        behind, end_behind, _ = engine.run(u0, shot0, jac0, -1.0, limit - len(ahead) + 1)
    points = [*reversed(behind[1:]), *ahead]
    end = end_ahead if closed else f"{end_behind}; {end_ahead}"
    from .orbit import multipliers_of

    others = {k: float(v) for k, v in zip(smap.order, par, strict=True) if k not in names}
    return BifurcationCurve(
        type=sp.type,
        n=sp.n,
        first=names[0],
        second=names[1],
        parameters=others,
        model=dict(smap.model),
        values=np.array([engine.unscaled(u[2:]) for u, _ in points]).reshape(-1, 2),
        states=np.array([u[:2] for u, _ in points]).reshape(-1, 2),
        multipliers=np.array(
            [multipliers_of(s.jacobian) for _, s in points], dtype=complex
        ).reshape(-1, 2),
        p=np.array([s.detachments for _, s in points], dtype=int),
        end=end,
        seed=sp,
        shots=smap.shots - shots0,
        closed=closed,
    )
