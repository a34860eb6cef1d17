"""Coexisting attractors of every cell of a map: the census a job's ``attractors`` key asks.

For each cell of a chain, besides the chain's own warm-started result (the usual map),
the K starts of ``census.spread_starts`` (rest, then Halton points over the start box)
and the chain's own end state (one more record) are each run at that cell as a
one-cell chain through the same kernel, with the settings ``campar point --attractors``
uses (the job's, but chaos called only at the end of the budget, σn clouds of
``census.CLOUD_POINTS`` points): so a cell's census equals ``find_attractors`` there
with the same K, start for start. The records are grouped by ``census.group_records``.

Per cell: ``n_attractors`` (distinct attractors of all K + 1 records),
``unsettled_starts`` (of the K starts) and, for the first ``attractors.cap``
attractors ranked by basin fraction, their n, p, kind and basin fraction (the share of
the K starts that reached them; the chain's record is not a sample of the start box,
so an attractor only it reached has fraction 0 and ranks last). Nothing here changes
the chain's own arrays. Cost: K + 1 cold one-cell runs per cell (benchmarks/RESULTS.md).
"""

import numpy as np

from ..core.kernel import OUT_MULTIPLIERS, OUT_SECTIONS, OUT_STATS, CellOutputs
from ..model.compute import allocate_outputs, cell_settings, run_chain_over, solver_options
from .census import CHAOS_AFTER, CLOUD_POINTS, cycle_tolerance, group_cells
from .census import spread_starts as census_starts
from .job import Job

# What every start computes: the outputs of ``campar point --attractors`` (its σn cloud,
# multipliers and window statistics), so its trajectory is that command's, bit for bit.
CENSUS_BITS = OUT_STATS | OUT_SECTIONS | OUT_MULTIPLIERS
NO_ATTRACTOR = -1  # n, p, kind of the slots beyond a cell's attractors


def run_starts(
    job: Job, cell: dict[str, np.ndarray], starts, n_sections: int, law=None
) -> CellOutputs:
    """The record of each start (y, y') at one parameter cell (``cell``: one-element
    arrays), each run as a chain of one cell — a fresh start, as a point is — with the
    settings of ``campar point --attractors`` (chaos called at the end of the budget, the
    census's outputs, ``n_sections`` σn points); the records stacked, one per start.
    ``law``: the cell's (job.law of its row; default the job's first row's)."""
    solver = solver_options(job)
    settings = cell_settings(job, CENSUS_BITS)._replace(chaos_after=CHAOS_AFTER)
    records = allocate_outputs(len(starts), CENSUS_BITS, n_sections)
    law = job.law() if law is None else law
    for i, x0 in enumerate(starts):
        rec = allocate_outputs(1, CENSUS_BITS, n_sections)
        run_chain_over(cell, law, np.array(x0, float), solver, settings, rec)
        for mine, one in zip(records, rec, strict=True):
            if len(one):  # outputs not asked for have no cells
                mine[i] = one[0]
    return records


def census_row(job: Job, par: dict[str, np.ndarray], chain_state: np.ndarray, law=None) -> dict:
    """The census arrays of one chain, cells in the order the chain ran (``par``, as
    ``plan.chain_parameters`` gives it); ``chain_state`` (cells, 2): the chain's final
    state of each cell (NaN where it failed: then no chain record)."""
    k, cap = job.attractors.starts, job.attractors.cap
    n_cells = len(par["omega"])
    out = {
        "n_attractors": np.zeros(n_cells, np.int16),
        "unsettled_starts": np.zeros(n_cells, np.int16),
        "attractor_n": np.full((n_cells, cap), NO_ATTRACTOR, np.int32),
        "attractor_p": np.full((n_cells, cap), NO_ATTRACTOR, np.int32),
        "attractor_kind": np.full((n_cells, cap), NO_ATTRACTOR, np.int8),
        "attractor_fraction": np.full((n_cells, cap), np.nan),
    }
    tol = cycle_tolerance(job)
    for i in range(n_cells):
        cell = {name: values[i : i + 1] for name, values in par.items()}
        starts = census_starts(k, float(par["omega"][i]))
        if np.all(np.isfinite(chain_state[i])):
            starts = np.vstack([starts, chain_state[i]])
        rec = run_starts(job, cell, starts, CLOUD_POINTS, law)
        kinds, ns, ps = rec.kind.astype(np.int64), rec.n, rec.p
        groups, basin = group_cells(kinds, ns, rec.sections, tol, counted=k)
        out["n_attractors"][i] = len(groups)
        out["unsettled_starts"][i] = int(np.sum(basin[:k] < 0))
        for slot, group in enumerate(groups[:cap]):
            first = group[0]
            out["attractor_n"][i, slot] = ns[first]
            out["attractor_p"][i, slot] = ps[first]
            out["attractor_kind"][i, slot] = kinds[first]
            out["attractor_fraction"][i, slot] = np.sum(group < k) / k
    return out
