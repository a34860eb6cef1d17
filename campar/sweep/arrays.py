"""What each job output stores: the per-cell arrays, their dtypes and shapes.

A leaf module (no numba): the store and the runner's master need this table
without loading the compiled kernel.
"""

import numpy as np

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
}

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
    "multipliers": (np.float64, (2, 2)),
    "sections": (np.float64, ("S", 2)),
}


def array_names(job: Job) -> list[str]:
    """Names of the per-cell arrays a job stores, in a fixed order."""
    wanted = {name for output in job.outputs for name in OUTPUT_ARRAYS[output]}
    return [name for name in ARRAY_SPECS if name in wanted]


def array_spec(job: Job, name: str) -> tuple[np.dtype, tuple[int, ...]]:
    """dtype and per-cell trailing shape of array ``name`` for this job."""
    dtype, tail = ARRAY_SPECS[name]
    return np.dtype(dtype), tuple(job.n_sections if d == "S" else d for d in tail)
