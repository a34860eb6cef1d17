"""An independent implementation of the model with SciPy: the peer of tests and benchmarks.

Written from docs/model.md without campar's code, and it must stay so (never import
campar's model, integrator or kernel, or it stops being a check): solve_ivp
(DOP853) integrates piecewise between cam phase boundaries and exact contact
events (terminal events, restarted in the new contact mode), as the reference
cells were made.

The paper's two ambiguities (docs/model.md) are options here too, written from
that page: ``cam_velocity="literal"`` takes the cam's velocity in the force's
damping term as dyc/dθ (the paper's eq. 6 without ω) instead of ω dyc/dθ, while
ε = yc(ωt) − y and its events stay as they are; ``integrate(..., mode_time=…)``
sums the time spent in each contact mode, from which ``duty_cycle`` counts
either the separated time (ε < 0) or the time without force (Pn = 0).

The cam and contact laws of docs/design.md are options too, written from that page
alone: a rise and a fall law over four phase angles (the composite laws built here from
their acceleration pieces, integrated in closed form piece by piece and scaled to a unit
stroke — not campar's half-rise construction), or a table through SciPy's periodic
CubicSpline; Hunt–Crossley with any exponent n, and Lankarani–Nikravesh and Flores et al.
with the impact velocity taken at each impact event (at least ``impact_floor``; the
floor before the first impact).
"""

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline

BOUNDS = (0.0, math.pi / 3, math.pi, 4 * math.pi / 3, 2 * math.pi)
PAPER_ANGLES = (math.pi / 3, 2 * math.pi / 3, math.pi / 3, 2 * math.pi / 3)
FREE, PUSH, SLACK = 0, 1, 2


def cam(theta):
    """yc, dyc/dθ, d²yc/dθ² of the cosine-acceleration law (stroke 1)."""
    return cam_in_phase(theta, theta)


# Acceleration pieces of the composite laws on u ∈ [0, 1], before scaling to a unit stroke:
# (u0, u1, α, β, γ, κ) for s'' = α sin(κ (u − u0)) + β cos(κ (u − u0)) + γ.
W4 = 4 * math.pi
PIECES = {
    "modified-trapezoid": [
        (0, 1 / 8, 1, 0, 0, W4),
        (1 / 8, 3 / 8, 0, 0, 1, 0),
        (3 / 8, 5 / 8, 0, 1, 0, W4),
        (5 / 8, 7 / 8, 0, 0, -1, 0),
        (7 / 8, 1, 0, -1, 0, W4),
    ],
    "modified-sine": [
        (0, 1 / 8, 1, 0, 0, W4),
        (1 / 8, 7 / 8, 0, 1, 0, W4 / 3),
        (7 / 8, 1, 0, -1, 0, W4),
    ],
}


def piece_values(piece, d, v0, s0):
    """s, s', s'' at d = u − u0 inside a piece starting at velocity v0, lift s0."""
    _, _, a, b, g, k = piece
    if k == 0:
        return s0 + v0 * d + g * d * d / 2, v0 + g * d, g
    sn, cs = math.sin(k * d), math.cos(k * d)
    acc = a * sn + b * cs + g
    vel = v0 + a * (1 - cs) / k + b * sn / k + g * d
    lift = s0 + v0 * d + a * (d / k - sn / k**2) + b * (1 - cs) / k**2 + g * d * d / 2
    return lift, vel, acc


class Composite:
    """s(u) of a law given by acceleration pieces, scaled so that s(1) = 1."""

    def __init__(self, pieces):
        self.pieces, self.starts = pieces, []
        v, s = 0.0, 0.0
        for piece in pieces:
            self.starts.append((v, s))
            s, v, _ = piece_values(piece, piece[1] - piece[0], v, s)
        self.scale = 1.0 / s

    def __call__(self, u):
        for piece, (v0, s0) in zip(self.pieces, self.starts, strict=True):
            if u <= piece[1] or piece is self.pieces[-1]:
                values = piece_values(piece, u - piece[0], v0, s0)
                return tuple(self.scale * x for x in values)
        raise AssertionError


def motion_law(name):
    """s(u), s'(u), s''(u) of a rise law on u ∈ [0, 1]."""
    if name == "cosine":
        return lambda u: (
            (1 - math.cos(math.pi * u)) / 2,
            math.pi / 2 * math.sin(math.pi * u),
            math.pi**2 / 2 * math.cos(math.pi * u),
        )
    if name == "cycloidal":
        return lambda u: (
            u - math.sin(2 * math.pi * u) / (2 * math.pi),
            1 - math.cos(2 * math.pi * u),
            2 * math.pi * math.sin(2 * math.pi * u),
        )
    if name == "polynomial-345":
        return lambda u: (
            10 * u**3 - 15 * u**4 + 6 * u**5,
            30 * u**2 - 60 * u**3 + 30 * u**4,
            60 * u - 180 * u**2 + 120 * u**3,
        )
    return Composite(PIECES[name])


class Model:
    def __init__(
        self,
        omega,
        f0=0.5,
        mu_kn=0.8,
        mu_cn=0.8,
        zeta=0.2,
        clamp=True,
        cam_velocity="chain",
        rise="cosine",
        fall="cosine",
        angles=PAPER_ANGLES,
        table=None,
        contact="hunt-crossley",
        n=1.5,
        restitution=0.8,
        impact_floor=1e-3,
    ):
        """``table``: (θ, S) arrays over [0, 2π) for a tabulated cam (rise, fall unused)."""
        self.omega, self.f0, self.zeta, self.clamp = omega, f0, zeta, clamp
        self.k = mu_kn / (1 - mu_kn)
        self.c = 2 * zeta * mu_cn / (1 - mu_cn)
        if cam_velocity not in ("chain", "literal"):
            raise ValueError(f"cam_velocity must be chain or literal, got {cam_velocity!r}")
        self.literal = cam_velocity == "literal"
        self.angles = angles
        self.bounds = tuple(np.concatenate([[0.0], np.cumsum(angles)]))
        self.rise, self.fall = motion_law(rise), motion_law(fall)
        self.paper_cam = (rise, fall, tuple(angles), table) == (
            "cosine",
            "cosine",
            PAPER_ANGLES,
            None,
        )
        self.spline = None
        if table is not None:
            theta, lift = table
            self.spline = CubicSpline(
                np.append(theta, 2 * math.pi), np.append(lift, lift[0]), bc_type="periodic"
            )
        self.n, self.contact, self.floor = n, contact, impact_floor
        if contact == "lankarani-nikravesh":
            self.chi = 3 * (1 - restitution**2) / 4
        elif contact == "flores":
            self.chi = 8 * (1 - restitution) / (5 * restitution)
        self.impact = impact_floor

    def damping(self):
        return self.c if self.contact == "hunt-crossley" else self.chi / self.impact

    def note_impact(self, t, x, theta_mid):
        """At an impact: a restitution law's damping takes this impact's velocity."""
        self.impact = max(self.gap(t, x, theta_mid)[1], self.floor)

    def cam_in_phase(self, theta, theta_mid):
        """yc, dyc/dθ, d²yc/dθ² with the formula of the phase that contains theta_mid."""
        if self.paper_cam:
            return cam_in_phase(theta, theta_mid)
        base = theta_mid - (theta_mid % (2 * math.pi))
        th, mid = theta - base, theta_mid - base
        if self.spline is not None:
            x = th % (2 * math.pi)
            return float(self.spline(x)), float(self.spline(x, 1)), float(self.spline(x, 2))
        b = self.bounds
        if mid < b[1]:
            s, ds, d2s = self.rise(th / self.angles[0])
            return s, ds / self.angles[0], d2s / self.angles[0] ** 2
        if mid < b[2]:
            return 1.0, 0.0, 0.0
        if mid < b[3]:
            s, ds, d2s = self.fall((th - b[2]) / self.angles[2])
            return 1 - s, -ds / self.angles[2], -d2s / self.angles[2] ** 2
        return 0.0, 0.0, 0.0

    def gap(self, t, y, theta_mid):
        """ε and the ε' the force law uses (the cam velocity as the option reads it)."""
        # evaluate the cam with the formula of the phase containing theta_mid
        yc, dyc, _ = self.cam_in_phase(self.omega * t, theta_mid)
        cam_speed = dyc if self.literal else self.omega * dyc
        return yc - y[0], cam_speed - y[1]

    def force(self, eps, deps):
        if eps <= 0:
            return 0.0
        f = self.k * eps**self.n * (1 + self.damping() * deps)
        return max(f, 0.0) if self.clamp else f

    def field(self, mode, theta_mid, with_divergence=False):
        def f(t, x):
            y, v = x[0], x[1]
            acc = -2 * self.zeta * v - y - self.f0
            div = -2 * self.zeta
            if mode == PUSH:
                eps, deps = self.gap(t, x, theta_mid)
                e = max(eps, 0.0)
                c = self.damping()
                acc += self.k * e**self.n * (1 + c * deps)
                div -= self.k * e**self.n * c
            if with_divergence:
                return [v, acc, div]
            return [v, acc]

        return f

    def mode_of(self, t, x, theta_mid):
        eps, deps = self.gap(t, x, theta_mid)
        if eps <= 0:
            return FREE
        if self.clamp and 1 + self.damping() * deps <= 0:
            return SLACK
        return PUSH

    def events_of(self, mode, theta_mid):
        def eps_event(t, x):
            return self.gap(t, x, theta_mid)[0]

        eps_event.terminal = True
        eps_event.direction = 1 if mode == FREE else -1
        evs = [eps_event]
        if self.clamp and mode != FREE:

            def bracket(t, x):
                return 1 + self.damping() * self.gap(t, x, theta_mid)[1]

            bracket.terminal = True
            bracket.direction = -1 if mode == PUSH else 1
            evs.append(bracket)
        return evs


def cam_in_phase(theta, theta_mid):
    """Cam law with the formula of the phase that contains theta_mid."""
    base = theta_mid - (theta_mid % (2 * math.pi))
    th = theta - base
    mid = theta_mid - base
    if mid < BOUNDS[1]:
        return 0.5 * (1 - math.cos(3 * th)), 1.5 * math.sin(3 * th), 4.5 * math.cos(3 * th)
    if mid < BOUNDS[2]:
        return 1.0, 0.0, 0.0
    if mid < BOUNDS[3]:
        u = 3 * (th - math.pi)
        return 0.5 * (1 + math.cos(u)), -1.5 * math.sin(u), -4.5 * math.cos(u)
    return 0.0, 0.0, 0.0


def integrate(
    model,
    x0,
    revolutions,
    *,
    rtol=1e-12,
    atol=1e-14,
    with_divergence=False,
    max_step=np.inf,
    mode_time=None,
    pieces=None,
    impact=None,
):
    """Integrate from (y, y') at θ = 0 over whole revolutions.

    solve_ivp looks for events only as sign changes between step ends, so a
    contact shorter than one step (ε > 0 briefly, inside a step) is missed;
    ``max_step`` bounds the step to catch such contacts.

    Returns (final state, list of (t, kind) events with kind in {"impact",
    "detachment", "force zero", "force resumes"}, ∫ div f dt if asked). A list
    ``mode_time`` of three numbers gets the time spent FREE, PUSH and SLACK added; a list
    ``pieces`` gets (dense solution, t from, t to, mode, θ of the phase, impact velocity)
    of every piece integrated. ``impact``: a restitution law's impact velocity at the start
    (default: the floor, as before any impact).
    """
    w = model.omega
    bounds = model.bounds
    model.impact = model.floor if impact is None else impact  # the floor: no impact yet
    x = np.array([x0[0], x0[1], 0.0] if with_divergence else list(x0[:2]), dtype=float)
    events = []
    t = 0.0
    mode = None
    for rev in range(revolutions):
        for i in range(4):
            if bounds[i + 1] == bounds[i]:
                continue  # a dwell of no length
            t_end = (2 * math.pi * rev + bounds[i + 1]) / w
            theta_mid = 2 * math.pi * rev + 0.5 * (bounds[i] + bounds[i + 1])
            if mode is None:
                mode = model.mode_of(t, x, theta_mid)
            while t < t_end - 1e-14 * max(1.0, t_end):
                sol = solve_ivp(
                    model.field(mode, theta_mid, with_divergence),
                    (t, t_end),
                    x,
                    method="DOP853",
                    rtol=rtol,
                    atol=atol,
                    max_step=max_step,
                    events=model.events_of(mode, theta_mid),
                    dense_output=pieces is not None,
                )
                if pieces is not None:
                    t_to = t_end
                    if sol.status == 1:
                        t_to = min(float(te[0]) for te in sol.t_events if len(te))
                    pieces.append((sol.sol, t, t_to, mode, theta_mid, model.impact))
                if sol.status == 1:
                    which = next(j for j, te in enumerate(sol.t_events) if len(te))
                    if mode_time is not None:
                        mode_time[mode] += float(sol.t_events[which][0]) - t
                    t = float(sol.t_events[which][0])
                    x = sol.y_events[which][0].copy()
                    if mode == FREE:
                        events.append((t, "impact"))
                        model.note_impact(t, x, theta_mid)
                        # the literal cam velocity can leave 1 + c ε' ≤ 0 at an impact
                        mode = model.mode_of(t, x, theta_mid)
                        if mode == FREE:  # at ε = 0 exactly: contact begins
                            _, deps = model.gap(t, x, theta_mid)
                            slack = model.clamp and 1 + model.damping() * deps <= 0
                            mode = SLACK if slack else PUSH
                    elif which == 0:
                        events.append((t, "detachment"))
                        mode = FREE
                    elif mode == PUSH:
                        events.append((t, "force zero"))
                        mode = SLACK
                    else:
                        events.append((t, "force resumes"))
                        mode = PUSH
                else:
                    if mode_time is not None:
                        mode_time[mode] += t_end - t
                    t = t_end
                    x = sol.y[:, -1].copy()
        mode = None  # campar decides the mode from the state at each θ = 0 as well
    divergence = x[2] if with_divergence else None
    return x[:2], events, divergence


def duty_cycle(model, x0, revolutions, by="separation", **options):
    """Fraction of ``revolutions`` revolutions from x0 (at θ = 0) spent separated (ε < 0,
    ``by="separation"``) or without force (Pn = 0: separated, or SLACK under the clamp,
    ``by="force"``). ``options``: those of ``integrate``."""
    if by not in ("separation", "force"):
        raise ValueError(f"by must be separation or force, got {by!r}")
    times = [0.0, 0.0, 0.0]
    integrate(model, x0, revolutions, mode_time=times, **options)
    total = revolutions * 2 * math.pi / model.omega
    released = times[FREE] + (times[SLACK] if by == "force" else 0.0)
    return released / total


def extremes(model, x0, revolutions, *, skip=0, samples=2001, **options):
    """(min ε, max ε, max Pn) over ``revolutions`` revolutions from x0 (at θ = 0), after
    ``skip`` more: every piece of the solution (``integrate``'s, ``options`` its own)
    sampled on its dense output at ``samples`` points, and each piece's extreme sample
    refined by a bounded scalar search on the dense output between its neighbours."""
    from scipy.optimize import minimize_scalar

    pieces = []
    integrate(model, x0, skip + revolutions, pieces=pieces, **options)
    start = skip * 2 * math.pi / model.omega
    pieces = [piece for piece in pieces if piece[1] >= start * (1 - 1e-12)]
    found = [math.inf, -math.inf, 0.0]

    def values(piece, t):
        sol, _, _, mode, theta_mid, impact = piece
        model.impact = impact
        x = sol(t)
        eps, deps = model.gap(t, x, theta_mid)
        return eps, (model.force(eps, deps) if mode == PUSH else 0.0)

    for piece in pieces:
        ts = np.linspace(piece[1], piece[2], samples)
        table = np.array([values(piece, t) for t in ts])
        for column, sign in ((0, 1.0), (0, -1.0), (1, -1.0)):
            i = int(np.argmin(sign * table[:, column]))
            best = sign * table[i, column]
            lo, hi = ts[max(i - 1, 0)], ts[min(i + 1, samples - 1)]
            if hi > lo:
                res = minimize_scalar(
                    lambda t, q=piece, c=column, s=sign: s * values(q, t)[c],
                    bounds=(lo, hi),
                    method="bounded",
                    options={"xatol": 1e-13 * max(1.0, hi)},
                )
                best = min(best, res.fun)
            if column == 0 and sign > 0:
                found[0] = min(found[0], best)
            elif column == 0:
                found[1] = max(found[1], -best)
            else:
                found[2] = max(found[2], -best)
    return tuple(found)
