"""Special points of a branch of periodic orbits: their test functions and their location.

Between two consecutive points of a branch a special point is detected by a change of
sign of its test function and then located by a root finder along the branch (each trial
point a corrected branch point), to ``LOCATE_TOL`` in the parameter:

- PD, period doubling (flip): a real multiplier crosses −1; ψ = det(DPⁿ + I).
- SN, fold (saddle-node, turning point): a real multiplier crosses +1 where the branch
  turns back in the parameter; ψ = det(DPⁿ − I), with the tangent's parameter component
  changing sign too. Without that turn the crossing is a branch point (BP: pitchfork or
  transcritical of Pⁿ).
- NS, Neimark–Sacker: a complex pair crosses the unit circle; ψ = det(DPⁿ) − 1 while the
  pair is complex. (With ζ > 0 this model has none: det DPⁿ = exp(∮ div f dt) < 1 since
  div f = −2ζ − k c ε^{3/2} ≤ −2ζ < 0.)
- G, grazing: the contact pattern changes — the detachments per period p differ between
  the two points. It is located as the root of the orbit's ``touch``, the value of ε at
  its extremum nearest 0 (a local minimum of ε in contact reaching 0 opens a flight, a
  local maximum of ε in flight reaching 0 makes a contact); where ``touch`` does not
  change sign it is located by bisection on p. The Hunt–Crossley force and its ε
  derivative vanish at ε = 0, so Pⁿ stays C¹ across a grazing (its second derivatives
  are singular there): Newton's method and the arclength steps cross it like any point,
  with no event to divide by.
"""

import math
from dataclasses import dataclass, field

import numpy as np

LOCATE_TOL = 1e-10  # a special point's parameter, to this (well inside the 1e-8 asked)
MAX_LOCATE_STEPS = 60
PD, SN, BP, NS, G = "PD", "SN", "BP", "NS", "G"
TYPES = (PD, SN, BP, NS, G)
DESCRIPTIONS = {
    PD: "period doubling: a real multiplier crosses −1",
    SN: "fold (saddle-node): a multiplier crosses +1 and the branch turns back",
    BP: "branch point: a multiplier crosses +1 without a turn",
    NS: "Neimark–Sacker: a complex pair crosses the unit circle",
    G: "grazing: the contact pattern (detachments per period) changes",
}


def psi_pd(m: np.ndarray) -> float:
    return 1.0 + m[0, 0] + m[1, 1] + np.linalg.det(m)


def psi_sn(m: np.ndarray) -> float:
    return 1.0 - m[0, 0] - m[1, 1] + np.linalg.det(m)


def psi_ns(m: np.ndarray) -> float:
    """det M − 1 while M's eigenvalues are a complex pair; NaN (no NS possible) otherwise."""
    tr = m[0, 0] + m[1, 1]
    det = np.linalg.det(m)
    return det - 1.0 if tr * tr < 4.0 * det else math.nan


@dataclass(frozen=True)
class SpecialPoint:
    """A located bifurcation or grazing point of a branch.

    value: the parameter there; state: the orbit's (y, y') at θ = 0; multipliers of DPⁿ
    there; labels and stability of the branch on both sides (before, after) in the
    branch's direction; accuracy: the parameter's bracket when the root finder stopped.
    """

    type: str
    parameter: str
    value: float
    state: tuple[float, float]
    n: int
    multipliers: tuple[complex, complex]
    labels: tuple[str, str]
    stable: tuple[bool, bool]
    accuracy: float
    parameters: dict = field(default_factory=dict)  # every model parameter there
    eigenvector: tuple[float, float] | None = None  # PD: of the multiplier −1
    arclength: float = 0.0  # along its branch, from the branch's first point

    def to_dict(self) -> dict:
        return {
            "type": self.type,
            "parameter": self.parameter,
            "value": self.value,
            "state": list(self.state),
            "n": self.n,
            "multipliers": [[m.real, m.imag] for m in self.multipliers],
            "labels": list(self.labels),
            "stable": list(self.stable),
            "accuracy": self.accuracy,
            "parameters": self.parameters,
            "description": DESCRIPTIONS[self.type],
        }


def crossings(a, b) -> list[str]:
    """The special point types whose test functions change between branch points a and b
    (branch.BranchPoint), in no particular order."""
    found = []
    if a.p != b.p:
        found.append(G)
    if np.sign(psi_pd(a.jacobian)) != np.sign(psi_pd(b.jacobian)):
        found.append(PD)
    if np.sign(psi_sn(a.jacobian)) != np.sign(psi_sn(b.jacobian)):
        turned = np.sign(a.tangent[2]) != np.sign(b.tangent[2])
        found.append(SN if turned else BP)
    na, nb = psi_ns(a.jacobian), psi_ns(b.jacobian)
    if math.isfinite(na) and math.isfinite(nb) and np.sign(na) != np.sign(nb):
        found.append(NS)
    return found


def test_function(kind: str):
    """ψ of a branch point for ``kind``: its root is the special point. For SN the fold's
    ψ = det(DPⁿ − I) (exact, from the variational equations) rather than the tangent's
    parameter component (a difference quotient)."""
    return {
        PD: lambda pt: psi_pd(pt.jacobian),
        SN: lambda pt: psi_sn(pt.jacobian),
        BP: lambda pt: psi_sn(pt.jacobian),
        NS: lambda pt: psi_ns(pt.jacobian),
        G: lambda pt: pt.touch,
    }[kind]


def illinois(f, a: float, b: float, fa: float, fb: float, small) -> float:
    """A root of f in [a, b] (fa, fb of opposite signs) by the Illinois variant of regula
    falsi; stops when ``small(lo, hi)`` says the bracket is small enough."""
    side = 0
    for _ in range(MAX_LOCATE_STEPS):
        if small(a, b):
            break
        c = (a * fb - b * fa) / (fb - fa)
        if not (min(a, b) < c < max(a, b)):
            c = 0.5 * (a + b)
        fc = f(c)
        if fc == 0.0:
            return c
        if np.sign(fc) == np.sign(fb):
            b, fb = c, fc
            if side == -1:
                fa *= 0.5
            side = -1
        else:
            a, fa = c, fc
            if side == 1:
                fb *= 0.5
            side = 1
    return b if abs(fb) < abs(fa) else a
