"""One cell from Python: ``simulate_point`` and its result, with an optional orbit trace.

This is the API behind ``campar point``; the CLI only parses and prints.
"""

import math
from dataclasses import dataclass, field

import numpy as np

from ..core import model
from ..core.codes import KIND_NAMES, Flag, Kind, cell_label, status_message
from ..core.revolution import make_trace
from ..core.tracer import trace_orbit
from ..errors import JobError
from ..sweep.job import (
    DEFAULT_CLASSIFY,
    DEFAULT_INITIAL,
    DEFAULT_INTEGRATOR,
    DEFAULT_MODEL,
    DEFAULT_TRANSIENT,
    PARAMETERS,
    Job,
    check_parameter,
    with_paper_values,
)
from ..sweep.plan import Tile
from ..sweep.tile import cell_settings, compile_kernel, run_tile, solver_options

# Event codes of a trace: 2·(contact mode before) + (event index), see core.revolution.Trace.
EVENT_NAMES = {0: "impact", 2: "detachment", 3: "force zero", 4: "detachment", 5: "force resumes"}
SAMPLES_PER_STEP = 12  # DOP853 steps are long; the report integrates div f over the samples
MAX_TRACE_REVOLUTIONS = 64
POINT_OUTPUTS = ("label", "dc", "eps", "pn", "sections")

# The cam phases of one revolution as the model defines them: (name, start θ, end θ).
# Handed to the plots on every OrbitTrace, which draw them without importing the model.
_PHASE_NAMES = {
    model.RISE: "rise",
    model.FAR_DWELL: "far dwell",
    model.FALL: "fall",
    model.NEAR_DWELL: "near dwell",
}
CAM_PHASES = tuple(
    (_PHASE_NAMES[i], float(model.PHASE_BOUNDS[i]), float(model.PHASE_BOUNDS[i + 1]))
    for i in range(model.N_PHASES)
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
        if self.multipliers is not None:
            data["multipliers"] = [[num(m.real), num(m.imag)] for m in self.multipliers]
        if self.lyapunov is not None:
            data["lyapunov"] = num(self.lyapunov)
        return data


def point_job(
    *,
    omega: float,
    tensile: str = DEFAULT_MODEL.tensile,
    duty_cycle: str = DEFAULT_MODEL.duty_cycle,
    cam_velocity: str = DEFAULT_MODEL.cam_velocity,
    y0: float = DEFAULT_INITIAL.y,
    v0: float = DEFAULT_INITIAL.v,
    transient: str = DEFAULT_TRANSIENT.mode,
    revolutions: int = DEFAULT_TRANSIENT.max_revolutions,
    chaos_after: int = DEFAULT_TRANSIENT.chaos_after,
    rtol: float = DEFAULT_INTEGRATOR.rtol,
    atol: float = DEFAULT_INTEGRATOR.atol,
    method: str = DEFAULT_INTEGRATOR.method,
    sections: int | None = DEFAULT_CLASSIFY.sections,
    outputs=POINT_OUTPUTS,
    **parameters: float,
) -> Job:
    """A one-cell job (validated like any job) from (y0, v0) at θ = 0.

    ``parameters``: f0, mu_kn, mu_cn, zeta; those not given take the paper's base values.
    Every setting defaults to the job model's (``campar.sweep.job``): the force law and
    its options (``duty_cycle``: separation or force; ``cam_velocity``: chain or literal), the
    transient (``revolutions`` is its budget when converged, its length when fixed;
    ``chaos_after`` the earliest chaotic verdict, 0: only at the budget), the integrator
    and the σn points kept of a non-periodic cell (``sections``, None: n_max).
    Raises JobError for a parameter unknown or out of range.
    """
    values = with_paper_values(parameters)
    for name, value in {"omega": omega, **values}.items():
        try:
            check_parameter(name, float(value))
        except ValueError as exc:
            raise JobError(str(exc)) from None
    f0 = values.pop("f0")  # swept (one value): a job sweeps ω and one more parameter
    data = {
        "name": "point",
        "sweep": {
            "omega": {"from": omega, "to": omega, "points": 1},
            "f0": {"from": f0, "to": f0, "points": 1},
        },
        "fixed": values,
        "model": {"tensile": tensile, "duty_cycle": duty_cycle, "cam_velocity": cam_velocity},
        "initial": {"y": y0, "v": v0},
        "integrator": {"method": method, "rtol": rtol, "atol": atol},
        "transient": {
            "mode": transient,
            "max_revolutions": revolutions,
            "chaos_after": chaos_after,
        },
        "classify": {"sections": sections},
        "outputs": list(outputs),
        "tiles": {"rows": 1},
    }
    return Job.from_dict(data, source="point")


def point_parameters(job: Job) -> dict:
    """The model parameters of a one-cell job (ω first, as PARAMETERS), its force law and the
    law's options (duty_cycle, cam_velocity)."""
    values = {"omega": float(job.omega[0]), job.second: float(job.second_values[0]), **job.fixed}
    model = job.model
    return {
        **{name: values[name] for name in PARAMETERS},
        "tensile": model.tensile,
        "duty_cycle": model.duty_cycle,
        "cam_velocity": model.cam_velocity,
    }


def simulate_point(
    omega: float,
    *,
    multipliers: bool = False,
    lyapunov: bool = False,
    trace: bool = False,
    **settings,
) -> PointResult:
    """Simulate one cell from (y0, v0) at θ = 0 and classify its steady motion.

    Parameters
    ----------
    omega : float
        Cam speed ω (dimensionless; θ = ωt).
    multipliers : bool
        Also compute the cycle's Floquet multipliers.
    lyapunov : bool
        Also compute the largest Lyapunov exponent per revolution.
    trace : bool
        Integrate the steady orbit once more from the final state (its period, or up to
        64 revolutions when not periodic) and record it densely (``PointResult.trace``).
    **settings
        The keywords of ``point_job``, each defaulting to the paper's base value or the
        job model's default (jobs/README.md):

        - ``f0``, ``mu_kn``, ``mu_cn``, ``zeta`` : float — preload, contact stiffness
          and damping ratios, damping (0.5, 0.8, 0.8, 0.2);
        - ``tensile`` : ``"clamp"`` or ``"allow"`` — the contact force law;
        - ``duty_cycle`` : ``"separation"`` or ``"force"``;
          ``cam_velocity`` : ``"chain"`` or ``"literal"`` — the paper's ambiguities;
        - ``y0``, ``v0`` : float — the start (y, y') at θ = 0 (0, 0);
        - ``transient`` : ``"converged"`` or ``"fixed"``; ``revolutions`` : int — its
          budget or length (500); ``chaos_after`` : int — the earliest chaotic verdict
          (0: only at the budget);
        - ``method`` : ``"dop853"``, ``"dp54"`` or ``"rk4"``; ``rtol``, ``atol`` : float;
        - ``sections`` : int or None — σn points kept of a non-periodic cell.

    Returns
    -------
    PointResult
        The cell's label, kind, duty cycle, ε extremes, Pn max, final state, σn points
        and what was asked for.

    Raises
    ------
    campar.errors.JobError
        A parameter unknown or out of range.

    Examples
    --------
    >>> import campar
    >>> cell = campar.simulate_point(3.0)
    >>> cell.label, round(cell.dc, 4)
    ('1-1', 0.4802)
    >>> campar.simulate_point(3.15, mu_kn=0.91, multipliers=True).label
    '2-2'
    >>> campar.simulate_point(3.0, mu_kn=2.0)
    Traceback (most recent call last):
    ...
    campar.errors.JobError: mu_kn must be in (0, 1), got 2.0
    """
    outputs = [*POINT_OUTPUTS]
    if multipliers:
        outputs.append("multipliers")
    if lyapunov:
        outputs.append("lyapunov")
    job = point_job(omega=omega, outputs=outputs, **settings)
    compile_kernel(job, trace=trace)  # on two cores if the cache is empty
    cell = {name: arr[0, 0] for name, arr in run_tile(job, Tile(0, 0, 1)).items()}
    result = point_result(job, cell)
    if trace and result.kind != KIND_NAMES[Kind.FAILED]:
        n_revs = result.n or min(job.classify.window_revolutions, MAX_TRACE_REVOLUTIONS)
        orbit = trace_steady(job, result.parameters, result.state, n_revs, result.steps)
        if orbit is not None:
            result = PointResult(**{**result.__dict__, "trace": orbit})
    return result


def point_result(job: Job, cell: dict) -> PointResult:
    """The PointResult of one cell of ``job``: ``cell`` maps each array name of run_tile
    to that cell's value (multipliers and Lyapunov exponent where the job computed them)."""
    kind = Kind(int(cell["kind"]))
    n = int(cell["n"])
    sections = cell["sections"][: n if n else job.n_sections]
    sections = sections[~np.isnan(sections[:, 0])]
    return PointResult(
        parameters=point_parameters(job),
        label=cell_label(kind, n, int(cell["p"]), job.classify.chatter_p),
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
    )


def trace_steady(
    job: Job, parameters: dict, state, revolutions: int, steps: int = 0
) -> OrbitTrace | None:
    """``revolutions`` revolutions from ``state`` (y, y') at θ = 0, sampled densely with the
    integrator settings of ``job``; ``parameters`` as ``point_parameters`` gives them and
    ``steps`` the cell's step count (sizes the buffer). None when the integration fails."""
    par = parameters
    max_samples = SAMPLES_PER_STEP * max(steps, 1000) * 4 + 16
    rec = make_trace(max_samples, 64 * revolutions + 64, SAMPLES_PER_STEP)
    status, _, _ = trace_orbit(
        par["omega"],
        par["zeta"],
        par["f0"],
        par["mu_kn"],
        par["mu_cn"],
        job.law(),
        np.array(state, dtype=float),
        solver_options(job),
        cell_settings(job),
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
        period=2 * math.pi / par["omega"],
        cam_phases=CAM_PHASES,
    )
