"""What the explorer's map can show of a cell, each computed from a tile's stored arrays.

A field is categorical (``label``, ``kind``: an integer category per cell, named in a
legend) or numeric (a float per cell, NaN where the cell has no value). Categories are
the maps' own (``campar.views.plot.labels``): ``map_labels`` and ``map_kinds`` name them,
so the explorer's legend and colours are those of ``campar plot``.
"""

from dataclasses import dataclass

import numpy as np

from ..sweep.attractor_sets import attractor_sets
from ..views.plot.labels import NOT_COMPUTED, map_kinds, map_labels

NONE_SETTLED = "none settled"  # a census cell whose starts reached no attractor


@dataclass(frozen=True)
class Field:
    name: str
    title: str  # what the legend and the selector say
    needs: tuple[str, ...]  # stored arrays it is computed from
    categorical: bool = False
    units: str = "dimensionless"


FIELDS = (
    Field("label", "n-p label", ("kind", "n", "p"), categorical=True, units=""),
    Field("kind", "kind of motion", ("kind",), categorical=True, units=""),
    Field("dc", "duty cycle", ("dc",)),
    Field("eps_min", "minimum penetration ε (units of stroke h)", ("eps_min",)),
    Field("eps_max", "intrusion depth, max ε (units of stroke h)", ("eps_max",)),
    Field("pn_max", "maximum contact force Pn (units of K1·h)", ("pn_max",)),
    Field("lyapunov", "largest Lyapunov exponent (per unit time 1/ωn)", ("lyapunov",)),
    Field("multiplier", "largest Floquet multiplier |λ|", ("multipliers",)),
    Field("flags", "flags (bits of campar.core.codes.Flag)", ("flags",), units=""),
    Field("revolutions", "revolutions computed", ("revolutions",), units=""),
    Field("n_attractors", "distinct attractors (census)", ("n_attractors",), units=""),
    Field(
        "attractor_set",
        "set of coexisting attractors (census)",
        ("n_attractors", "attractor_kind", "attractor_n", "attractor_p"),
        categorical=True,
        units="",
    ),
)
BY_NAME = {f.name: f for f in FIELDS}


def fields_of(names) -> list[Field]:
    """The fields a store with the arrays ``names`` can show."""
    have = set(names)
    return [f for f in FIELDS if set(f.needs) <= have]


def categories(field: Field, arrays: dict, chatter_p: int):
    """(codes, names): each cell's category index into ``names``, for a categorical field."""
    if field.name == "attractor_set":  # "1-1 + 2-2", as campar plot --what attractor_sets
        count = np.asarray(arrays["n_attractors"])
        codes, names = attractor_sets(
            arrays["attractor_kind"],
            arrays["attractor_n"],
            arrays["attractor_p"],
            count,
            chatter_p,
        )
        names = [name or NONE_SETTLED for name in names]
        pending = len(names)
        return np.where(count < 0, pending, codes), [*names, NOT_COMPUTED]
    cells = map_labels(arrays, chatter_p) if field.name == "label" else map_kinds(arrays)
    return cells.codes, [e.label for e in cells.entries]


def numeric(field: Field, arrays: dict) -> np.ndarray:
    """The float32 value of every cell of a numeric field (NaN: none)."""
    if field.name == "multiplier":  # (…, multiplier, part): the largest modulus
        m = arrays["multipliers"]
        with np.errstate(invalid="ignore"):
            values = np.hypot(m[..., 0], m[..., 1]).max(axis=-1)
    else:
        values = np.asarray(arrays[field.needs[0]], np.float64)
        if np.asarray(arrays[field.needs[0]]).dtype.kind in "iu":
            values = np.where(np.asarray(arrays[field.needs[0]]) < 0, np.nan, values)
    return values.astype(np.float32)
