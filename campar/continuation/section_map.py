"""Pⁿ with its derivatives, for any parameter of the model: what the continuation solves.

``SectionMap`` wraps the compiled shooting entry (campar.core.shooting): one call gives
the image Pⁿ(x; λ), the exact Jacobian DPⁿ (variational equations) and the orbit's contact
pattern. The parameter derivative ∂Pⁿ/∂λ is a central difference quotient with the step
``Precision.fd_step`` relative to max(1, |λ|): with the integrator at rtol 1e-12 its
rounding part (~rtol/h ≈ 1e-7) and its truncation part (~h² ≈ 1e-12) both lie far below
what Newton's method needs — the residual Pⁿ(x) − x is computed exactly and the column
only enters the Jacobian, so it costs convergence speed, never accuracy
(benchmarks/RESULTS.md, "Continuation").
"""

from dataclasses import dataclass, replace

import numpy as np
from pydantic import ValidationError

from ..core.codes import status_message
from ..core.shooting import (
    SHOT_DETACH,
    SHOT_EPS_MAX,
    SHOT_EPS_MIN,
    SHOT_PN_MAX,
    SHOT_STEPS,
    SHOT_T_FREE,
    SHOT_TOUCH,
    Shooter,
    compile_shooter,
)
from ..errors import ContinuationError, JobError
from ..model import Model
from ..model.compute import cell_settings, output_bits, solver_options
from ..model.laws import LAW_PARAMETERS, kernel_law
from ..model.sections import PAPER_VALUES
from ..model.settings import check_parameter

# The model's parameters in the order the compiled core takes them (model.make_params).
PARAMETER_ORDER = ("omega", "zeta", "f0", "mu_kn", "mu_cn")
# A law parameter continued: its laws' kernels kept at once (a branch's step and its two
# difference quotients each need one; older ones are rebuilt if a branch turns back).
MAX_SHOOTERS = 16
DEFAULT_RESTITUTION = 0.8  # the contact laws' own default (campar.model.laws.kernel_law)


@dataclass(frozen=True)
class Precision:
    """How accurately orbits are computed.

    rtol, atol, method: the integrator's (rtol 1e-12 makes the fixed points and
    multipliers accurate to ~1e-10); newton_tol: the residual ‖Pⁿ(x) − x‖∞ a fixed point
    must reach; max_newton: Newton iterations before a correction is refused; fd_step:
    the relative step of the parameter difference quotient.
    """

    rtol: float = 1e-12
    atol: float = 1e-14
    method: str = "dop853"
    newton_tol: float = 1e-10
    max_newton: int = 8
    fd_step: float = 1e-7


@dataclass(frozen=True)
class Shot:
    """One integration of n revolutions from ``start``."""

    start: np.ndarray  # (2,) (y, y') at θ = 0
    image: np.ndarray  # (2,) Pⁿ(start)
    jacobian: np.ndarray  # (2, 2) DPⁿ at start (NaN when not asked for)
    detachments: int
    touch: float  # ε at the extremum of ε nearest 0, signed (grazing where it is 0)
    eps_min: float
    eps_max: float
    pn_max: float
    time_free: float  # time separated in the n revolutions
    steps: int
    points: np.ndarray  # (n, 2): P¹(start), …, Pⁿ(start)

    @property
    def residual(self) -> np.ndarray:
        return self.image - self.start


def model_settings(tensile="clamp", duty_cycle="separation", cam_velocity="chain", **laws) -> dict:
    """The job model's options as a dict (validated when the SectionMap is built): the
    force law's options and, in ``laws``, the job's ``cam`` and ``contact`` sections."""
    return {"tensile": tensile, "duty_cycle": duty_cycle, "cam_velocity": cam_velocity, **laws}


def parameter_vector(parameters: dict) -> np.ndarray:
    """(ω, ζ, f0, μkn, μcn) from a dict (ω required; the paper's base values for the rest),
    each checked against its range (JobError)."""
    unknown = sorted(set(parameters) - set(PARAMETER_ORDER))
    if unknown:
        raise JobError(
            f"unknown parameter {unknown[0]!r}; the model's parameters: "
            f"{', '.join(PARAMETER_ORDER)}"
        )
    if "omega" not in parameters:
        raise JobError("omega is required")
    values = {**PAPER_VALUES, **parameters}
    vector = np.empty(len(PARAMETER_ORDER))
    for i, name in enumerate(PARAMETER_ORDER):
        try:
            vector[i] = check_parameter(name, float(values[name]))
        except ValueError as exc:
            raise JobError(str(exc)) from None
    return vector


def parameter_index(name: str) -> int:
    if name not in PARAMETER_ORDER:
        raise JobError(
            f"{name!r} is not a parameter of the model; one of {', '.join(PARAMETER_ORDER)}"
        )
    return PARAMETER_ORDER.index(name)


def in_range(name: str, value: float) -> bool:
    try:
        check_parameter(name, value)
    except ValueError:
        return False
    return True


class SectionMap:
    """Pⁿ(x; λ), DPⁿ and ∂Pⁿ/∂λ for one force law at one precision.

    ``model``: a Model (its ``model`` section: the force law's options, cam and contact),
    or that section as a mapping (``model_settings``); ``precision``: a Precision, whose
    integrator settings replace the model's.
    """

    def __init__(self, model=None, precision: Precision | None = None, law_parameter=None):
        if isinstance(model, Model):
            model = model.model.model_dump(mode="json")
        self.model = model_settings(**(model or {}))
        self.precision = precision or Precision()
        pr = self.precision
        integrator = {"method": pr.method, "rtol": pr.rtol, "atol": pr.atol}
        # validates the options and the integrator settings (ω: any value in range)
        self.cell = Model.build({"omega": 1.0, "model": self.model, "integrator": integrator})
        if law_parameter is not None and law_parameter not in LAW_PARAMETERS:
            raise JobError(
                f"{law_parameter!r} is not a law parameter; one of {', '.join(LAW_PARAMETERS)}"
            )
        self.law_parameter = law_parameter
        # the vector's names: the parameters, and the law parameter continued (if any)
        self.order = PARAMETER_ORDER + ((law_parameter,) if law_parameter else ())
        self.law = self._law(None)
        self._solver = solver_options(self.cell)
        self._settings = cell_settings(self.cell, output_bits(("dc", "eps", "pn")))
        compile_shooter(self.law, self._solver, self._settings)
        self._shooter = Shooter(self.law, self._solver, self._settings)
        self._shooters = {}  # a law parameter's value → the Shooter of that law
        self._retired = 0  # shots of shooters dropped from that cache

    def _law(self, value):
        """The kernel's Law at the law parameter's ``value`` (None: the model's own)."""
        if self.law_parameter is None or value is None:
            swept = (self.law_parameter,) if self.law_parameter else ()
            return kernel_law(self.cell.model, swept=swept)
        try:
            return kernel_law(
                self.cell.model, self.law_parameter, value, swept=(self.law_parameter,)
            )
        except (ValueError, ValidationError) as exc:
            raise ContinuationError(f"{self.law_parameter}={value:.10g}: {exc}") from None

    def _shooter_at(self, par) -> Shooter:
        if len(par) == len(PARAMETER_ORDER):
            return self._shooter
        value = float(par[-1])
        if value not in self._shooters:
            if len(self._shooters) >= MAX_SHOOTERS:  # a branch moves on: keep the newest
                oldest = next(iter(self._shooters))
                self._retired += self._shooters.pop(oldest).shots
            self._shooters[value] = Shooter(self._law(value), self._solver, self._settings)
        return self._shooters[value]

    def vector(self, parameters: dict) -> np.ndarray:
        """The parameter vector (``order``) of a dict: ``parameter_vector``'s, and the law
        parameter's value (default the model's) when one is continued."""
        par = parameter_vector({k: v for k, v in parameters.items() if k != self.law_parameter})
        if self.law_parameter is None:
            return par
        value = parameters.get(self.law_parameter)
        if value is None:
            value = self.cell.value(self.law_parameter)
        if value is None:  # a restitution left at its law's default
            value = DEFAULT_RESTITUTION
        return np.append(par, float(value))

    def index(self, name: str) -> int:
        """Where the parameter ``name`` lies in the vector (``order``)."""
        if name in self.order:
            return self.order.index(name)
        return parameter_index(name)

    def with_precision(self, **changes) -> "SectionMap":
        return SectionMap(self.model, replace(self.precision, **changes), self.law_parameter)

    @property
    def shots(self) -> int:
        """Integrations of n revolutions so far (for the benchmarks)."""
        others = sum(shooter.shots for shooter in self._shooters.values())
        return self._shooter.shots + others + self._retired

    def shoot(self, x, par: np.ndarray, n: int, jacobian: bool = True) -> Shot:
        """Integrate n revolutions from x at parameters ``par`` (``order``: PARAMETER_ORDER,
        and the law parameter's value when one is continued)."""
        start = np.array(x, dtype=np.float64)
        shooter = self._shooter_at(par)
        status, result, jac, points = shooter(par[: len(PARAMETER_ORDER)], start, n, jacobian)
        if status != 0:
            raise ContinuationError(
                f"integration failed at {describe(par, self.order)}: {status_message(status)}"
            )
        return Shot(
            start=start,
            image=result[:2].copy(),
            jacobian=jac.copy(),
            detachments=int(round(result[SHOT_DETACH])),
            touch=float(result[SHOT_TOUCH]),
            eps_min=float(result[SHOT_EPS_MIN]),
            eps_max=float(result[SHOT_EPS_MAX]),
            pn_max=float(result[SHOT_PN_MAX]),
            time_free=float(result[SHOT_T_FREE]),
            steps=int(result[SHOT_STEPS]),
            points=points,
        )

    def parameter_derivative(self, x, par: np.ndarray, n: int, index: int) -> np.ndarray:
        """∂Pⁿ/∂λ at x for parameter ``index`` of ``order`` (central differences)."""
        h = self.precision.fd_step * max(1.0, abs(par[index]))
        up = par.copy()
        down = par.copy()
        up[index] += h
        down[index] -= h
        forward = self.shoot(x, up, n, jacobian=False).image
        backward = self.shoot(x, down, n, jacobian=False).image
        return (forward - backward) / (2.0 * h)


def describe(par, order=PARAMETER_ORDER) -> str:
    return ", ".join(f"{name}={value:.10g}" for name, value in zip(order, par, strict=False))
