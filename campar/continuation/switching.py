"""Branch switching at period doublings: from a PD point onto the doubled branch, recursively.

At a PD point (x*, λ*) of an n-cycle, DPⁿ has the eigenvalue −1 with eigenvector v, and
P²ⁿ has a pitchfork: besides x*(λ), a branch of 2n-cycles x* ± a v + O(a²) leaves it with
λ − λ* = O(a²). The first point of the doubled branch is found as BifurcationKit and AUTO
do it, from the pitchfork's predicted direction: Newton's method on P²ⁿ(x; λ) − x = 0 with
the constraint v·(x − x*) = δ, started at (x* + δ v, λ*), which lies O(δ²) from the
doubled branch and O(δ) from x*(λ). The continuation then leaves the PD point along +v;
the doubled branch ends where it leaves the window, turns into another branch or returns
onto the n-cycles (at the PD point closing a period-doubling bubble).

``continue_with_switching`` applies this at every PD point of a branch and of its
children, down to ``depth`` doublings: a period-doubling cascade 1 → 2 → 4 → …
"""

import logging

import numpy as np

from ..errors import ContinuationError
from .branch import BranchSettings, Continuation, continue_branch
from .branch_result import Branch, assemble
from .orbit import PeriodicOrbit, minimal_period, section_points
from .section_map import SectionMap
from .special import PD, SpecialPoint

log = logging.getLogger("campar.continue")

SWITCH_OFFSETS = (1e-3, 4e-3, 1.6e-2)  # δ tried in turn: the doubled branch's first point
SAME_POINT = 1e-5  # PD points this close in the parameter are one (a bubble's two ends)
MAX_BRANCHES = 64  # every branch of one cascade, at most
MAX_PERIOD = 32  # no switching onto cycles longer than this (revolutions)


def switch_at_pd(
    smap: SectionMap, sp: SpecialPoint, window, settings: BranchSettings, offsets=SWITCH_OFFSETS
) -> Branch:
    """The doubled branch (period 2n) born at the PD point ``sp``, continued in ``window``.

    Raises ContinuationError when Newton finds no 2n-cycle near the PD point for any
    offset δ in ``offsets``.
    """
    if sp.type != PD or sp.eigenvector is None:
        raise ContinuationError(f"branch switching needs a PD point, got {sp.type}")
    par = smap.vector(sp.parameters)
    engine = Continuation(smap, par, sp.parameter, 2 * sp.n, window, settings)
    v = np.array(sp.eigenvector)
    normal = np.array([v[0], v[1], 0.0])
    shots0 = smap.shots
    for delta in offsets:
        anchor = np.array([sp.state[0] + delta * v[0], sp.state[1] + delta * v[1], sp.value])
        found = engine.correct(anchor, normal, anchor, engine.column(anchor))
        if found is None:
            continue
        u, shot, _ = found
        if minimal_period(section_points(shot)) < engine.n:
            continue  # Newton fell back onto the n-cycle
        start = engine.point(u, shot, normal)
        points, special, end = engine.run(start)
        return assemble(engine, points, special, end, origin=sp, shots=smap.shots - shots0)
    raise ContinuationError(
        f"no {2 * sp.n}-cycle found next to the PD point at {sp.parameter}={sp.value:.10g}"
    )


def continue_with_switching(
    orbit: PeriodicOrbit,
    parameter: str,
    window,
    depth: int,
    *,
    direction: float | None = None,
    section_map: SectionMap | None = None,
    settings: BranchSettings | None = None,
    switched: list | None = None,
    max_period: int = MAX_PERIOD,
) -> Branch:
    """The branch of ``orbit`` and, ``depth`` doublings deep, the branches born at its PD
    points (each a child of the branch it was switched from: ``Branch.children``).

    A PD point is switched once: where a doubled branch was already started, or where one
    ended (the far end of a period-doubling bubble), it is not switched again. Several
    calls share that record through ``switched`` (a list of (period, parameter value)).
    Where no doubled branch could be started, the reason is kept in the branch's
    ``switch_failures``. No branch of period above ``max_period`` is switched onto.

    Parameters
    ----------
    orbit : PeriodicOrbit
        The corrected orbit the root branch starts from.
    parameter : str
        The continuation parameter: omega, f0, mu_kn, mu_cn or zeta.
    window : (float, float)
        The parameter window every branch stays in.
    depth : int
        How many doublings deep to switch (0: the root branch alone).
    direction : float, optional
        +1 or -1: the root branch's first step in the parameter (default: towards the
        window's far end).
    section_map : SectionMap, optional
        The section map to shoot with (one is built from the orbit's model if not given).
    settings : BranchSettings, optional
        Step control of every branch.
    switched : list, optional
        The (period, parameter value) of PD points already switched, shared between calls.
    max_period : int
        The longest period a branch is switched onto.

    Returns
    -------
    Branch
        The root branch; the switched branches are its descendants (``Branch.walk``).

    Examples
    --------
    >>> from campar.continuation.orbit import find_cycle
    >>> from campar.continuation.switching import continue_with_switching
    >>> orbit = find_cycle(1, (0.6, -0.6), omega=4.0, mu_kn=0.91)
    >>> root = continue_with_switching(orbit, "omega", (2.0, 4.0), 1)
    >>> [(branch.n, branch.returned) for branch in root.walk()]
    [(1, False), (2, True)]
    """
    smap = section_map or SectionMap(orbit.model)
    settings = settings or BranchSettings()
    root = continue_branch(
        orbit, parameter, window, direction=direction, section_map=smap, settings=settings
    )
    switched = [] if switched is None else switched
    pending = [(root, depth)]
    count = 1
    while pending:
        branch, left = pending.pop(0)
        if left <= 0:
            continue
        for sp in branch.special:
            if sp.type != PD or count >= MAX_BRANCHES or 2 * sp.n > max_period:
                continue
            if any(n == sp.n and abs(v - sp.value) < SAME_POINT for n, v in switched):
                continue
            switched.append((sp.n, sp.value))
            try:
                child = switch_at_pd(smap, sp, window, settings)
            except ContinuationError as exc:
                branch.switch_failures.append(str(exc))
                continue
            if child.returned and len(child.values):
                switched.append((sp.n, float(child.values[-1])))  # the bubble's other end
            log.info(
                "%d-cycles switched at %s=%.8f: %d points, %s",
                child.n,
                sp.parameter,
                sp.value,
                len(child.values),
                child.end,
            )
            branch.children.append(child)
            count += 1
            pending.append((child, left - 1))
    return root
