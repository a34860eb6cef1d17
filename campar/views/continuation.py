"""Continuation from Python and for ``campar continue``: a branch from a simulated cell.

``continue_from_cell`` is what the command runs: it simulates the cell at the start of
the parameter's range (from rest or a given state, exactly as ``campar point``), solves
for the periodic orbit there by Newton's method (the simulated period, or the one asked
for), continues its branch across the range with branch switching at period doublings,
and optionally continues the curves of the branch's special points in a plane.
"""

import math
import time
from dataclasses import dataclass, field

from ..continuation.branch import Branch, BranchSettings
from ..continuation.curves import CURVE_TYPES, BifurcationCurve, continue_curve
from ..continuation.orbit import PeriodicOrbit, find_cycle
from ..continuation.section_map import PARAMETER_ORDER, SectionMap
from ..continuation.switching import continue_with_switching
from ..errors import ContinuationError, JobError
from .point import simulate_point


@dataclass
class ContinuationResult:
    """A continuation run: its first orbit, the branch tree and the curves, with its cost."""

    start: PeriodicOrbit
    root: Branch
    curves: list[BifurcationCurve] = field(default_factory=list)
    curve_failures: list[str] = field(default_factory=list)
    seconds: float = 0.0
    shots: int = 0

    def special_points(self):
        """(branch, special point) of every branch, in tree order."""
        for branch in self.root.walk():
            for sp in branch.special:
                yield branch, sp

    def to_dict(self) -> dict:
        return {
            "start": self.start.to_dict(),
            "branch": self.root.to_dict(),
            "special": [{"branch_period": b.n, **sp.to_dict()} for b, sp in self.special_points()],
            "curves": [curve.to_dict() for curve in self.curves],
            "curve_failures": self.curve_failures,
            "seconds": self.seconds,
            "shots": self.shots,
        }


def continue_from_cell(parameter: str, span: tuple[float, float], fixed: dict, *,
                       y0: float = 0.0, v0: float = 0.0, cycle: int | None = None,
                       switch: int = 0, model: dict | None = None,
                       settings: BranchSettings | None = None,
                       curve_types=(), second: str | None = None,
                       second_window: tuple[float, float] | None = None,
                       section_map: SectionMap | None = None) -> ContinuationResult:  # fmt: skip
    """Continue the periodic orbit of the cell at ``span[0]`` along ``parameter`` to span[1].

    Parameters
    ----------
    parameter : str
        The continuation parameter: omega, f0, mu_kn, mu_cn or zeta.
    span : (float, float)
        Where the branch starts and the far end of its window.
    fixed : dict
        The other parameters (the paper's base values for those not given).
    y0, v0 : float
        The simulation's start at θ = 0 (rest by default).
    cycle : int, optional
        The period solved for; by default the simulated cell's period.
    switch : int
        Period doublings to follow from each PD point (0: none).
    model : dict, optional
        The force law's options (tensile, duty_cycle, cam_velocity).
    settings : BranchSettings, optional
        Step control of the branches.
    curve_types : iterable of str
        PD, SN, NS, G: continue the curve of every special point of these types found on
        the branches in the plane (parameter, ``second``) over (span, ``second_window``).

    Returns
    -------
    ContinuationResult

    Raises
    ------
    ContinuationError
        The start cell is not periodic and no ``cycle`` is given, or Newton fails there.
    JobError
        A parameter or option out of range.
    """
    if parameter not in PARAMETER_ORDER:
        raise JobError(f"cannot continue along {parameter!r}; one of {', '.join(PARAMETER_ORDER)}")
    if span[0] == span[1]:
        raise JobError(f"the range of {parameter} is empty: {span[0]}:{span[1]}")
    unknown = sorted(set(curve_types) - set(CURVE_TYPES))
    if unknown:
        raise JobError(f"no curves of {unknown[0]}; one of {', '.join(CURVE_TYPES)}")
    if curve_types and (second is None or second_window is None or second == parameter):
        raise JobError("curves need a second parameter and its range (--second NAME:A:B)")
    began = time.perf_counter()
    model = dict(model or {})
    smap = section_map or SectionMap(model)
    shots0 = smap.shots
    values = {**fixed, parameter: span[0]}
    omega = values.pop("omega")
    cell = simulate_point(omega, y0=y0, v0=v0, **model, **values)
    period = cycle or cell.n
    if not period:
        raise ContinuationError(
            f"the cell at {parameter}={span[0]} is {cell.label} from ({y0}, {v0}): give the "
            "period to solve for (--cycle N) or a start on a cycle (--y0 --v0)"
        )
    if not all(map(math.isfinite, cell.state)):
        raise ContinuationError(f"the cell at {parameter}={span[0]} failed: {cell.status}")
    start = find_cycle(period, cell.state, section_map=smap, **{**fixed, parameter: span[0]})
    direction = 1.0 if span[1] > span[0] else -1.0
    root = continue_with_switching(start, parameter, span, switch, direction=direction,
                                   section_map=smap, settings=settings)  # fmt: skip
    result = ContinuationResult(start=start, root=root)
    for _, sp in list(result.special_points()):
        if sp.type not in curve_types:
            continue
        try:
            result.curves.append(continue_curve(sp, second, (span, second_window),
                                                section_map=smap))  # fmt: skip
        except ContinuationError as exc:
            result.curve_failures.append(f"{sp.type} at {parameter}={sp.value:.10g}: {exc}")
    result.seconds = time.perf_counter() - began
    result.shots = smap.shots - shots0
    return result


def describe_continuation(result: ContinuationResult) -> str:
    """A few lines: the start, every branch with its end, every special point."""
    start = result.start
    state = "stable" if start.stable else "unstable"
    lines = [f"start: {start.label} ({state}) at "
             + ", ".join(f"{k}={v:g}" for k, v in start.parameters.items())]  # fmt: skip
    for branch in result.root.walk():
        where = (
            ""
            if branch.origin is None
            else (
                f", switched at the PD point {branch.origin.parameter}={branch.origin.value:.10g}"
            )
        )
        lines.append(f"branch of period {branch.n}: {len(branch.values)} points{where}; "
                     f"{branch.end}")  # fmt: skip
        for sp in branch.special:
            mult = ", ".join(f"{m.real:+.6f}{m.imag:+.6f}j" for m in sp.multipliers)
            sides = " → ".join(f"{lab} {'stable' if st else 'unstable'}"
                               for lab, st in zip(sp.labels, sp.stable, strict=True))  # fmt: skip
            lines.append(f"  {sp.type:2s} at {sp.parameter}={sp.value:.10f} (±{sp.accuracy:.1e})"
                         f"  {sides}  multipliers {mult}")  # fmt: skip
        for failure in branch.switch_failures:
            lines.append(f"  no switch: {failure}")
    for curve in result.curves:
        lines.append(f"{curve.type} curve of {curve.n}-cycles in ({curve.first}, {curve.second}):"
                     f" {len(curve.values)} points; {curve.end}")  # fmt: skip
    lines.extend(f"no curve: {failure}" for failure in result.curve_failures)
    lines.append(f"{result.shots} integrations of the section map, {result.seconds:.2f} s")
    return "\n".join(lines)
