"""Codes of a cell's outcome: status, kind of steady motion, flags; text given once here.

A leaf module: njit code returns and sets these integers (module-level ints,
which numba folds into constants), Python code translates them with the enums
and tables below. Not to be confused with ``campar status``, the progress of a
run's store (``campar.sweep.progress``).
"""

import enum

# Plain ints for njit code (numba folds module-level ints into constants).
OK = 0
STEP_UNDERFLOW = 1
NONFINITE = 2
STEP_LIMIT = 3
EVENT_LOOP = 4

PERIODIC = 0
QUASIPERIODIC = 1
CHAOTIC = 2
UNCONVERGED = 3
FAILED = 4

# Flag bits of a cell (see Flag for their meaning).
FLAG_NEWTON = 1
FLAG_SLOW = 2
FLAG_GRAZING = 4
FLAG_WARM_EXTRAPOLATED = 8
FLAG_RESTARTED = 16
FLAG_ESCAPED = 32
FLAG_SETTLED = 64


class Status(enum.IntEnum):
    """Why a cell ended; anything but OK marks a failed cell (its numbers are NaN)."""

    OK = OK
    STEP_UNDERFLOW = STEP_UNDERFLOW
    NONFINITE = NONFINITE
    STEP_LIMIT = STEP_LIMIT
    EVENT_LOOP = EVENT_LOOP


STATUS_MESSAGES = {
    Status.OK: "ok",
    Status.STEP_UNDERFLOW: "step size fell below the floor (stiff or singular field)",
    Status.NONFINITE: "the state became NaN or infinite",
    Status.STEP_LIMIT: "the cell ran over its step budget",
    Status.EVENT_LOOP: "contact events repeated at one instant (grazing without progress)",
}


class Kind(enum.IntEnum):
    """What the steady motion of a cell was classified as."""

    PERIODIC = PERIODIC
    QUASIPERIODIC = QUASIPERIODIC
    CHAOTIC = CHAOTIC
    UNCONVERGED = UNCONVERGED
    FAILED = FAILED


KIND_NAMES = {
    Kind.PERIODIC: "periodic",
    Kind.QUASIPERIODIC: "quasi-periodic",
    Kind.CHAOTIC: "chaotic",
    Kind.UNCONVERGED: "unconverged",
    Kind.FAILED: "failed",
}

# Short labels used in maps for the non-periodic kinds.
KIND_LABELS = {
    Kind.QUASIPERIODIC: "QP",
    Kind.CHAOTIC: "chaos",
    Kind.UNCONVERGED: "unconverged",
    Kind.FAILED: "failed",
}


class Flag(enum.IntFlag):
    """Remarks on a cell that a reader of a map should know about."""

    NONE = 0
    # the transient was shortened by Newton jumps on the section map
    NEWTON = FLAG_NEWTON
    # a multiplier lies within 0.02 of the unit circle: slow convergence; on a
    # non-periodic cell, the multiplier of a stable cycle estimated within 0.1 of its
    # last section point (the verdict may be a cycle the budget did not reach)
    SLOW = FLAG_SLOW
    # a local minimum of ε lies within 1e-5 of 0: p is sensitive (needs dc/eps/pn)
    GRAZING = FLAG_GRAZING
    # the start was extrapolated from the previous cells
    WARM_EXTRAPOLATED = FLAG_WARM_EXTRAPOLATED
    # the previous cell failed; this one started from the job's state
    RESTARTED = FLAG_RESTARTED
    # the transient lingered at an unstable cycle and was moved off it along its unstable
    # direction (next to a period doubling or a fold)
    ESCAPED = FLAG_ESCAPED
    # the budget ended with the motion within 1e-4 of a stable cycle that Newton's method
    # could not bring within conv_tol (the integration's noise over 1 − |μ|, or a multiplier
    # near the unit circle): the cell is that cycle, its outputs the cycle's to about 1e-4
    SETTLED = FLAG_SETTLED


def status_message(code: int) -> str:
    """Text for a status code, also for codes from a newer campar."""
    try:
        return STATUS_MESSAGES[Status(code)]
    except ValueError:
        return f"unknown status {code}"


def cell_label(kind: int, n: int, p: int, chatter_p: int = 7) -> str:
    """The map label of a cell: "2-2", "1-7~" (chattering), "QP", "chaos", …"""
    if kind != Kind.PERIODIC:
        return KIND_LABELS.get(Kind(kind), "failed")
    if p >= chatter_p:
        return f"{n}-{p}~"
    return f"{n}-{p}"
