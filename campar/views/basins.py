"""Which attractor each start of a basin store reached: the attractors matched across cells.

A basin store (a job sweeping ``y0``, ``ydot0``; ``campar.sweep.basin``) holds, per
start, the record ``campar point --attractors`` makes of it: kind, n, p, σn points
(a whole read window) and multipliers. Here the records are grouped into distinct
attractors by the census's rules (``campar.sweep.census.group_cells``: periodic
records one attractor when their σn points agree up to a cyclic shift within
``cycle_tolerance``, non-periodic ones when of one kind with overlapping section
clouds), the same rules as ``campar point --attractors`` and a map's census, so a
basin and a census of its cell name the same attractors. Attractors are ranked by
the starts that reached them, most first (ties: the first start in the store's
order); a start's ``basin`` is that rank (1, 2, …), 0 where it settled on no
attractor (unconverged or failed), -1 where not computed.

Derived when the store is opened (``campar.open`` adds these variables), never
stored: the grouping is a function of the stored records alone, so a repaired or
resumed store can never hold a stale one.
"""

from dataclasses import dataclass

import numpy as np
import xarray as xr

from ..core.codes import Kind
from ..sweep.census import cycle_tolerance, group_cells

UNSETTLED = 0  # ``basin`` of a start that reached no attractor
NOT_COMPUTED = -1


@dataclass(frozen=True)
class BasinAttractors:
    """The attractors of a basin and the start each cell is (flattened in the store's order)."""

    basin: np.ndarray  # per cell: rank of the attractor reached (1 …), 0 none, -1 not computed
    first: np.ndarray  # per attractor: the cell index of its first start (its representative)
    starts: np.ndarray  # per attractor: the starts that reached it
    computed: int  # the starts computed (the denominator of the fractions)

    @property
    def fraction(self) -> np.ndarray:
        """Per attractor: the share of the computed starts that reached it."""
        return self.starts / max(self.computed, 1)


def match_basin(job, kind, n, sections) -> BasinAttractors:
    """Group a basin's records (arrays over the grid; ``sections`` with two trailing axes)
    into attractors (``campar.sweep.census.group_cells``)."""
    kind = np.asarray(kind).reshape(-1).astype(np.int64)
    n = np.asarray(n).reshape(-1).astype(np.int64)
    sections = np.asarray(sections, float).reshape(kind.size, *np.shape(sections)[-2:])
    groups, found = group_cells(kind, n, sections, cycle_tolerance(job))
    computed = kind >= 0
    basin = np.where(computed, found + 1, NOT_COMPUTED)
    first = np.array([g[0] for g in groups], np.int64)
    starts = np.array([len(g) for g in groups], np.int64)
    return BasinAttractors(basin, first, starts, int(computed.sum()))


# Per-attractor variables: (source, long name, extra attributes); the source is a stored
# per-cell array taken at the attractor's first start, or one of the match's own counts.
ATTRACTOR_VARIABLES = {
    "attractor_n": ("n", "period of the attractor", {}),
    "attractor_p": ("p", "detachments per period of the attractor", {}),
    "attractor_kind": ("kind", "kind of the attractor", {}),
    "attractor_label": ("label", "n-p label of the attractor", {}),
    "attractor_starts": ("starts", "starts that reached the attractor", {}),
    "attractor_fraction": ("fraction", "basin fraction of the attractor", {"units": "1"}),
    "attractor_sections": (
        "points",
        "stroboscopic section points of the attractor",
        {"units": "1", "comment": "of its first start: a cycle's n points, a cloud's read window"},
    ),
    "attractor_multipliers": (
        "multipliers",
        "Floquet multipliers of the attractor",
        {"units": "1", "comment": "of its first start; NaN where not periodic"},
    ),
}


def basin_variables(ds: xr.Dataset, job) -> dict[str, xr.DataArray]:
    """The variables ``campar.open`` adds to a basin store: ``basin`` over the grid, and
    per attractor (ATTRACTOR_VARIABLES) its n, p, kind, label, starts, fraction, σn points
    and multipliers."""
    grid = (job.second, job.first)
    match = match_basin(job, ds["kind"].values, ds["n"].values, ds["sections"].values)
    per = {
        name: ds[name].values.reshape(match.basin.size, *ds[name].shape[2:])[match.first]
        for name in ("n", "p", "kind", "sections", "multipliers", "label")
    }
    # a cycle's own points: its first n σn points; a cloud keeps the whole read window
    width = per["sections"].shape[1]
    periodic = per["kind"] == Kind.PERIODIC
    keep = np.where(periodic, per["n"], width)[:, None] > np.arange(width)[None, :]
    per["points"] = np.where(keep[..., None], per["sections"], np.nan)
    per["starts"], per["fraction"] = match.starts, match.fraction
    tails = {"points": ds["sections"].dims[2:], "multipliers": ds["multipliers"].dims[2:]}
    rank = np.arange(1, len(match.first) + 1, dtype=np.int32)
    coords = {
        "attractor": (
            "attractor",
            rank,
            {
                "long_name": "attractor of the basin",
                "comment": "rank by the starts that reached it, 1 the most",
            },
        )
    }
    codes = {k: v for k, v in ds["kind"].attrs.items() if k in ("flag_values", "flag_meanings")}
    out = {
        "basin": xr.DataArray(
            match.basin.reshape(ds["kind"].shape).astype(np.int32),
            dims=grid,
            coords={name: ds[name] for name in grid},
            attrs={
                "long_name": "attractor reached from the start (y0, ydot0)",
                "comment": "its rank along the attractor dimension (1 the most starts); "
                f"{UNSETTLED}: settled on none (unconverged or failed); {NOT_COMPUTED}: not "
                "computed. Periodic motions are one attractor when their stroboscopic "
                "section points agree within "
                f"{cycle_tolerance(job):.3g} (infinity norm) after a cyclic shift",
            },
        )
    }
    for name, (source, long_name, attrs) in ATTRACTOR_VARIABLES.items():
        attrs = {"long_name": long_name, **attrs, **(codes if source == "kind" else {})}
        if source == "fraction":
            attrs["comment"] = f"of the {match.computed} starts computed"
        dims = ("attractor", *tails.get(source, ()))
        out[name] = xr.DataArray(per[source], dims=dims, coords=coords, attrs=attrs)
    return out
