"""One cell from Python: ``simulate_point`` and its result, with an optional orbit trace.

This is the API behind ``campar point``; the CLI only parses and prints.
"""

import math
from dataclasses import dataclass, field

import numpy as np

from ..core import model as core_model
from ..core.codes import KIND_NAMES, Flag, Kind, cell_label, status_message
from ..core.revolution import make_trace
from ..core.tracer import trace_orbit
from ..model import Model
from ..model.compute import cell_settings, model_law, output_bits, run_cells, solver_options

# Event codes of a trace: 2·(contact mode before) + (event index), see core.revolution.Trace.
EVENT_NAMES = {0: "impact", 2: "detachment", 3: "force zero", 4: "detachment", 5: "force resumes"}
SAMPLES_PER_STEP = 12  # DOP853 steps are long; the report integrates div f over the samples
MAX_TRACE_REVOLUTIONS = 64
POINT_OUTPUTS = ("label", "dc", "eps", "pn", "sections")

# The cam phases of one revolution as the model defines them: (name, start θ, end θ).
# Handed to the plots on every OrbitTrace, which draw them without importing the model.
_PHASE_NAMES = {
    core_model.RISE: "rise",
    core_model.FAR_DWELL: "far dwell",
    core_model.FALL: "fall",
    core_model.NEAR_DWELL: "near dwell",
}
CAM_PHASES = tuple(
    (_PHASE_NAMES[i], float(core_model.PHASE_BOUNDS[i]), float(core_model.PHASE_BOUNDS[i + 1]))
    for i in range(core_model.N_PHASES)
)


@dataclass(frozen=True)
class OrbitTrace:
    """The steady orbit sampled densely; times count from the start of the trace."""

    t: np.ndarray
    y: np.ndarray
    v: np.ndarray
    yc: np.ndarray
    eps: np.ndarray
    pn: np.ndarray
    contact: np.ndarray  # contact mode (0 separated, 1 pushing, 2 in contact without force)
    events: np.ndarray  # (M, 4): t, y, y', code
    period: float  # one cam revolution, 2π/ω
    cam_phases: tuple[tuple[str, float, float], ...]  # (name, start θ, end θ), CAM_PHASES
    per_step: int = SAMPLES_PER_STEP  # samples a step, its end included

    def by_step(self, values: np.ndarray) -> np.ndarray:
        """One of the sampled arrays (``eps``, ``contact``, …) as (steps, per_step): a row
        a step's samples, its end last. The sample each revolution opens with (the last
        one's end again, or the start) is left out."""
        keep = np.ones(self.t.size, bool)
        keep[0] = False
        keep[1:] = self.t[1:] != self.t[:-1]
        return values[keep].reshape(-1, self.per_step)

    def events_named(self, name: str) -> np.ndarray:
        """Rows (t, y, y') of the events called ``name`` ("impact", "detachment", …)."""
        codes = [code for code, label in EVENT_NAMES.items() if label == name]
        return self.events[np.isin(self.events[:, 3], codes), :3]


@dataclass(frozen=True)
class PointResult:
    """One cell's steady motion, as :func:`simulate_point` classifies it (frozen).

    Parameters
    ----------
    parameters : dict
        ω, f0, μkn, μcn, ζ of the cell, its force law ``tensile`` and the law's options
        ``duty_cycle`` and ``cam_velocity``.
    label : str
        ``n-p`` (period n revolutions, p detachments in them), ``n-p~`` for chattering
        impacts, ``QP``, ``chaos``, or the reason it has none.
    n, p : int
        Period in revolutions (0 if not periodic) and detachments per period (of a
        non-periodic motion: in the read window).
    kind : str
        ``periodic``, ``quasi-periodic``, ``chaotic``, ``unconverged`` or ``failed``.
    status : str
        ``ok``, or why the integration failed (step budget, step size underflow, …).
    flags : tuple of str
        Notes on the cell: ``newton`` (Newton jumps shortened its transient), ``slow``,
        ``grazing``, … (``campar.core.codes.Flag``).
    dc : float
        Duty cycle: the fraction of a period the follower is detached (ε < 0).
    eps_min, eps_max : float
        Extremes of the penetration ε over the steady motion (ε > 0: in contact).
    pn_max : float
        Largest contact force Pn (dimensionless).
    revolutions, steps : int
        Cam revolutions integrated and accepted integrator steps.
    state : tuple of float
        Final state (y, y') at θ = 0, a point of the attractor: a start that lands on it.
    sections : numpy.ndarray
        σn points (y, y') of the cycle, shape (n, 2); of a non-periodic motion a cloud of
        up to ``sections`` points.
    multipliers : tuple of complex or None
        Floquet multipliers of the cycle, when asked for (``multipliers=True``).
    lyapunov : float or None
        Largest Lyapunov exponent per revolution, when asked for (``lyapunov=True``).
    trace : OrbitTrace or None
        The steady orbit sampled densely, when asked for (``trace=True``).
    model : Model or None
        The cell's whole model (``campar.model.Model``): what its numbers depend on.

    Examples
    --------
    >>> import campar
    >>> cell = campar.simulate_point(3.0)
    >>> cell.label, cell.kind, cell.n, cell.p
    ('1-1', 'periodic', 1, 1)
    >>> cell.to_dict()["dc"] == cell.dc
    True
    """

    parameters: dict
    label: str
    n: int
    p: int
    kind: str
    status: str
    flags: tuple[str, ...]
    dc: float
    eps_min: float
    eps_max: float
    pn_max: float
    revolutions: int
    steps: int
    state: tuple[float, float]
    sections: np.ndarray  # (m, 2): σn points (y, y')
    multipliers: tuple[complex, ...] | None = None
    lyapunov: float | None = None
    trace: OrbitTrace | None = field(default=None, repr=False)
    model: Model | None = field(default=None, repr=False, compare=False)

    def to_dict(self) -> dict:
        """JSON-ready summary (multipliers as [re, im] pairs; NaN as None)."""

        def num(x):
            return None if x is None or not math.isfinite(x) else float(x)

        data = {
            "label": self.label,
            "n": self.n,
            "p": self.p,
            "kind": self.kind,
            "status": self.status,
            "flags": list(self.flags),
            "dc": num(self.dc),
            "eps_min": num(self.eps_min),
            "eps_max": num(self.eps_max),
            "pn_max": num(self.pn_max),
            "revolutions": self.revolutions,
            "steps": self.steps,
            "state": [num(self.state[0]), num(self.state[1])],
            "sections": [[num(a), num(b)] for a, b in self.sections],
            "parameters": self.parameters,
        }
        if self.model is not None:
            data["model"] = self.model.to_dict()
        if self.multipliers is not None:
            data["multipliers"] = [[num(m.real), num(m.imag)] for m in self.multipliers]
        if self.lyapunov is not None:
            data["lyapunov"] = num(self.lyapunov)
        return data


def point_parameters(model: Model) -> dict:
    """ω, f0, μkn, μcn, ζ of a cell (PARAMETERS order), its force law and the law's
    options (duty_cycle, cam_velocity)."""
    options = model.model
    return {
        **model.parameters,
        "tensile": options.tensile,
        "duty_cycle": options.duty_cycle,
        "cam_velocity": options.cam_velocity,
    }


def simulate_point(
    model=None,
    *,
    state=None,
    multipliers: bool = False,
    lyapunov: bool = False,
    trace: bool = False,
    **fields,
) -> PointResult:
    """Simulate one cell from a start at θ = 0 and classify its steady motion.

    Parameters
    ----------
    model : Model, mapping or float, optional
        The cell's model (``campar.model.Model``), a mapping of a job's keys, or ω; the
        ``fields`` change it.
    state : (float, float), optional
        The start (y, y') at θ = 0; default the model's ``initial`` (rest).
    multipliers : bool
        Also compute the cycle's Floquet multipliers.
    lyapunov : bool
        Also compute the largest Lyapunov exponent per revolution.
    trace : bool
        Integrate the steady orbit once more from the final state (its period, or up to
        64 revolutions when not periodic) and record it densely (``PointResult.trace``).
    **fields
        Any key of the model by its name (``Model.build``): the parameters ``omega``,
        ``f0``, ``mu_kn``, ``mu_cn``, ``zeta`` (the paper's base values but ω); the force
        law's options ``tensile``, ``duty_cycle``, ``cam_velocity``; the cam's ``rise``,
        ``fall``, ``phi1`` … ``phi4``, ``table``; the contact's ``law``, ``n``,
        ``restitution``; the start ``y0``, ``v0``; the integrator's ``method``, ``rtol``,
        ``atol``, …; the transient's ``transient`` (its mode), ``revolutions``,
        ``chaos_after``, …; the classification's ``n_max``, ``sections``, … (jobs/README.md
        gives every key and its default; ``campar point --help`` its flag).

    Returns
    -------
    PointResult
        The cell's label, kind, duty cycle, ε extremes, Pn max, final state, σn points,
        its model and what was asked for.

    Raises
    ------
    campar.errors.JobError
        A key unknown or a value out of range.

    Examples
    --------
    >>> import campar
    >>> cell = campar.simulate_point(3.0)
    >>> cell.label, round(cell.dc, 4)
    ('1-1', 0.4802)
    >>> campar.simulate_point(3.15, mu_kn=0.91, multipliers=True).label
    '2-2'
    >>> campar.simulate_point(omega=2.0, rise="cycloidal", fall="cycloidal").label
    '1-1'
    >>> campar.simulate_point(3.0, mu_kn=2.0)
    Traceback (most recent call last):
    ...
    campar.errors.JobError: mu_kn must be in (0, 1), got 2.0
    """
    model = Model.build(model, **fields)
    start = model.start if state is None else checked_state(state)
    outputs = [*POINT_OUTPUTS]
    if multipliers:
        outputs.append("multipliers")
    if lyapunov:
        outputs.append("lyapunov")
    law = model_law(model)
    if trace:
        from ..model.compute import compile_cells

        compile_cells(model, law, output_bits(outputs), model.n_sections, trace=True)
    out = run_cells(model, start=start, outputs=outputs, law=law)
    cell = {name: values[0] for name, values in out._asdict().items() if len(values)}
    result = point_result(model, cell)
    if trace and result.kind != KIND_NAMES[Kind.FAILED]:
        n_revs = result.n or min(model.classify.window_revolutions, MAX_TRACE_REVOLUTIONS)
        orbit = trace_steady(model, result.state, n_revs, result.steps, law)
        if orbit is not None:
            result = PointResult(**{**result.__dict__, "trace": orbit})
    return result


def checked_state(state) -> tuple[float, float]:
    """A start (y, y') as two finite floats within ±MAX_START; JobError otherwise."""
    from ..errors import JobError
    from ..model.settings import MAX_START

    try:
        y, v = (float(x) for x in state)
    except (TypeError, ValueError):
        raise JobError(f"state: a start is two numbers (y, y'), got {state!r}") from None
    if not all(math.isfinite(x) and abs(x) <= MAX_START for x in (y, v)):
        raise JobError(f"state: a start is two finite numbers within ±{MAX_START:g}, got {state!r}")
    return (y, v)


def point_result(model: Model, cell: dict) -> PointResult:
    """The PointResult of one cell of ``model``: ``cell`` maps each output array's name
    (``CellOutputs``, a map's arrays) to that cell's value (multipliers and Lyapunov
    exponent where they were computed)."""
    kind = Kind(int(cell["kind"]))
    n = int(cell["n"])
    sections = cell.get("sections", np.empty((0, 2)))[: n if n else model.n_sections]
    sections = sections[~np.isnan(sections[:, 0])]
    return PointResult(
        parameters=point_parameters(model),
        label=cell_label(kind, n, int(cell["p"]), model.classify.chatter_p),
        n=n,
        p=int(cell["p"]),
        kind=KIND_NAMES[kind],
        status=status_message(int(cell["status"])),
        flags=tuple(f.name.lower() for f in Flag if f and int(cell["flags"]) & f),
        dc=float(cell["dc"]),
        eps_min=float(cell["eps_min"]),
        eps_max=float(cell["eps_max"]),
        pn_max=float(cell["pn_max"]),
        revolutions=int(cell["revolutions"]),
        steps=int(cell["steps"]),
        state=(float(cell["state"][0]), float(cell["state"][1])),
        sections=sections,
        multipliers=(
            tuple(complex(re, im) for re, im in cell["multipliers"])
            if "multipliers" in cell
            else None
        ),
        lyapunov=float(cell["lyapunov"]) if "lyapunov" in cell else None,
        model=model,
    )


def trace_steady(
    model: Model,
    state,
    revolutions: int,
    steps: int = 0,
    law=None,
    per_step: int = SAMPLES_PER_STEP,
) -> OrbitTrace | None:
    """``revolutions`` revolutions of ``model`` from ``state`` (y, y') at θ = 0, sampled
    densely with the model's integrator settings; ``steps`` the cell's step count (sizes
    the buffer); ``law`` the kernel's Law (default the model's); ``per_step`` samples a
    step, its end included (each revolution opens with a sample of its start). None when
    the integration fails."""
    max_samples = per_step * max(steps, 1000) * 4 + 16
    rec = make_trace(max_samples, 64 * revolutions + 64, per_step)
    status, _, _ = trace_orbit(
        model.omega,
        model.zeta,
        model.f0,
        model.mu_kn,
        model.mu_cn,
        model_law(model) if law is None else law,
        np.array(state, dtype=float),
        solver_options(model),
        cell_settings(model, output_bits(POINT_OUTPUTS)),
        revolutions,
        rec,
    )
    if status != 0:
        return None
    samples = rec.samples[: rec.count[0]]
    return OrbitTrace(
        t=samples[:, 0],
        y=samples[:, 1],
        v=samples[:, 2],
        yc=samples[:, 3],
        eps=samples[:, 4],
        pn=samples[:, 5],
        contact=samples[:, 6].astype(np.int8),
        events=rec.events[: rec.count[1]].copy(),
        period=2 * math.pi / model.omega,
        cam_phases=cam_phases(model),
        per_step=per_step,
    )


def cam_phases(model: Model) -> tuple[tuple[str, float, float], ...]:
    """The cam phases of one revolution of the model's cam: (name, start θ, end θ)."""
    from ..model.cam_table import phase_bounds

    bounds = phase_bounds(model.model.cam.angles)
    names = [_PHASE_NAMES[i] for i in range(core_model.N_PHASES)]
    return tuple((name, bounds[i], bounds[i + 1]) for i, name in enumerate(names))
