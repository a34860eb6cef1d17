"""The base of every job section: frozen pydantic settings that refuse unknown keys, and
YAML's true/false or text where a number belongs; the bounds of every integer and the
grid axis (campar.sweep.job, campar.model.laws)."""

import math
import reprlib
import typing
from typing import Annotated

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator


class Settings(BaseModel):
    # allow_inf_nan: no infinity or NaN in any number of a job (settings and axis ends alike).
    model_config = ConfigDict(
        extra="forbid",
        frozen=True,
        populate_by_name=True,
        allow_inf_nan=False,
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
# Parameter bounds: the integrator's steps per revolution grow with ω/ωn and with f0, ζ
# (stiff springs), so values far beyond any cam's would only exhaust the step budget.
MAX_OMEGA = 100.0  # cam speed / natural frequency
MAX_LOAD = 1e3  # f0 and zeta
MAX_PERIOD = 256  # a cycle's period in revolutions (classify.n_max's bound, --cycle N)
MAX_STARTS = 4096  # starts of an attractor census (attractors.starts, --attractors K)


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
    if name == "omega" and value > MAX_OMEGA:
        raise ValueError(f"omega must be ≤ {MAX_OMEGA:g}, got {value:g}")
    if name in ("f0", "zeta") and value > MAX_LOAD:
        raise ValueError(f"{name} must be ≤ {MAX_LOAD:g}, got {value:g}")
    if name in ("mu_kn", "mu_cn") and not 0.0 < value < 1.0:
        raise ValueError(f"{name} must be in (0, 1), got {value}")
    if name == "zeta" and not value >= 0.0:
        raise ValueError(f"zeta must be ≥ 0, got {value}")
    if name == "f0" and not value >= 0.0:
        raise ValueError(f"f0 must be ≥ 0, got {value}")
    return value


def check_count(what: str, value: int, low: int, high: int) -> int:
    """``value`` unless outside [low, high]: ValueError "WHAT must be from LOW to HIGH, got
    VALUE" (a count or size the user gives: starts, a cycle's period, points)."""
    if type(value) is not int or not low <= value <= high:
        raise ValueError(f"{what} must be an integer from {low} to {high}, got {value}")
    return value


SHOWN_CHARS = 60  # of a bad value in a message: a value may be huge (a list from aliases)


def short_repr(value) -> str:
    """``repr(value)`` cut to SHOWN_CHARS, without building the whole of a huge value."""
    if isinstance(value, (list, tuple, dict, set)) and len(value) > 8:
        return f"a {type(value).__name__} of {len(value)} items"
    text = reprlib_repr(value)
    return text if len(text) <= SHOWN_CHARS else text[: SHOWN_CHARS - 1] + "…"


def reprlib_repr(value) -> str:
    shown = reprlib.Repr()
    shown.maxstring, shown.maxother, shown.maxlevel = SHOWN_CHARS, SHOWN_CHARS, 3
    return shown.repr(value)
