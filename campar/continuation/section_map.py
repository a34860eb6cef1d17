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
from ..model.compute import cell_settings, model_law, output_bits, solver_options
from ..model.sections import PAPER_VALUES
from ..model.settings import check_parameter

# The model's parameters in the order the compiled core takes them (model.make_params).
PARAMETER_ORDER = ("omega", "zeta", "f0", "mu_kn", "mu_cn")


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

    def __init__(self, model=None, precision: Precision | None = None):
        if isinstance(model, Model):
            model = model.model.model_dump(mode="json")
        self.model = model_settings(**(model or {}))
        self.precision = precision or Precision()
        pr = self.precision
        integrator = {"method": pr.method, "rtol": pr.rtol, "atol": pr.atol}
        # validates the options and the integrator settings (ω: any value in range)
        cell = Model.build({"omega": 1.0, "model": self.model, "integrator": integrator})
        self.law = model_law(cell)
        solver = solver_options(cell)
        settings = cell_settings(cell, output_bits(("dc", "eps", "pn")))
        compile_shooter(self.law, solver, settings)
        self._shooter = Shooter(self.law, solver, settings)

    def with_precision(self, **changes) -> "SectionMap":
        return SectionMap(self.model, replace(self.precision, **changes))

    @property
    def shots(self) -> int:
        """Integrations of n revolutions so far (for the benchmarks)."""
        return self._shooter.shots

    def shoot(self, x, par: np.ndarray, n: int, jacobian: bool = True) -> Shot:
        """Integrate n revolutions from x at parameters ``par`` (PARAMETER_ORDER)."""
        start = np.array(x, dtype=np.float64)
        status, result, jac, points = self._shooter(par, start, n, jacobian)
        if status != 0:
            raise ContinuationError(
                f"integration failed at {describe(par)}: {status_message(status)}"
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
        """∂Pⁿ/∂λ at x for parameter ``index`` of PARAMETER_ORDER (central differences)."""
        h = self.precision.fd_step * max(1.0, abs(par[index]))
        up = par.copy()
        down = par.copy()
        up[index] += h
        down[index] -= h
        forward = self.shoot(x, up, n, jacobian=False).image
        backward = self.shoot(x, down, n, jacobian=False).image
        return (forward - backward) / (2.0 * h)


def describe(par) -> str:
    return ", ".join(
        f"{name}={value:.10g}" for name, value in zip(PARAMETER_ORDER, par, strict=True)
    )
