"""A map's unknown edges between periodic cells, typed by shooting.

``find_boundaries`` types an edge from what the store holds on both sides; where that
cannot tell (most often a change of detachments with no stored ε extremum near 0) the
edge is ``unknown``. ``shoot_unknown`` types each such edge between two periodic cells
with ``campar.continuation.edges.type_edge``: both sides' cycles solved by Newton on Pⁿ
from the stored states, continued across the edge, and the change between them located
(G, PD, SN, NS, or a jump between coexisting cycles). The segment's evidence then names
the side whose cycle meets the change and the critical quantity there; its reason says
"by shooting" and where along the edge the change lies.
"""

import math
from dataclasses import replace

import numpy as np

from .transitions import PERIODIC_NAME, Approach, Transition

# The critical value each located change reaches (transitions.CRITICAL's keys).
CRITICAL_OF = {"PD": "-1", "SN": "+1", "NS": "circle", "G": "graze"}
SHOT_NOTE = "unknown edges between periodic cells typed by shooting (Newton on Pⁿ, continued)"


def shoot_unknown(found, job, state, omega, second):
    """``found`` (a ``boundaries.MapBoundaries``, which calls this module) with every
    unknown edge between two periodic cells typed by shooting.

    job: the store's Job (the model and the fixed parameters); state: (rows, cols, 2) the
    cells' stored final states; omega, second: the cell centres of ``found``'s grid.
    """
    from ..continuation.edges import Cell, type_edge
    from ..continuation.section_map import SectionMap

    smap = None
    fixed = {k: float(v) for k, v in dict(job.fixed).items()}
    segments = []
    for segment in found.segments:
        t = segment.transition
        if not (t.type == "unknown" and t.before.kind == t.after.kind == PERIODIC_NAME):
            segments.append(segment)
            continue
        smap = smap or SectionMap(job.model.model_dump(mode="json"))

        def cell(where, side):
            row, col = where
            parameters = {
                **fixed,
                "omega": float(omega[col]),
                found.second_name: float(second[row]),
            }
            return Cell(parameters, (float(state[row, col, 0]), float(state[row, col, 1])), side.n)

        if not all(np.all(np.isfinite(state[w])) for w in (segment.before, segment.after)):
            segments.append(segment)
            continue
        change = type_edge(cell(segment.before, t.before), cell(segment.after, t.after), smap)
        segments.append(retyped(segment, change))
    notes = (*found.notes, SHOT_NOTE)
    return replace(found, segments=tuple(segments), notes=notes)


def retyped(segment, change):
    """The ``boundaries.Segment`` with the type, reason and evidence of a shooting's
    ``change``."""
    t = segment.transition
    where = "" if math.isnan(change.at) else f" at {change.at:.3f} of the edge"
    reason = f"by shooting{where}: {change.reason}"
    evidence = None
    if change.type in CRITICAL_OF and change.side in ("before", "after"):
        value = change.value
        distance = abs(float(value)) if change.type == "G" else abs(abs(complex(value)) - 1.0)
        evidence = Approach(CRITICAL_OF[change.type], change.side, value, distance, None, None)
    transition = Transition(t.before, t.after, change.type, reason, evidence)
    return replace(segment, transition=transition)
