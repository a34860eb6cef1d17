"""What each job output stores: the per-cell arrays, their dtypes, shapes and meaning.

A leaf module (no numba): the store and the runner's master need this table
without loading the compiled kernel. The model is dimensionless (docs/model.md):
lengths in units of the stroke h, time t in units of 1/ωn, forces in units of
K1·h; the cam angle is θ = ω t.
"""

import numpy as np

from .curves_job import CURVE_ARRAYS, CURVE_TAIL_DIMS
from .job import Job

# Arrays each job output brings into the store; "label" is always present.
OUTPUT_ARRAYS = {
    "label": ("n", "p", "kind", "status", "flags", "state", "revolutions", "steps"),
    "dc": ("dc",),
    "eps": ("eps_min", "eps_max"),
    "pn": ("pn_max",),
    "sections": ("sections",),
    "multipliers": ("multipliers",),
    "lyapunov": ("lyapunov",),
    "separation": ("separation_omega", "separation_eps_max", "separation_pn_max"),
}
# Arrays of a job's ``attractors`` census (campar.sweep.multistable), only with that key.
CENSUS_ARRAYS = (
    "n_attractors",
    "unsettled_starts",
    "attractor_n",
    "attractor_p",
    "attractor_kind",
    "attractor_fraction",
)

# dtype and trailing shape of every per-cell array (S = sections per cell).
ARRAY_SPECS = {
    "n": (np.int32, ()),
    "p": (np.int32, ()),
    "kind": (np.int8, ()),
    "status": (np.int8, ()),
    "flags": (np.int16, ()),
    "dc": (np.float64, ()),
    "eps_min": (np.float64, ()),
    "eps_max": (np.float64, ()),
    "pn_max": (np.float64, ()),
    "state": (np.float64, (2,)),  # (y, y′): model.N_STATE, not imported (numba)
    "revolutions": (np.int32, ()),
    "steps": (np.int64, ()),
    "lyapunov": (np.float64, ()),
    "separation_omega": (np.float64, ()),
    "separation_eps_max": (np.float64, ()),
    "separation_pn_max": (np.float64, ()),
    "multipliers": (np.float64, (2, 2)),
    "sections": (np.float64, ("S", 2)),
    "n_attractors": (np.int16, ()),
    "unsettled_starts": (np.int16, ()),
    "attractor_n": (np.int32, ("A",)),  # A = attractors.cap
    "attractor_p": (np.int32, ("A",)),
    "attractor_kind": (np.int8, ("A",)),
    "attractor_fraction": (np.float64, ("A",)),
}

# Names of the trailing dimensions, one per entry of the trailing shape above.
TAIL_DIMS = {
    "state": ("component",),
    "sections": ("section_point", "component"),
    "multipliers": ("multiplier", "part"),
    **{name: ("attractor",) for name in CENSUS_ARRAYS[2:]},
    **CURVE_TAIL_DIMS,
}

# Labels along the trailing dimensions that have names rather than indices.
COMPONENTS = ("y", "ydot")  # the state (y, ẏ)
PARTS = ("real", "imag")  # of a complex Floquet multiplier

# What a reader of the store needs to know of each array: long name, units ("1":
# dimensionless, None: a code or count without units) and a comment. The codes'
# values and names are in campar.core.codes; the store states them from there.
ARRAY_DOCS = {
    "n": (
        "period of the steady motion",
        "1",
        "cam revolutions per period: points of the stroboscopic section σn (θ = 0 mod 2π); "
        "0 where kind is not periodic",
    ),
    "p": (
        "detachments per period",
        "1",
        "contact→separation events (ε crossing 0 downward) in n revolutions; where kind is "
        "not periodic, in the read window",
    ),
    "kind": ("kind of steady motion", None, "the label of a map cell is n-p where periodic"),
    "status": ("why the cell ended", None, "anything but ok is a failed cell (its numbers NaN)"),
    "flags": ("remarks on the cell", None, "bits that a reader of a map should know about"),
    "dc": (
        "duty cycle",
        "1",
        "fraction of time separated (ε < 0) in the steady window: 0 never, 1 always detached",
    ),
    "eps_min": (
        "minimum penetration",
        "1",
        "min ε = yc − y over the steady window, in units of the stroke h; < 0: detachment height",
    ),
    "eps_max": (
        "intrusion depth",
        "1",
        "max ε = yc − y over the steady window, in units of the stroke h",
    ),
    "pn_max": (
        "maximum contact force",
        "1",
        "max Pn over the steady window, in units of K1·h (Hunt–Crossley, docs/model.md)",
    ),
    "state": (
        "final state at θ = 0",
        "1",
        "the cell's last section point, where the next cell of the chain starts: y in units of "
        "the stroke h, ydot = dy/dt with t in units of 1/ωn",
    ),
    "revolutions": ("revolutions computed", "1", "transient and read window: the cell's cost"),
    "steps": ("integrator steps accepted", "1", "the cell's cost"),
    "lyapunov": (
        "largest Lyapunov exponent",
        "1",
        "per unit dimensionless time t (t in units of 1/ωn); of the cycle where periodic",
    ),
    "separation_omega": (
        "separation speed",
        "1",
        "of the cell's row, the same in every cell of it: the lowest ω at which the follower "
        "detaches (p > 0) along the row's chain, located between cells to 1e-6 by bisection "
        "(campar.sweep.separation); NaN where the row's lowest cell detaches or none does",
    ),
    "separation_eps_max": (
        "largest intrusion below the separation speed",
        "1",
        "of the cell's row: max ε over its contact cells up to the separation speed (grid and "
        "bisection), in units of the stroke h",
    ),
    "separation_pn_max": (
        "largest contact force below the separation speed",
        "1",
        "of the cell's row: max Pn over its contact cells up to the separation speed (grid and "
        "bisection), in units of K1·h",
    ),
    "multipliers": (
        "Floquet multipliers",
        "1",
        "eigenvalues of the Jacobian of the period-n section map, largest modulus first; "
        "NaN where not periodic or where the Jacobian was not integrated",
    ),
    "sections": (
        "stroboscopic section points σn",
        "1",
        "(y, ydot) at θ = 0 mod 2π over the last revolutions, in order; NaN-padded",
    ),
    "n_attractors": (
        "distinct attractors found",
        None,
        "of the cell's census: the attractors reached by the job's attractors.starts starts "
        "(rest, then Halton points over y in [-1, 2], ydot within ±1.5 omega at θ = 0) and "
        "by the chain's own end state, each run at the cell to its steady motion; periodic "
        "motions one attractor when their σn points agree up to a cyclic shift",
    ),
    "unsettled_starts": (
        "starts that settled on no attractor",
        None,
        "of the census's starts: unconverged or failed within the transient budget",
    ),
    "attractor_n": (
        "period of the attractor",
        "1",
        "cam revolutions per period; 0 where not periodic; -1 where the cell has fewer attractors",
    ),
    "attractor_p": (
        "detachments per period of the attractor",
        "1",
        "as p; -1 where the cell has fewer attractors",
    ),
    "attractor_kind": (
        "kind of the attractor",
        None,
        "attractors by basin fraction, most frequent first; -1 where the cell has fewer",
    ),
    "attractor_fraction": (
        "basin fraction of the attractor",
        "1",
        "share of the census's starts that reached it (0: reached by the chain alone); "
        "NaN where the cell has fewer attractors",
    ),
}


def array_names(job: Job) -> list[str]:
    """Names of the per-cell arrays a job stores, in a fixed order."""
    if job.kind == "curves":
        return list(CURVE_ARRAYS)
    wanted = {name for output in job.outputs for name in OUTPUT_ARRAYS[output]}
    if job.attractors is not None:  # the census: a job key, not an output
        wanted.update(CENSUS_ARRAYS)
    return [name for name in ARRAY_SPECS if name in wanted]


def array_spec(job: Job, name: str) -> tuple[np.dtype, tuple[int, ...]]:
    """dtype and per-cell trailing shape of array ``name`` for this job."""
    dtype, tail = CURVE_ARRAYS[name] if name in CURVE_ARRAYS else ARRAY_SPECS[name]
    sizes = {"S": job.n_sections, "A": job.attractors.cap if job.attractors else 0}
    return np.dtype(dtype), tuple(sizes.get(d, d) for d in tail)
