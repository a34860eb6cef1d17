"""A continued branch as a record: its points' parameter, orbits, multipliers, stability,
n-p labels, ε and Pn extremes, special points and why it ended, and its switched children.

``assemble`` builds it from the points of a continuation (campar.continuation.branch);
``Branch.to_dict`` is what ``campar continue --json`` prints.
"""

import math
from dataclasses import dataclass, field

import numpy as np

from .orbit import multipliers_of, section_points
from .special import SpecialPoint


@dataclass
class Branch:
    """A branch of n-cycles along ``parameter``, point by point (arrays of length N).

    values: the parameter; states (N, 2) and sections (N, n, 2): the orbit at θ = 0;
    multipliers (N, 2) complex; stable, p, dc, eps_min, eps_max, pn_max, touch per point;
    special: the located special points in branch order; end: why the branch stopped;
    origin: the PD point it was switched from (None for a branch started from an orbit);
    children: the branches switched from its PD points.
    """

    parameter: str
    n: int
    parameters: dict  # the other parameters (fixed along the branch)
    model: dict
    values: np.ndarray
    states: np.ndarray
    sections: np.ndarray
    multipliers: np.ndarray
    stable: np.ndarray
    p: np.ndarray
    dc: np.ndarray
    eps_min: np.ndarray
    eps_max: np.ndarray
    pn_max: np.ndarray
    touch: np.ndarray
    special: list[SpecialPoint]
    end: str
    origin: SpecialPoint | None = None
    children: list["Branch"] = field(default_factory=list)
    switch_failures: list[str] = field(default_factory=list)
    shots: int = 0  # integrations of n revolutions it took
    returned: bool = False  # ended where it returned onto the branch of period n/2
    closed: bool = False  # a closed loop, ended back at its first point

    @property
    def labels(self) -> list[str]:
        return [f"{self.n}-{p}" for p in self.p]

    def walk(self):
        """This branch, then its children's branches, depth first."""
        yield self
        for child in self.children:
            yield from child.walk()

    def to_dict(self) -> dict:
        def complex_pairs(row):
            return [[float(m.real), float(m.imag)] for m in row]

        return {
            "parameter": self.parameter,
            "n": self.n,
            "parameters": self.parameters,
            "model": self.model,
            "end": self.end,
            "origin": self.origin.to_dict() if self.origin else None,
            "points": [
                {
                    "value": float(self.values[i]),
                    "state": self.states[i].tolist(),
                    "sections": self.sections[i].tolist(),
                    "label": self.labels[i],
                    "stable": bool(self.stable[i]),
                    "multipliers": complex_pairs(self.multipliers[i]),
                    "dc": float(self.dc[i]),
                    "eps_min": float(self.eps_min[i]),
                    "eps_max": float(self.eps_max[i]),
                    "pn_max": float(self.pn_max[i]),
                }
                for i in range(len(self.values))
            ],
            "special": [sp.to_dict() for sp in self.special],
            "children": [child.to_dict() for child in self.children],
        }


def assemble(
    engine,
    points: list,
    special: list[SpecialPoint],
    end: str,
    origin: SpecialPoint | None = None,
    shots: int = 0,
) -> Branch:
    """The Branch of a continuation's points (``engine``: the campar.continuation.branch
    Continuation that found them: its period, parameter, fixed values and section map)."""
    n = engine.n
    period = [n * 2.0 * math.pi / engine.parameters_at(pt.u[2])[0] for pt in points]
    mult = np.array([multipliers_of(pt.jacobian) for pt in points], dtype=complex).reshape(-1, 2)
    others = {
        k: float(v) for k, v in zip(engine.smap.order, engine.par, strict=True) if k != engine.name
    }
    return Branch(
        parameter=engine.name,
        n=n,
        parameters=others,
        model=dict(engine.smap.model),
        values=np.array([pt.u[2] for pt in points]),
        states=np.array([pt.u[:2] for pt in points]).reshape(-1, 2),
        sections=np.array([section_points(pt.shot) for pt in points]).reshape(-1, n, 2),
        multipliers=mult,
        stable=np.abs(mult).max(axis=1) < 1.0 if len(points) else np.zeros(0, bool),
        p=np.array([pt.p for pt in points], dtype=int),
        dc=np.array([pt.shot.time_free / T for pt, T in zip(points, period, strict=True)]),
        eps_min=np.array([pt.shot.eps_min for pt in points]),
        eps_max=np.array([pt.shot.eps_max for pt in points]),
        pn_max=np.array([pt.shot.pn_max for pt in points]),
        touch=np.array([pt.touch for pt in points]),
        special=special,
        end=end,
        origin=origin,
        shots=shots,
        returned=engine.returned,
        closed=engine.closed,
    )
