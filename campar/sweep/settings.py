"""The base of every job section: frozen pydantic settings that refuse unknown keys, and
YAML's true/false or text where a number belongs; the bounds of every integer and the
grid axis (campar.sweep.job, campar.sweep.laws)."""

import math
import typing
from typing import Annotated

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator


class Settings(BaseModel):
    # allow_inf_nan: no infinity or NaN in any number of a job (settings and axis ends alike)
    model_config = ConfigDict(
        extra="forbid", frozen=True, populate_by_name=True, allow_inf_nan=False
    )

    @field_validator("*", mode="before")
    @classmethod
    def booleans_are_not_numbers(cls, value, info):
        """true/false or text ("4") where a number belongs is a mistake (pydantic reads both)."""
        annotation = cls.model_fields[info.field_name].annotation
        values = value.values() if isinstance(value, dict) else [value]
        if any(isinstance(v, bool) for v in values) and wants_number(annotation):
            raise ValueError("must be a number, not true or false")
        if any(isinstance(v, str) for v in values) and wants_number(annotation, text=False):
            raise ValueError("must be a number, not text (write it without quotes)")
        return value


def wants_number(annotation, text: bool = True) -> bool:
    """A field typed int or float (inside Annotated, Optional or a dict's values); with
    ``text`` False, only one that takes no text either (``tiles.rows`` takes auto)."""
    if annotation in (int, float):
        return True
    args = typing.get_args(annotation)
    if typing.get_origin(annotation) is dict:
        return wants_number(args[1], text)
    if not text and str in args:
        return False
    return any(wants_number(a, text) for a in args if a is not bool)


# Integer bounds: far beyond any useful setting, and every product fits 64-bit integers.
MAX_POINTS = 100_000  # per axis
MAX_STEPS = 10**12  # integrator steps per cell: at ~1 µs a step, days for one cell
MAX_COUNT = 1_000_000  # revolutions, jumps and other per-cell counts
MAX_START = 1e3  # a basin's starts (lifts h, h per unit time): far outside every attractor


class Axis(Settings):
    """A grid axis: ``points`` values from ``from`` to ``to`` inclusive, evenly spaced."""

    start: float = Field(alias="from")
    stop: float = Field(alias="to")
    points: Annotated[int, Field(ge=1, le=MAX_POINTS)]

    @model_validator(mode="after")
    def distinct_values(self):
        if self.points > 1 and self.start == self.stop:
            raise ValueError(
                f"from = to = {self.start:g} with {self.points} points would compute "
                f"{self.points} identical cells; give a range, or points: 1"
            )
        return self

    def values(self) -> np.ndarray:
        return np.linspace(self.start, self.stop, self.points)


def check_parameter(name: str, value: float) -> float:
    """Raise ValueError with the allowed range when a model parameter is out of range."""
    if not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value}")
    if name == "omega" and not value > 0.0:
        raise ValueError(f"omega must be > 0, got {value}")
    if name in ("mu_kn", "mu_cn") and not 0.0 < value < 1.0:
        raise ValueError(f"{name} must be in (0, 1), got {value}")
    if name == "zeta" and not value >= 0.0:
        raise ValueError(f"zeta must be ≥ 0, got {value}")
    if name == "f0" and not value >= 0.0:
        raise ValueError(f"f0 must be ≥ 0, got {value}")
    return value
