"""The job's cam and contact laws (``model.cam``, ``model.contact``): their settings, the
law parameters a map may sweep, and the kernel's Law built from them (docs/design.md).

Validation needs numpy alone (campar.model.cam_table); ``kernel_law`` loads the compiled
core's law classes.
"""

import math
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, ValidationError, model_validator

from .settings import Settings

# Parameters of the job's laws (model.cam, model.contact) that a map may sweep as its
# second axis: the name in ``sweep`` and the model section it overrides row by row.
LAW_PARAMETERS = {
    "phi1": "cam",
    "phi2": "cam",
    "phi3": "cam",
    "phi4": "cam",
    "n": "contact",
    "restitution": "contact",
}
# The cam angle that takes up the difference when one is swept (they sum to 2π): the near
# dwell, or the far dwell when the near dwell itself is swept.
TAKES_UP = {"phi1": "phi4", "phi2": "phi4", "phi3": "phi4", "phi4": "phi2"}

MOTION_LAWS = ("cosine", "cycloidal", "polynomial-345", "modified-trapezoid", "modified-sine")
CONTACT_LAWS = ("hunt-crossley", "lankarani-nikravesh", "flores")
ANGLES = ("phi1", "phi2", "phi3", "phi4")
PAPER_ANGLES = (math.pi / 3.0, 2.0 * math.pi / 3.0, math.pi / 3.0, 2.0 * math.pi / 3.0)


class CamSettings(Settings):
    """The cam: a motion law for the rise and one for the fall over the phase angles
    phi1 … phi4 (rise, far dwell, fall, near dwell; radians, summing to 2π), or a table."""

    rise: Literal[MOTION_LAWS] = "cosine"
    fall: Literal[MOTION_LAWS] = "cosine"
    phi1: float = PAPER_ANGLES[0]
    phi2: float = PAPER_ANGLES[1]
    phi3: float = PAPER_ANGLES[2]
    phi4: float = PAPER_ANGLES[3]
    table: str | None = None
    """A CSV of (θ in radians, S in units of the stroke) over one revolution: the cam is the
    periodic C² cubic spline through it (campar.model.cam_table); rise and fall then have
    no say, the angles only say where the revolution's steps end."""
    table_joins: Literal["smooth", "phases"] = "smooth"
    """smooth: one periodic C² spline through the table; phases: a C² spline on each
    phase, the acceleration free to jump at the phase boundaries (points of the table),
    as a cam made of segments (a tabulated cosine law needs it)."""
    table_sha256: str | None = None
    """The table's content hash, set when the job is read: the numbers depend on it."""

    @model_validator(mode="after")
    def consistent(self):
        from .cam_table import check_angles, phase_bounds, read_table  # numpy only

        check_angles(self.angles)
        if self.table is None:
            if self.table_sha256 is not None:
                raise ValueError("table_sha256 belongs to a table: give table too")
            return self
        if (self.rise, self.fall) != ("cosine", "cosine"):
            raise ValueError("a cam is either a table or rise/fall laws, not both")
        table = read_table(self.table, self.table_sha256)
        if self.table_joins == "phases":
            table.spline("phases", phase_bounds(self.angles))  # its boundaries are points
        digest = table.sha256
        if self.table_sha256 is not None and self.table_sha256 != digest:
            raise ValueError(
                f"table {self.table} has changed since this job was made "
                f"(sha256 {digest[:12]}…, the job says {self.table_sha256[:12]}…)"
            )
        object.__setattr__(self, "table_sha256", digest)
        return self

    @property
    def angles(self) -> tuple[float, float, float, float]:
        return (self.phi1, self.phi2, self.phi3, self.phi4)

    def with_angle(self, name: str, value: float) -> "CamSettings":
        """These settings with angle ``name`` at ``value``, TAKES_UP's angle taking up the
        difference (ValueError where that leaves the angles inconsistent)."""
        if value == getattr(self, name):
            return self  # the angles as they are, bit for bit
        other = TAKES_UP[name]
        rest = sum(getattr(self, key) for key in ANGLES if key not in (name, other))
        update = {name: value, other: 2.0 * math.pi - rest - value}
        return CamSettings.model_validate({**self.model_dump(), **update})


class ContactSettings(Settings):
    """The contact force law Pn = k ε^n (1 + c ε') (campar.core.contact)."""

    law: Literal[CONTACT_LAWS] = "hunt-crossley"
    """hunt-crossley: c from μcn (the paper's); lankarani-nikravesh, flores: c from the
    coefficient of restitution and the impact velocity."""
    n: Annotated[float, Field(ge=1.0, le=3.0)] = 1.5
    """Exponent of the penetration: 1.5 Hertz point contact; line contacts ≈ 1.0–1.1."""
    restitution: Annotated[float, Field(gt=0.0, le=1.0)] | None = None
    """Coefficient of restitution e (lankarani-nikravesh, flores: default 0.8)."""
    impact_floor: Annotated[float, Field(gt=0.0)] | None = None
    """Impact velocities below this count as this (lankarani-nikravesh, flores: default
    0.001, in units of h ωn)."""

    @model_validator(mode="after")
    def restitution_only_where_used(self):
        for key in ("restitution", "impact_floor"):
            if self.law == "hunt-crossley" and getattr(self, key) is not None:
                raise ValueError(
                    f"{key}: hunt-crossley takes its damping from mu_cn; "
                    f"{key} belongs to lankarani-nikravesh and flores"
                )
        return self


def check_law_axis(model, name: str, axis) -> None:
    """ValueError unless a map's second axis ``name`` (an Axis) fits the job's ``model``:
    a law parameter not also set in the model, swept in a law that has it, within range at
    both ends (the cam's angles then still summing to 2π)."""
    if name not in LAW_PARAMETERS:
        return
    section = LAW_PARAMETERS[name]
    settings = getattr(model, section)
    default = type(settings).model_fields[name].default
    if name in settings.model_fields_set and getattr(settings, name) != default:
        # (a normalised job states the default there: the sweep overrides it row by row)
        raise ValueError(f"{name} is both swept and set in model.{section}")
    if name == "restitution" and model.contact.law == "hunt-crossley":
        raise ValueError(
            "restitution: a hunt-crossley contact has none to sweep; "
            "model.contact.law: lankarani-nikravesh or flores"
        )
    if name in ANGLES and settings.table is not None and name in ("phi1", "phi3"):
        raise ValueError(f"{name}: a tabulated cam has no rise or fall angle to sweep")
    for end, value in (("from", axis.start), ("to", axis.stop)):
        try:
            if name in ANGLES:
                settings.with_angle(name, value)
            else:
                ContactSettings.model_validate(
                    {**settings.model_dump(exclude_unset=True), name: value}
                )
        except ValidationError as exc:
            message = exc.errors()[0]["msg"].removeprefix("Value error, ")
            raise ValueError(f"sweep.{name}.{end} = {value:g}: {message}") from None


def kernel_law(model, name: str | None = None, value: float | None = None, swept=()):
    """The kernel's Law (campar.core.model.Law) of the job's ``model`` settings, with law
    parameter ``name`` (LAW_PARAMETERS) at ``value``; ``swept``: the law parameters a map
    sweeps (a swept exponent n compiles the general power even at 1.5, so every row runs
    one kernel)."""
    from ..core import cam, contact  # here: numba only for those who compute
    from ..core.model import Law
    from .cam_table import read_table

    settings = model.cam
    con = model.contact
    if name in ANGLES:
        settings = settings.with_angle(name, value)
    elif name is not None:
        con = con.model_copy(update={name: value})
    if settings.table is not None:
        bounds = cam.phase_bounds(settings.angles)
        table = read_table(settings.table, settings.table_sha256)
        knots, coef = table.spline(settings.table_joins, bounds)
        the_cam = cam.tabulated_cam(knots, coef, bounds)
    else:
        the_cam = cam.phased_cam(settings.rise, settings.fall, settings.angles)
    restitution = 0.8 if con.restitution is None else con.restitution
    floor = contact.IMPACT_FLOOR if con.impact_floor is None else con.impact_floor
    the_contact = contact.contact_law(con.law, con.n, restitution, floor, general="n" in swept)
    return Law(np.int64(model.law_bits), the_cam, the_contact)


def row_law(model, second: str, values, row: int):
    """The kernel's Law of a chain: the model's laws with a swept law parameter (a map's
    ``second`` axis in LAW_PARAMETERS) at the row's value."""
    if second not in LAW_PARAMETERS:
        return kernel_law(model)
    return kernel_law(model, second, float(values[row]), swept=(second,))
