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

import numpy as np

from ..continuation.branch import BranchSettings
from ..continuation.branch_result import Branch
from ..continuation.curves import CURVE_TYPES, BifurcationCurve, continue_curve
from ..continuation.orbit import PeriodicOrbit, find_cycle, solve_cycle
from ..continuation.section_map import PARAMETER_ORDER, SectionMap
from ..continuation.switching import continue_with_switching
from ..errors import ContinuationError, JobError
from ..model import Model
from ..model.laws import LAW_PARAMETERS
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
    reached: str = ""  # the label of the simulated start cell
    chosen: str = ""  # how the start cycle was chosen
    missing: list[str] = field(default_factory=list)  # what was asked for and not found, why

    def special_points(self):
        """(branch, special point) of every branch, in tree order."""
        for branch in self.root.walk():
            for sp in branch.special:
                yield branch, sp

    def to_dict(self) -> dict:
        return {
            "start": self.start.to_dict(),
            "start_cell": self.reached,
            "start_chosen": self.chosen,
            "missing": self.missing,
            "branch": self.root.to_dict(),
            "special": [{"branch_period": b.n, **sp.to_dict()} for b, sp in self.special_points()],
            "curves": [curve.to_dict() for curve in self.curves],
            "curve_failures": self.curve_failures,
            "seconds": self.seconds,
            "shots": self.shots,
        }


def continue_from_cell(
    parameter: str,
    span: tuple[float, float],
    fixed: dict | None = None,
    *,
    y0: float | None = None,
    v0: float | None = None,
    cycle: int | None = None,
    switch: int = 0,
    model: Model | dict | None = None,
    settings: BranchSettings | None = None,
    curve_types=(),
    second: str | None = None,
    second_window: tuple[float, float] | None = None,
    section_map: SectionMap | None = None,
) -> ContinuationResult:
    """Continue the periodic orbit of the cell at ``span[0]`` along ``parameter`` to span[1].

    Parameters
    ----------
    parameter : str
        The continuation parameter: omega, f0, mu_kn, mu_cn, zeta, or a law parameter of
        the model (phi1 … phi4, n, restitution; campar.model.laws.LAW_PARAMETERS).
    span : (float, float)
        Where the branch starts and the far end of its window.
    fixed : dict, optional
        The other parameters: the ``model``'s values for those not given (the paper's
        base values without a Model).
    y0, v0 : float, optional
        The simulation's start at θ = 0 (default the model's ``initial``: rest).
    cycle : int, optional
        The period solved for; by default the simulated cell's period.
    switch : int
        Period doublings to follow from each PD point (0: none).
    model : Model or dict, optional
        The cell's model (``campar.model.Model``: the force law, cam, contact and
        settings of the simulated start), or the force law's options (tensile,
        duty_cycle, cam_velocity). The parameters in ``fixed`` and ``span`` take
        precedence over its own.
    settings : BranchSettings, optional
        Step control of the branches.
    curve_types : iterable of str
        PD, SN, NS, G: continue the curve of every special point of these types found on
        the branches in the plane (parameter, ``second``) over (span, ``second_window``).
    second : str, optional
        The second parameter of those curves: omega, f0, mu_kn, mu_cn, zeta, or a law
        parameter when ``parameter`` is not one (a plane holds one law parameter).
    second_window : (float, float), optional
        The window of ``second`` the curves stay in.
    section_map : SectionMap, optional
        The section map to shoot with (one is built from ``model`` if not given).

    Returns
    -------
    ContinuationResult
        Its ``start`` cycle, ``reached`` (the simulated cell's label) and ``chosen`` (how
        the start was chosen), the branch tree, the curves (each once: a special point on
        a curve already continued starts none) and ``missing``: a line for each thing
        asked for and not found, saying why.

    Examples
    --------
    >>> from campar.views.continuation import continue_from_cell
    >>> result = continue_from_cell("omega", (6.0, 5.0), {"mu_kn": 0.91})
    >>> result.start.label, [(sp.type, round(sp.value, 5)) for _, sp in result.special_points()]
    ('3-1', [('G', 5.46923), ('SN', 5.27333)])

    Raises
    ------
    ContinuationError
        The start cell is not periodic and no ``cycle`` is given, or Newton fails there.
    JobError
        Before any work (``check_request``): a parameter the model does not have, a range
        that is empty, not finite or outside the model's range, a second window that is
        not low:high inside its range, curves without a second parameter.
    """
    check_request(parameter, span, fixed or {}, curve_types, second, second_window, model)
    began = time.perf_counter()
    given = {**(fixed or {}), parameter: span[0]}
    base = start_model(model, given)
    # the law parameter the section map takes as its own: the branch's, or the curves'
    law = next((name for name in (parameter, second) if name in LAW_PARAMETERS), None)
    # every parameter of the model continued: its own where neither fixed nor span says
    values = {**base.parameters, **({law: span[0]} if law == parameter else {})}
    smap = section_map or SectionMap(base, law_parameter=law)
    shots0 = smap.shots
    y0, v0 = (base.initial.y if y0 is None else y0), (base.initial.v if v0 is None else v0)
    cell = simulate_point(base, state=(y0, v0))
    period = cycle or cell.n
    if not period:
        raise ContinuationError(
            f"the cell at {parameter}={span[0]} is {cell.label} from ({y0}, {v0}): give the "
            "period to solve for (--cycle N) or a start on a cycle (--y0 --v0)"
        )
    if not all(map(math.isfinite, cell.state)):
        raise ContinuationError(f"the cell at {parameter}={span[0]} failed: {cell.status}")
    start = solve_cycle(period, cell.state, values, section_map=smap)
    direction = 1.0 if span[1] > span[0] else -1.0
    root = continue_with_switching(
        start, parameter, span, switch, direction=direction, section_map=smap, settings=settings
    )
    result = ContinuationResult(start=start, root=root, reached=cell.label)
    result.chosen = (
        f"--cycle {cycle}, from the simulated cell ({cell.label})"
        if cycle
        else f"the cycle the simulation from ({y0:g}, {v0:g}) reaches (--cycle N: another)"
    )
    window = (span, second_window)
    for _, sp in list(result.special_points()):
        if sp.type not in curve_types or on_a_curve(sp, result.curves, window):
            continue
        try:
            result.curves.append(continue_curve(sp, second, window, section_map=smap))
        except ContinuationError as exc:
            result.curve_failures.append(f"{sp.type} at {parameter}={sp.value:.10g}: {exc}")
    result.missing = missing(result, parameter, span, switch, curve_types)
    result.seconds = time.perf_counter() - began
    result.shots = smap.shots - shots0
    return result


def start_model(model, given: dict) -> Model:
    """The model at the branch's start: ``model`` (a Model, the force law's options or
    None: the paper's) with the ``given`` parameters set."""
    if isinstance(model, Model):
        return model.replace(**given)
    if model is not None and not isinstance(model, dict):
        raise JobError(f"a model is a Model or the force law's options, got {type(model).__name__}")
    # the model section's keys, then the parameters (a law parameter after the law it sets)
    return Model.build(None, **{**(model or {}), **given})


def check_request(
    parameter, span, fixed, curve_types=(), second=None, second_window=None, model=None
):
    """Refuse, before any work, a request that cannot be computed as asked (JobError, one
    line): a parameter the model does not have, a range that is empty, not finite or
    leaves the model's range of its parameter, a fixed value out of range, curves of an
    unknown type, or curves without a second parameter and window (low:high) of their own.
    The ranges are those of ``model`` (a Model, the force law's options or None: the
    paper's; ``Model.build`` checks each value): a contact's restitution, say, is a
    parameter of the laws that have one."""
    if parameter not in (*PARAMETER_ORDER, *LAW_PARAMETERS):
        allowed = ", ".join((*PARAMETER_ORDER, *LAW_PARAMETERS))
        raise JobError(f"cannot continue along {parameter!r}; one of {allowed}")
    at = start_model(model, {"omega": 1.0}).replace(**fixed)  # each fixed value in its range
    check_range(at, parameter, span, f"the range {span[0]:g}:{span[1]:g} of {parameter}")
    if span[0] == span[1]:
        raise JobError(f"the range of {parameter} is empty: {span[0]:g}:{span[1]:g}")
    unknown = sorted(set(curve_types) - set(CURVE_TYPES))
    if unknown:
        raise JobError(f"no curves of {unknown[0]}; one of {', '.join(CURVE_TYPES)}")
    if second is None and second_window is None:
        if curve_types:
            raise JobError("curves need a second parameter and its window (--second NAME:A:B)")
        return
    where = f"--second {second}:{second_window[0]:g}:{second_window[1]:g}"
    if second not in (*PARAMETER_ORDER, *LAW_PARAMETERS):
        raise JobError(
            f"{where}: {second!r} is not a parameter of the model; one of "
            f"{', '.join((*PARAMETER_ORDER, *LAW_PARAMETERS))}"
        )
    if second in LAW_PARAMETERS and parameter in LAW_PARAMETERS:
        raise JobError(
            f"{where}: a curve's plane holds one law parameter; the branch's is {parameter}"
        )
    if second == parameter:
        raise JobError(f"{where}: the second parameter must differ from the branch's, {parameter}")
    check_range(at, second, second_window, where)
    low, high = second_window
    if low == high:
        raise JobError(f"{where}: the window is empty; give two values, low:high")
    if low > high:
        raise JobError(f"{where}: a window runs from low to high: {second}:{high:g}:{low:g}")
    if not curve_types:
        raise JobError(f"{where} is the plane of the curves: give their types (--curves PD,G)")


def check_range(model: Model, name: str, span, where: str) -> None:
    """Both ends of ``span`` finite and inside ``model``'s range of ``name`` (JobError
    naming ``where``)."""
    for value in span:
        try:
            model.replace(**{name: value})
        except JobError as exc:
            raise JobError(f"{where}: {exc}") from None


def on_a_curve(sp, curves: list[BifurcationCurve], window) -> bool:
    """True when the special point ``sp`` lies on one of ``curves`` of its type and period:
    within a step of the curve's nearest vertex in the plane (scaled to the window) and in
    the cycle's state (a closed curve passes through several points of one branch)."""
    scale = np.array([abs(w[1] - w[0]) for w in window], dtype=float)
    for curve in curves:
        if (curve.type, curve.n) != (sp.type, sp.n) or not len(curve.values):
            continue
        point = np.array([sp.value, sp.parameters[curve.second]]) / scale
        values = curve.values / scale
        i = int(np.argmin(np.linalg.norm(values - point, axis=1)))
        near = [j for j in (i - 1, i + 1) if 0 <= j < len(values)]
        reach = max((np.linalg.norm(values[j] - values[i]) for j in near), default=0.0)
        state_reach = max(
            (np.linalg.norm(curve.states[j] - curve.states[i]) for j in near), default=0.0
        )
        if (
            np.linalg.norm(values[i] - point) <= reach + 1e-9
            and np.linalg.norm(curve.states[i] - np.asarray(sp.state)) <= state_reach + 1e-6
        ):
            return True
    return False


def missing(result: ContinuationResult, parameter, span, switch, curve_types) -> list[str]:
    """One line for each thing asked for and not found, saying why."""
    found = [sp for _, sp in result.special_points()]
    over = f"{parameter} {span[0]:g} → {span[1]:g}"
    start = f"the {result.start.label} cycle's branch over {over}"
    lines = []
    if switch and not any(sp.type == "PD" for sp in found):
        lines.append(f"no switch: no PD point on {start} (--cycle N starts another cycle)")
    for branch in result.root.walk():
        lines.extend(f"no switch: {failure}" for failure in branch.switch_failures)
    for kind in curve_types:
        if not any(sp.type == kind for sp in found):
            lines.append(
                f"no {kind} curve: no {kind} point on the branches ({start}); "
                "--cycle N starts another cycle"
            )
    lines.extend(f"no curve: {failure}" for failure in result.curve_failures)
    return lines


def describe_continuation(result: ContinuationResult) -> str:
    """A few lines: the start cycle and how it was chosen, every branch with its end, every
    special point, every curve; what was asked for and not found is ``result.missing``."""
    start = result.start
    state = "stable" if start.stable else "unstable"
    lines = [
        f"start: {start.label} cycle ({state}) at "
        + ", ".join(f"{k}={v:g}" for k, v in start.parameters.items())
        + f"; {result.chosen}"
    ]
    for branch in result.root.walk():
        where = (
            ""
            if branch.origin is None
            else (
                f", switched at the PD point {branch.origin.parameter}={branch.origin.value:.10g}"
            )
        )
        lines.append(
            f"branch of period {branch.n}: {len(branch.values)} points{where}; {branch.end}"
        )
        for sp in branch.special:
            mult = ", ".join(f"{m.real:+.6f}{m.imag:+.6f}j" for m in sp.multipliers)
            sides = " → ".join(
                f"{lab} {'stable' if st else 'unstable'}"
                for lab, st in zip(sp.labels, sp.stable, strict=True)
            )
            lines.append(
                f"  {sp.type:2s} at {sp.parameter}={sp.value:.10f} (±{sp.accuracy:.1e})"
                f"  {sides}  multipliers {mult}"
            )
    for curve in result.curves:
        lines.append(
            f"{curve.type} curve of {curve.n}-cycles in ({curve.first}, {curve.second}):"
            f" {len(curve.values)} points; {curve.end}"
        )
    lines.append(f"{result.shots} integrations of the section map, {result.seconds:.2f} s")
    return "\n".join(lines)


@dataclass
class LineStructure:
    """Every branch met along a line: the periodic attractors a simulation finds along it
    (the seeds), each continued across the window both ways with switching, and the
    branches found twice dropped.

    branches: the root branches (each with its switched children), those of a seed one
    after the other (down then up, or one where the branch is a closed loop); seeds: (ω,
    label, "path" or "census") of the cells the branches were started from; line: the
    simulated line.
    """

    branches: list[Branch]
    seeds: list[tuple[float, str, str]]
    line: object
    seconds: float = 0.0
    shots: int = 0

    def special_points(self):
        for root in self.branches:
            for branch in root.walk():
                for sp in branch.special:
                    yield branch, sp

    def to_dict(self) -> dict:
        return {
            "seeds": [{"omega": w, "label": lab, "source": src} for w, lab, src in self.seeds],
            "branches": [root.to_dict() for root in self.branches],
            "special": [{"branch_period": b.n, **sp.to_dict()} for b, sp in self.special_points()],
            "seconds": self.seconds,
            "shots": self.shots,
        }


def line_structure(
    window: tuple[float, float],
    points: int,
    fixed: dict,
    *,
    switch: int = 3,
    census: int = 0,
    census_points: int = 9,
    max_period: int = 32,
    model: dict | None = None,
    settings: BranchSettings | None = None,
    section_map: SectionMap | None = None,
) -> LineStructure:
    """The branch structure along ω over ``window`` at the parameters ``fixed``.

    The line is simulated from the window's upper end down (``campar line``, ``points``
    cells); from the middle cell of every run of one periodic label a cycle is solved for
    and continued both ways across the window, switching at PD points ``switch`` deep
    (onto cycles of at most ``max_period`` revolutions).
    With ``census`` > 0, the attractors that many starts reach (``find_attractors``) at
    ``census_points`` speeds spread over the window seed branches too: the attractors
    the line's path does not visit. A seed whose cycle lies on a branch already computed
    (its state within 1e-6 of a branch point at the same ω, up to a cyclic shift) starts
    none.
    """
    from .line import compute_line, line_spec

    began = time.perf_counter()
    model = dict(model or {})
    smap = section_map or SectionMap(model)
    shots0 = smap.shots
    others = {k: v for k, v in fixed.items() if k != "omega"}
    line = compute_line(line_spec(window, points, **model, **others), transitions=False)
    runs, start = [], 0
    labels = list(line.labels)
    for i in range(1, len(labels) + 1):
        if i == len(labels) or labels[i] != labels[start]:
            if line.kind[start] == 0:
                runs.append((start, i))
            start = i
    candidates = []  # (ω, n, label, state, section points, source)
    for a, b in runs:
        k = (a + b) // 2
        n = int(line.n[k])
        omega = float(line.omega[k])
        candidates.append((omega, n, labels[k], line.state[k], line.sections[k, :n], "path"))
    if census:
        from .attractors import find_attractors

        for omega in np.linspace(max(window), min(window), census_points + 2)[1:-1]:
            found = find_attractors(float(omega), count=census, **model, **others)
            for a in found.attractors:
                if a.kind == "periodic":
                    r = a.result
                    candidates.append(
                        (
                            float(omega),
                            r.n,
                            r.label,
                            np.array(r.state),
                            np.asarray(r.sections)[: r.n],
                            "census",
                        )
                    )
    settings = settings or BranchSettings()
    roots, seeds, switched = [], [], []
    for omega, n, label, state, points, source in candidates:
        if on_a_branch(roots, omega, points):
            continue
        try:
            orbit = find_cycle(n, state, section_map=smap, omega=omega, **others)
        except ContinuationError:
            continue
        if on_a_branch(roots, omega, orbit.sections):
            continue
        seeds.append((omega, label, source))
        for direction in (-1.0, 1.0):
            root = continue_with_switching(
                orbit,
                "omega",
                window,
                switch,
                direction=direction,
                section_map=smap,
                settings=settings,
                switched=switched,
                max_period=max_period,
            )
            roots.append(root)
            if root.closed:  # a loop: the other direction goes round it again
                break
    return LineStructure(roots, seeds, line, time.perf_counter() - began, smap.shots - shots0)


def on_a_branch(roots: list[Branch], omega: float, points, tol: float = 1e-4) -> bool:
    """True when the cycle with section ``points`` at ω lies on a computed branch: between
    two consecutive branch points that bracket ω, the branch's cycle (interpolated
    linearly) within ``tol`` plus the two points' own distance of it, up to a cyclic
    shift (a branch's steps are short against the distance between distinct cycles)."""
    n = len(points)
    points = np.asarray(points)
    for root in roots:
        for branch in root.walk():
            if branch.n != n:
                continue
            v = branch.values
            for i in np.nonzero((v[:-1] - omega) * (v[1:] - omega) <= 0.0)[0]:
                w = 0.0 if v[i + 1] == v[i] else (omega - v[i]) / (v[i + 1] - v[i])
                cycle = (1 - w) * branch.sections[i] + w * branch.sections[i + 1]
                reach = tol + np.abs(branch.sections[i + 1] - branch.sections[i]).max()
                for shift in range(n):
                    if np.abs(np.roll(cycle, shift, axis=0) - points).max() < reach:
                        return True
    return False
