"""The model's sections as a job file writes them: the force law's options, the cam and the
contact (``model:``), the start (``initial:``), the integrator, the transient and the
classification. Every field, default and bound is stated here once; ``campar.model.Model``
gathers them with the parameters, and a job (``campar.sweep.job``) holds them as its
sections of the same names.
"""

import math
import typing
from typing import Annotated, Literal

from pydantic import Field, field_validator, model_validator

from ..errors import JobError
from .laws import CamSettings, ContactSettings
from .settings import MAX_COUNT, MAX_PERIOD, MAX_START, MAX_STEPS, Settings

PARAMETERS = ("omega", "f0", "mu_kn", "mu_cn", "zeta")
# The paper's base values (docs/model.md, sweeps) for parameters a job does not sweep or
# fix. Points, lines, the CLI, the benchmarks and the paper's set-ups take them from here.
PAPER_VALUES = {"f0": 0.5, "mu_kn": 0.8, "mu_cn": 0.8, "zeta": 0.2}


def with_paper_values(parameters: dict[str, float]) -> dict[str, float]:
    """f0, mu_kn, mu_cn, zeta (PAPER_VALUES order): those given, the paper's base values for
    the rest. JobError for a name that is none of them."""
    unknown = [name for name in parameters if name not in PAPER_VALUES]
    if unknown:
        raise JobError(
            f"unknown parameter {unknown[0]!r}; the model's parameters besides omega: "
            f"{', '.join(PAPER_VALUES)}"
        )
    return {name: parameters.get(name, value) for name, value in PAPER_VALUES.items()}


class ModelSettings(Settings):
    tensile: Literal["clamp", "allow"] = "clamp"
    """clamp: Pn = max(0, …), contact cannot pull (default); allow: the paper's literal formula."""
    duty_cycle: Literal["separation", "force"] = "separation"
    """separation: DC is the time with ε < 0 (default); force: the time with Pn = 0, the
    paper's other word for detachment (under the clamp it adds the time the follower is
    ahead of the cam without force; under allow the two are the same)."""
    cam_velocity: Literal["chain", "literal"] = "chain"
    """chain: the force's ε' uses ẏc = ω dyc/dθ, the chain rule (default); literal: ẏc =
    dyc/dθ, the paper's eq. 6 as printed (without the factor ω)."""
    cam: CamSettings = CamSettings()
    """The cam's motion laws and phase angles, or a table (docs/design.md)."""
    contact: ContactSettings = ContactSettings()
    """The contact force law (docs/design.md)."""

    @property
    def law_bits(self) -> int:
        """The kernel's LAW_* bits of these settings (campar.core.model.law_flags)."""
        from ..core.model import law_flags  # here: numba only for those who compute

        return law_flags(self.tensile, self.duty_cycle, self.cam_velocity)

    @property
    def law(self):
        """The kernel's ``law`` (campar.core.model.Law) of these settings: what make_params,
        run_chain and trace_orbit take (``laws.kernel_law``)."""
        from .laws import kernel_law  # here: numba only for those who compute

        return kernel_law(self)


# Model options whose default leaves a job's hash as it was before the option existed,
# so stores computed then stay valid (``job_digest``).
MODEL_OPTION_DEFAULTS = {
    "duty_cycle": "separation",
    "cam_velocity": "chain",
    "cam": CamSettings().model_dump(mode="json"),
    "contact": ContactSettings().model_dump(mode="json"),
}


class InitialState(Settings):
    y: float = 0.0
    v: float = 0.0

    @field_validator("y", "v")
    @classmethod
    def finite(cls, value: float) -> float:
        if not math.isfinite(value):
            raise ValueError("must be a finite number")
        if abs(value) > MAX_START:  # as a basin's starts: far outside every attractor
            raise ValueError(f"must be in [-{MAX_START:g}, {MAX_START:g}]")
        return value


class IntegratorSettings(Settings):
    method: Literal["dp54", "dop853", "rk4"] = "dop853"
    """dop853: Dormand–Prince 8(5,3), the default; dp54: Dormand–Prince 5(4) (use rtol
    1e-8 with it); rk4: fixed-step RK4, the paper's method."""
    rtol: Annotated[float, Field(gt=1e-15, lt=1.0)] = 1e-7
    atol: Annotated[float, Field(gt=0.0, lt=1.0)] = 1e-10
    rk4_steps: Annotated[int, Field(ge=6, le=10_000_000)] = 600
    """RK4 steps per revolution (a multiple of 6 lands on every cam phase boundary)."""
    event_tol: Annotated[float, Field(gt=0.0, lt=1e-3)] = 1e-12
    """Event times are located to event_tol × max(1, revolution period)."""
    max_steps: Annotated[int, Field(ge=1000, le=MAX_STEPS)] = 5_000_000
    """Steps per cell before the cell fails with 'step budget'."""


class TransientSettings(Settings):
    mode: Literal["converged", "fixed"] = "converged"
    """converged: stop once the section has converged to a cycle; fixed: the paper's recipe."""
    max_revolutions: Annotated[int, Field(ge=1, le=1_000_000)] = 500
    """converged: the revolution budget; fixed: revolutions discarded before the read window."""
    newton: bool = True
    """Shorten the transient with capped Newton jumps to the estimated cycle (converged only)."""
    jump_cap: Annotated[float, Field(gt=0.0)] = 0.02
    jump_residual: Annotated[float, Field(gt=0.0)] = 1e-3
    """Newton jumps are tried only where |x_k − x_{k−n}| is below this."""
    max_jumps: Annotated[int, Field(ge=0, le=MAX_COUNT)] = 20
    jump_agree: Annotated[float, Field(ge=0.0, lt=1.0)] = 0.1
    """Also jump (up to 0.2) where the estimate agrees with the one n revolutions
    earlier to this fraction of its distance, whatever the residual (0: off)."""
    conv_tol: Annotated[float, Field(gt=0.0, lt=1e-2)] = 1e-8
    """Distance to the cycle (Newton estimate) at which a cell has converged."""
    window_tol: Annotated[float, Field(gt=0.0, lt=1e-1)] = 1e-6
    """… and the distance of the read window's first point from it."""
    extrapolate: Annotated[int, Field(ge=0, le=3)] = 3
    """Warm start: 0 the previous cell's state; 1 linear, 2 quadratic, 3 cubic (the highest
    order) extrapolation through the previous cells' cycle points, where they are cycles of
    one period on a smooth branch (each finite difference no larger than the one below)."""
    chaos_after: Annotated[int, Field(ge=0, le=MAX_COUNT)] = 96
    """From this revolution on, a surely chaotic motion ends the transient (0: never)."""
    chaos_lyapunov: Annotated[float, Field(gt=0.0)] = 0.1
    """Lyapunov exponent per revolution that counts as clearly chaotic."""
    chaos_confidence: Annotated[float, Field(ge=0.5, lt=1.0)] = 0.9
    """A chaos verdict needs the exponent (since the last restart, at most a read window,
    at least 16 revolutions after the first two) above chaos_lyapunov and its lower
    bound at this one-sided confidence (Student's t on 4-revolution batch means) above
    classify.lyap_tol, …"""
    chaos_clear: Annotated[int, Field(ge=1, le=MAX_COUNT)] = 64
    """… and no Newton jump, nor a stable cycle in sight, for this many revolutions …"""
    chaos_sight: Annotated[float, Field(ge=0.0, le=1.0)] = 0.0
    """… in sight: the motion within this distance of repeating with a period ≤ n_max,
    the Jacobian over that period stable, its Newton estimate as close (0: not looked
    for)."""
    quasiperiodic_after: Annotated[int, Field(ge=0, le=MAX_COUNT)] = 0
    """From this revolution on, a quasi-periodic motion (|Lyapunov exponent| ≤ lyap_tol)
    ends the transient (0: never)."""


# Transient settings whose default leaves a job's hash as it was before the setting
# existed (``job_digest``); what the kernel computes with them is told apart by the store's
# ``versions.kernel``.
TRANSIENT_OPTION_DEFAULTS = {
    name: TransientSettings.model_fields[name].default
    for name in ("chaos_confidence", "chaos_clear", "chaos_sight")
}


class ClassifySettings(Settings):
    n_max: Annotated[int, Field(ge=1, le=MAX_PERIOD)] = 32
    chatter_p: Annotated[int, Field(ge=1, le=MAX_COUNT)] = 7
    window_revolutions: Annotated[int, Field(ge=1, le=100_000)] = 64
    """Read window: fixed transient, and non-periodic verdicts (Lyapunov exponent)."""
    period_tol: Annotated[float, Field(gt=0.0, lt=1.0)] = 1e-6
    """Section points closer than this (∞-norm) count as one point of σn."""
    lyap_tol: Annotated[float, Field(gt=0.0)] = 0.01
    """|largest Lyapunov exponent per revolution| below this: quasi-periodic; above: chaos."""
    sections: Annotated[int, Field(ge=1, le=100_000)] | None = None
    """σn points stored per cell (default n_max)."""

    @model_validator(mode="after")
    def window_at_least_two_revolutions(self):
        if self.window_revolutions < 2:
            raise ValueError("window_revolutions must be ≥ 2")
        return self


# Every default of the model's sections: code that builds models by keyword (points,
# lines, the CLI, benchmarks) reads its defaults here, e.g. DEFAULT_INTEGRATOR.rtol, so
# each default is the field default above and nowhere else.
DEFAULT_MODEL = ModelSettings()
DEFAULT_INITIAL = InitialState()
DEFAULT_INTEGRATOR = IntegratorSettings()
DEFAULT_TRANSIENT = TransientSettings()
DEFAULT_CLASSIFY = ClassifySettings()


def field_choices(settings: type[Settings], name: str) -> tuple[str, ...]:
    """The values a Literal field allows: ``field_choices(ModelSettings, "tensile")`` is
    ("clamp", "allow"); the CLI offers these as choices."""
    return typing.get_args(settings.model_fields[name].annotation)
