"""Contact force laws: the normal force Pn of a penetration ε and its rate ε'.

Every law here has the form Pn = k ε^n (1 + c ε') for ε > 0 (dimensionless, docs/model.md):

- Hunt–Crossley (the paper's): c = 2 ζ μcn / (1 − μcn) from the job, exponent n (1.5,
  Hertz's point contact, unless the job says otherwise: line contacts are often
  modelled with n ≈ 1.0–1.1);
- Lankarani–Nikravesh: c = 3 (1 − e²) / (4 ε'⁻), and Flores et al.: c = 8 (1 − e) /
  (5 e ε'⁻), with e the coefficient of restitution and ε'⁻ the penetration rate at the
  onset of the contact (the impact velocity). μcn plays no part in them.

The impact velocity of the last impact is kept in the law's own one-element buffer
(``RestitutionDamped.impact``), written where the revolution switches FREE → contact:
for as long as a contact lasts, its damping is the one its impact set. Below
``floor`` an impact counts as one at ``floor``: these laws are derived for impacts, and
their damping χ/ε'⁻ grows without bound as impacts die out into lasting contact. A chain
starts with the buffer at the floor (``start_chain``) and carries it from cell to cell
with the state; so with these laws the state at θ = 0 is (y, y', ε'⁻), and the
variational equations hold ε'⁻ fixed (Floquet multipliers and Newton jumps leave out
how the impact velocity moves with the start).

As the cam laws (campar.core.cam), each law is a class of its own and the functions here
pick the law's formula by its class when numba types the call: the kernel compiles
only the job's law, and the paper's (n = 1.5) is written as the paper's kernel always was.
"""

import math
from typing import NamedTuple

import numpy as np
from numba.extending import overload

from .cam import OPTIONS, _law_class

CONTACT_LAWS = ("hunt-crossley", "lankarani-nikravesh", "flores")
HERTZ_EXPONENT = 1.5
IMPACT_FLOOR = 1e-3  # default floor of the impact velocity (units of h ωn)


class HuntCrossleyHertz(NamedTuple):
    """Hunt–Crossley with n = 3/2 (the paper's): ε^{3/2} as ε √ε."""

    n: float


class HuntCrossley(NamedTuple):
    """Hunt–Crossley with any exponent n ≥ 1."""

    n: float


class RestitutionDamped(NamedTuple):
    """Lankarani–Nikravesh or Flores et al.: damping chi / ε'⁻ (ε'⁻: ``impact[0]``)."""

    n: float
    chi: float
    floor: float
    impact: np.ndarray  # float64[1]: the impact velocity of the contact, ≥ floor


HERTZ = HuntCrossleyHertz(HERTZ_EXPONENT)


def hysteresis_factor(law: str, restitution: float) -> float:
    """χ of a restitution law: c = χ / ε'⁻."""
    e = restitution
    if law == "lankarani-nikravesh":
        return 0.75 * (1.0 - e * e)
    return 8.0 * (1.0 - e) / (5.0 * e)


def contact_law(
    law: str = "hunt-crossley",
    n: float = HERTZ_EXPONENT,
    restitution: float = 0.8,
    floor: float = IMPACT_FLOOR,
    general: bool = False,
):
    """The kernel's contact law; ``general``: Hunt–Crossley by pow even at n = 1.5 (so a map
    that sweeps n compiles one law for every row). ValueError for values out of range."""
    if law not in CONTACT_LAWS:
        raise ValueError(f"unknown contact law {law!r}; allowed: {', '.join(CONTACT_LAWS)}")
    if not (math.isfinite(n) and 1.0 <= n <= 3.0):
        raise ValueError(f"the contact exponent n must be in [1, 3], got {n}")
    if law == "hunt-crossley":
        return HERTZ if n == HERTZ_EXPONENT and not general else HuntCrossley(float(n))
    if not (math.isfinite(restitution) and 0.0 < restitution <= 1.0):
        raise ValueError(f"the restitution coefficient must be in (0, 1], got {restitution}")
    if not (math.isfinite(floor) and floor > 0.0):
        raise ValueError(f"the impact velocity floor must be > 0, got {floor}")
    impact = np.full(1, float(floor))
    return RestitutionDamped(float(n), hysteresis_factor(law, restitution), float(floor), impact)


def start_chain(law) -> None:
    """A chain's first cell knows no impact yet: its impact velocity starts at the floor."""
    if isinstance(law, RestitutionDamped):
        law.impact[0] = law.floor


# -- evaluation (numba) ------------------------------------------------------------------


def damping(law, c):
    """The damping coefficient c of the force's bracket 1 + c ε' (compiled code only)."""
    raise TypeError("campar.core.contact.damping is for compiled code")


def pushing(law, k, c, eps, deps):
    """(Pn, ∂(y'')/∂y, ∂(y'')/∂y') of a pushing contact, ε ≥ 0 (compiled code only)."""
    raise TypeError("campar.core.contact.pushing is for compiled code")


def force_and_rate(law, k, c, eps, deps, rate, d2eps):
    """(Pn, dPn/dt) of a pushing contact at ε > 0 (compiled code only)."""
    raise TypeError("campar.core.contact.force_and_rate is for compiled code")


def force(law, k, c, eps, deps):
    """Pn at ε > 0, no clamp (compiled code only)."""
    raise TypeError("campar.core.contact.force is for compiled code")


def note_impact(law, deps):
    """Keep the impact velocity ε'⁻ of a contact that begins (compiled code only)."""
    raise TypeError("campar.core.contact.note_impact is for compiled code")


def impact_velocity(law):
    """The impact velocity the law keeps, 0 for a law without one (compiled code only):
    note_impact(law, impact_velocity(law)) restores it."""
    raise TypeError("campar.core.contact.impact_velocity is for compiled code")


def _own_damping(law, c):
    return c


def _impact_damping(law, c):
    return law.chi / law.impact[0]


def _hertz_pushing(law, k, c, eps, deps):
    s = math.sqrt(eps)
    bracket = 1.0 + c * deps
    return k * eps * s * bracket, -1.5 * k * s * bracket, -k * eps * s * c


def _power_pushing(law, k, c, eps, deps):
    en1 = math.pow(eps, law.n - 1.0)
    en = eps * en1
    bracket = 1.0 + c * deps
    return k * en * bracket, -law.n * k * en1 * bracket, -k * en * c


def _hertz_rate(law, k, c, eps, deps, rate, d2eps):
    s = math.sqrt(eps)
    bracket = 1.0 + c * deps
    return k * eps * s * bracket, k * (1.5 * s * rate * bracket + eps * s * c * d2eps)


def _power_rate(law, k, c, eps, deps, rate, d2eps):
    en1 = math.pow(eps, law.n - 1.0)
    en = eps * en1
    bracket = 1.0 + c * deps
    return k * en * bracket, k * (law.n * en1 * rate * bracket + en * c * d2eps)


def _hertz_force(law, k, c, eps, deps):
    return k * eps * math.sqrt(eps) * (1.0 + c * deps)


def _power_force(law, k, c, eps, deps):
    return k * math.pow(eps, law.n) * (1.0 + c * deps)


def _no_memory(law, deps):
    return None


def _keep_impact(law, deps):
    law.impact[0] = max(deps, law.floor)


def _no_impact(law):
    return 0.0


def _kept_impact(law):
    return law.impact[0]


_IMPLS = {  # damping, pushing, force_and_rate, force, note_impact, impact_velocity
    HuntCrossleyHertz: (
        _own_damping,
        _hertz_pushing,
        _hertz_rate,
        _hertz_force,
        _no_memory,
        _no_impact,
    ),
    HuntCrossley: (_own_damping, _power_pushing, _power_rate, _power_force, _no_memory, _no_impact),
    RestitutionDamped: (
        _impact_damping,
        _power_pushing,
        _power_rate,
        _power_force,
        _keep_impact,
        _kept_impact,
    ),
}


def _impl(law, index):
    impls = _IMPLS.get(_law_class(law))
    return None if impls is None else impls[index]


@overload(damping, jit_options=OPTIONS)
def _damping(law, c):
    return _impl(law, 0)


@overload(pushing, jit_options=OPTIONS)
def _pushing(law, k, c, eps, deps):
    return _impl(law, 1)


@overload(force_and_rate, jit_options=OPTIONS)
def _force_and_rate(law, k, c, eps, deps, rate, d2eps):
    return _impl(law, 2)


@overload(force, jit_options=OPTIONS)
def _force(law, k, c, eps, deps):
    return _impl(law, 3)


@overload(note_impact, jit_options=OPTIONS)
def _note_impact(law, deps):
    return _impl(law, 4)


@overload(impact_velocity, jit_options=OPTIONS)
def _impact_velocity(law):
    return _impl(law, 5)
