"""The cam with flat-bottomed follower: cam law, Hunt–Crossley contact, vector field.

Dimensionless equation of motion (docs/model.md, paper eq. 11):

    y'' + 2 ζ y' + y = Pn − f0,    Pn = k ε^{3/2} (1 + c ε')  for ε = yc − y > 0

Time t is scaled by the natural frequency; the cam angle is θ = ω t. Every
revolution is integrated from t = 0, so inside the kernel θ ∈ [0, 2π] and the
time of a phase boundary is its angle divided by ω.

The hybrid state is carried in a small int array ``mode``: ``mode[0]`` is the
cam phase (the formula of yc in use, so the field stays smooth across a step)
and ``mode[1]`` the contact mode. Each contact mode has its own smooth field
and its own event functions g_i, positive while the mode holds; the integrator
ends a step where a g_i reaches zero and the kernel switches mode there
(Hunt & Crossley 1975 for the force law; the field is continuous across every
switching surface, so the variational equations need no saltation).

Two readings of the paper are runtime options (``law`` bits, so one compiled
kernel serves all of them, docs/model.md): the duty cycle counted by separation
(ε < 0, default) or by force (Pn = 0, which under the clamp adds the SLACK
time), and the cam velocity in the force's ε' by the chain rule (ω dyc/dθ,
default) or as the paper's eq. 6 prints it (dyc/dθ). The literal velocity
changes only the force: ε itself, and so every event time and rate of ε, is
yc(ωt) − y either way.
"""

import math
from typing import NamedTuple

import numpy as np
from numba import types
from numba.extending import overload

from . import contact
from .cam import OPTIONS, PAPER_CAM, Cosine, PhasedCam, lift
from .contact import HERTZ, HuntCrossleyHertz, damping, force_and_rate, pushing
from .jit import entry, hot

# Cam phases of the cosine-acceleration law with stroke 1.
RISE = 0
FAR_DWELL = 1
FALL = 2
NEAR_DWELL = 3
N_PHASES = 4
# Phase boundaries in cam angle θ; phase i spans [PHASE_BOUNDS[i], PHASE_BOUNDS[i+1]].
PHASE_BOUNDS = np.array([0.0, math.pi / 3.0, math.pi, 4.0 * math.pi / 3.0, 2.0 * math.pi])
TWO_PI = 2.0 * math.pi

# Contact modes.
FREE = 0  # separated, ε ≤ 0, Pn = 0
PUSH = 1  # in contact and pushing: ε > 0 (and 1 + c ε' > 0 when clamped)
SLACK = 2  # clamp only: ε > 0 but 1 + c ε' ≤ 0, so the force is zero
MAX_EVENTS = 2  # event functions per contact mode, at most

# Layout of the state vector: y, y', then optionally the 2×2 fundamental
# matrix Φ row-major (variational equations Φ' = A Φ, Φ(0) = I).
N_STATE = 2
N_STATE_VARIATIONAL = 6

# Bits of a force law (``law_flags``, the kernel's ``law`` argument).
LAW_CLAMP = 1  # no tensile force, Pn = max(0, …) (a bool True means this bit alone)
LAW_DC_FORCE = 2  # duty cycle: time with Pn = 0, not only with ε ≤ 0
LAW_CAM_LITERAL = 4  # the force's cam velocity dyc/dθ (paper eq. 6), not ω dyc/dθ

# The job's ModelSettings values of each option, in bit order (False, True).
TENSILE_CHOICES = ("allow", "clamp")
DUTY_CYCLE_CHOICES = ("separation", "force")
CAM_VELOCITY_CHOICES = ("chain", "literal")


def law_flags(
    tensile: str = "clamp", duty_cycle: str = "separation", cam_velocity: str = "chain"
) -> int:
    """The LAW_* bits of the job's model settings (ValueError for an unknown value)."""
    bits = 0
    for value, choices, bit in (
        (tensile, TENSILE_CHOICES, LAW_CLAMP),
        (duty_cycle, DUTY_CYCLE_CHOICES, LAW_DC_FORCE),
        (cam_velocity, CAM_VELOCITY_CHOICES, LAW_CAM_LITERAL),
    ):
        if value not in choices:
            raise ValueError(f"{value!r} is not one of {', '.join(choices)}")
        if value == choices[1]:
            bits |= bit
    return bits


class Law(NamedTuple):
    """What a job chooses of the model besides its numbers: the LAW_* option bits, the cam
    (campar.core.cam: PhasedCam or TabulatedCam) and the contact law (campar.core.contact).
    Its type decides what numba compiles: one kernel per combination of laws."""

    bits: np.int64
    cam: tuple
    contact: tuple


PAPER_LAW = Law(np.int64(LAW_CLAMP), PAPER_CAM, HERTZ)


def kernel_law(law) -> Law:
    """The kernel's ``law`` argument: a Law as given (its bits as int64), or LAW_* bits (an
    int, or a bool: the clamp bit alone) with the paper's cam and contact law."""
    if isinstance(law, Law):
        return law._replace(bits=np.int64(int(law.bits)))
    return Law(np.int64(int(law)), PAPER_CAM, HERTZ)


def start_chain(law: Law) -> None:
    """Before a chain's first cell: forget what its laws remember (the last impact)."""
    contact.start_chain(law.contact)


class ModelParams(NamedTuple):
    """Parameters of one grid cell, in the form the vector field uses."""

    omega: float  # cam angular speed / natural frequency
    zeta: float  # spring damping ratio ζ
    f0: float  # preload / (K1 h)
    k: float  # contact stiffness μkn / (1 − μkn)
    c: float  # contact damping 2 ζ μcn / (1 − μcn)
    clamp: bool  # True: no tensile force, Pn = max(0, …)
    vcam: float  # cam velocity in the force's ε' per unit dyc/dθ: ω (chain rule) or 1
    dc_force: bool  # True: the duty cycle counts the time with Pn = 0 (ε ≤ 0 or SLACK)
    cam: tuple  # the cam (campar.core.cam)
    contact: tuple  # the contact law (campar.core.contact)


@entry
def make_params(omega, zeta, f0, mu_kn, mu_cn, law):
    """Pack the physical parameters (μkn, μcn ∈ (0, 1)) and the job's ``law`` into
    ModelParams. ``law``: a Law (``kernel_law``, a job's ``law()``), or LAW_* bits alone
    (an integer; a bool is the clamp bit alone) for the paper's cam and contact law."""
    bits, the_cam, the_contact = law_parts(law)
    k = mu_kn / (1.0 - mu_kn)
    c = 2.0 * zeta * mu_cn / (1.0 - mu_cn)
    vcam = 1.0 if bits & LAW_CAM_LITERAL else omega
    return ModelParams(
        omega,
        zeta,
        f0,
        k,
        c,
        (bits & LAW_CLAMP) != 0,
        vcam,
        (bits & LAW_DC_FORCE) != 0,
        the_cam,
        the_contact,
    )


def law_parts(law):
    """(bits, cam, contact) of a Law, or of LAW_* bits with the paper's laws (compiled
    code only)."""
    raise TypeError("campar.core.model.law_parts is for compiled code")


@overload(law_parts, jit_options=OPTIONS)
def _law_parts(law):
    if isinstance(law, (types.Integer, types.Boolean)):
        rise, fall, bounds, peak = PAPER_CAM
        r0, r1, r2, r3 = rise
        f0_, f1, f2, f3 = fall
        b0, b1, b2, b3, b4 = bounds
        q0, q1, q2, q3 = peak
        n = HERTZ.n

        def paper(law):
            the_cam = PhasedCam(
                Cosine(r0, r1, r2, r3),
                Cosine(f0_, f1, f2, f3),
                (b0, b1, b2, b3, b4),
                (q0, q1, q2, q3),
            )
            return int(law), the_cam, HuntCrossleyHertz(n)

        return paper

    def parts(law):
        return int(law.bits), law.cam, law.contact

    return parts


@hot
def phase_of(theta):
    """Cam phase containing angle θ ∈ [0, 2π) (a boundary belongs to the next phase)."""
    if theta < PHASE_BOUNDS[1]:
        return RISE
    if theta < PHASE_BOUNDS[2]:
        return FAR_DWELL
    if theta < PHASE_BOUNDS[3]:
        return FALL
    return NEAR_DWELL


@hot
def cam(theta, phase, law):
    """Cam lift yc(θ) and its first two θ-derivatives with the formula of ``phase`` of the
    cam ``law`` (p.cam; campar.core.cam).

    The formula is used as given even a rounding error outside the phase, so
    within a step the cam is a smooth function of time.
    """
    return lift(law, theta, phase)


@hot
def contact_force(eps, deps, p):
    """The contact law's force Pn for penetration ε and its rate ε' (docs/model.md, paper
    eq. 12; campar.core.contact)."""
    if eps <= 0.0:
        return 0.0
    force = contact.force(p.contact, p.k, damping(p.contact, p.c), eps, deps)
    if p.clamp and force < 0.0:
        return 0.0
    return force


@hot
def gap(t, y, p, phase):
    """Penetration ε = yc − y and the force law's ε' = ẏc − y' at time t (ẏc = p.vcam
    dyc/dθ: the time rate of ε by the chain rule, dyc/dθ with the literal cam velocity)."""
    yc, dyc, _ = cam(p.omega * t, phase, p.cam)
    return yc - y[0], p.vcam * dyc - y[1]


@hot
def released(contact, p):
    """True while the time counts towards the duty cycle: separated (contact mode FREE),
    or, with the duty cycle by force, any mode without force (FREE or SLACK)."""
    return contact == FREE or (p.dc_force and contact == SLACK)


@hot
def contact_mode(eps, deps, p):
    """The contact mode a state is in (used where no event history exists)."""
    if eps <= 0.0:
        return FREE
    if p.clamp and 1.0 + damping(p.contact, p.c) * deps <= 0.0:
        return SLACK
    return PUSH


@hot
def acceleration(t, y, v, p, mode):
    """y'' of the current mode at (y, y') and its partial derivatives ∂y''/∂y, ∂y''/∂y'."""
    acc = -2.0 * p.zeta * v - y - p.f0
    dfdy = 0.0
    dfdv = 0.0
    if mode[1] == PUSH:  # only a pushing contact needs the cam
        yc, dyc, _ = cam(p.omega * t, mode[0], p.cam)
        eps = yc - y
        deps = p.vcam * dyc - v
        if eps < 0.0:  # a stage point just past an event: extend by zero force
            eps = 0.0
        force, dfdy, dfdv = pushing(p.contact, p.k, damping(p.contact, p.c), eps, deps)
        acc += force
    return acc, dfdy, dfdv


@hot
def rhs(t, y, p, mode, dy):
    """Vector field of the current mode into ``dy``; variational part if len(y) == 6."""
    v = y[1]
    acc = -2.0 * p.zeta * v - y[0] - p.f0
    dfdy = 0.0
    dfdv = 0.0
    if mode[1] == PUSH:  # only a pushing contact needs the cam
        yc, dyc, _ = cam(p.omega * t, mode[0], p.cam)
        eps = yc - y[0]
        deps = p.vcam * dyc - v
        if eps < 0.0:  # a stage point just past an event: extend by zero force
            eps = 0.0
        force, dfdy, dfdv = pushing(p.contact, p.k, damping(p.contact, p.c), eps, deps)
        acc += force
    dy[0] = v
    dy[1] = acc
    if y.shape[0] == N_STATE_VARIATIONAL:
        a10 = -1.0 + dfdy
        a11 = -2.0 * p.zeta + dfdv
        dy[2] = y[4]
        dy[3] = y[5]
        dy[4] = a10 * y[2] + a11 * y[4]
        dy[5] = a10 * y[3] + a11 * y[5]


@hot
def events(t, y, f, p, mode, g, dg):
    """Event functions of the current contact mode into g, their rates into dg.

    Each g_i is positive while the mode holds; the mode ends where one reaches 0.
    FREE: g0 = −ε (impact). PUSH: g0 = ε (detachment), g1 = 1 + c ε' (force
    reaches zero, clamp only). SLACK: g0 = ε (detachment), g1 = −(1 + c ε').
    Rates use f = rhs(t, y): the rate of ε is its time derivative ω dyc/dθ − y', that
    of the force's ε' (p.vcam dyc/dθ − y') is p.vcam ω d²yc/dθ² − y''. Returns the
    number of event functions.
    """
    yc, dyc, d2yc = cam(p.omega * t, mode[0], p.cam)
    eps = yc - y[0]
    rate = p.omega * dyc - y[1]
    if mode[1] == FREE:
        g[0] = -eps
        dg[0] = -rate
        return 1
    g[0] = eps
    dg[0] = rate
    if not p.clamp:
        return 1
    deps = p.vcam * dyc - y[1]
    d2eps = p.vcam * p.omega * d2yc - f[1]
    sign = 1.0 if mode[1] == PUSH else -1.0
    c = damping(p.contact, p.c)
    g[1] = sign * (1.0 + c * deps)
    dg[1] = sign * c * d2eps
    return 2


@hot
def event_curvature(y, p, mode):
    """A bound on |g0''| (in time) over any step from y in this mode: in free flight,
    where the field does not see the cam, g0 = −ε = y − yc and the step size knows
    nothing of the cam's lift (the integrator's event search uses the bound there); inf
    in the contact modes, whose field has the cam.

    The free follower's (y + f0)² + y'² does not grow (its rate is −4ζ y'²), so
    |y''| = |y + f0 + 2ζ y'| ≤ √(1 + 4ζ²) √((y + f0)² + y'²) all along the step, and
    |d²yc/dt²| ≤ ω² times the phase's largest |S''| (the cam's ``peak``).
    """
    if mode[1] != FREE:
        return math.inf
    energy = (y[0] + p.f0) ** 2 + y[1] ** 2
    follower = math.sqrt((1.0 + 4.0 * p.zeta * p.zeta) * energy)
    return p.omega * p.omega * p.cam.peak[mode[0]] + follower


@hot
def mode_after_event(contact, which):
    """Contact mode after event ``which`` of mode ``contact`` fired (an impact: see
    ``impact_mode``, which the kernel uses)."""
    if contact == FREE:
        return PUSH  # impact: ε' ≥ 0 there, so 1 + c ε' > 0 (with the chain rule)
    if which == 0:
        return FREE  # detachment
    return SLACK if contact == PUSH else PUSH


@hot
def impact_mode(deps, p):
    """Contact mode at an impact where the force law's ε' is ``deps`` (``gap``). ε rises
    there, so with the chain rule ε' ≥ 0 and the follower pushes; the literal cam
    velocity's ε' can be below −1/c, and the clamp then holds Pn = 0 from the impact on."""
    if p.clamp and 1.0 + damping(p.contact, p.c) * deps <= 0.0:
        return SLACK
    return PUSH


@hot
def is_detachment(contact, which):
    """True when event ``which`` of mode ``contact`` is a contact → separation."""
    return contact != FREE and which == 0


@hot
def contact_kinematics(t, y, f, p, mode):
    """ε, dε/dt, d²ε/dt², Pn and dPn/dt at a state with field value f, in the current mode.

    Pn is the force of the mode's own field (zero unless pushing), so its rate
    is continuous inside a step.
    """
    yc, dyc, d2yc = cam(p.omega * t, mode[0], p.cam)
    eps = yc - y[0]
    rate = p.omega * dyc - y[1]
    accel = p.omega * p.omega * d2yc - f[1]
    if mode[1] != PUSH or eps <= 0.0:
        return eps, rate, accel, 0.0, 0.0
    deps = p.vcam * dyc - y[1]  # the force law's ε'
    d2eps = p.vcam * p.omega * d2yc - f[1]
    pn, dpn = force_and_rate(p.contact, p.k, damping(p.contact, p.c), eps, deps, rate, d2eps)
    return eps, rate, accel, pn, dpn


@hot
def kinematics(t, y, v, acc, p, mode):
    """contact_kinematics of the state (y, y') with y'' = acc."""
    yc, dyc, d2yc = cam(p.omega * t, mode[0], p.cam)
    eps = yc - y
    rate = p.omega * dyc - v
    accel = p.omega * p.omega * d2yc - acc
    if mode[1] != PUSH or eps <= 0.0:
        return eps, rate, accel, 0.0, 0.0
    deps = p.vcam * dyc - v  # the force law's ε'
    d2eps = p.vcam * p.omega * d2yc - acc
    pn, dpn = force_and_rate(p.contact, p.k, damping(p.contact, p.c), eps, deps, rate, d2eps)
    return eps, rate, accel, pn, dpn
