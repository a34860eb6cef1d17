"""A map that stores the duty cycle but no extremum refines ε's dips alone.

Its revolutions keep only the steps whose models see a minimum of ε (the dips the grazing
flag reads) and refine only those (campar.core.revolution's DUTY_STATS): every output it
stores, the window's dips and the time separated are those of the map that refines every
extremum (checked against SciPy in test_extrema), bit for bit, and its revolutions keep
fewer steps.
"""

import numpy as np

from campar.core.analysis import REV_EPS_MIN, REV_GRAZE, REV_T_FREE
from campar.core.deferred import DEFERRED
from campar.core.kernel import OUT_EXTREMA, OUT_STATS, chain_compiled, make_chain_work
from campar.core.model import kernel_law, start_chain
from campar.core.revolution_call import revolution_link
from campar.model.compute import output_bits
from campar.sweep.job import Job
from campar.sweep.plan import chain_parameters
from campar.sweep.tile import allocate_outputs, cell_settings, chain_starts, solver_options

FULL = ("label", "dc", "eps", "pn", "multipliers")
DUTY = ("label", "dc", "multipliers")


def chain(outputs):
    """(outputs, chain work) of a chain of cells that fly and push (ω 3 → 0.6)."""
    job = Job.from_dict(
        {
            "name": "duty",
            "sweep": {
                "omega": {"from": 3.0, "to": 0.6, "points": 9},
                "mu_cn": {"from": 0.8, "to": 0.8, "points": 1},
            },
            "fixed": {"zeta": 0.2, "mu_kn": 0.8, "f0": 0.5},
            "chains": {"start": "continue"},
            "outputs": list(outputs),
        }
    )
    par = chain_parameters(job, 0)
    cs = cell_settings(job)
    out = allocate_outputs(len(par["omega"]), cs.output_bits, job.n_sections)
    solver = solver_options(job)
    law = kernel_law(job.law(0))
    cw = make_chain_work(cs)
    cw.revolution[:] = revolution_link(solver, cs, cw.w6, law=law)
    start_chain(law)
    args = [par[name] for name in ("omega", "zeta", "f0", "mu_kn", "mu_cn")]
    chain_compiled(*args, law, chain_starts(job)[0], solver, cs, out, cw)
    return out, cw


def test_output_bits_ask_for_extrema_only_with_eps_pn_or_separation():
    assert output_bits(("label", "dc")) == OUT_STATS
    for name in ("eps", "pn", "separation"):
        assert output_bits(("label", name)) == OUT_STATS | OUT_EXTREMA
    assert output_bits(("label", "multipliers")) & (OUT_STATS | OUT_EXTREMA) == 0


def test_a_duty_cycle_map_refines_the_dips_alone_with_the_same_numbers():
    full, full_work = chain(FULL)
    duty, duty_work = chain(DUTY)
    assert (full.p > 0).any() and (full.p == 0).any()  # cells that fly and cells that push
    for name in ("n", "p", "kind", "status", "flags", "dc", "state", "revolutions", "steps"):
        assert getattr(duty, name).tobytes() == getattr(full, name).tobytes(), name
    assert duty.multipliers.tobytes() == full.multipliers.tobytes()
    for name in ("eps_min", "eps_max", "pn_max"):  # not stored, not all refined
        assert np.isnan(getattr(duty, name)).all() and np.isfinite(getattr(full, name)).all()
    # the last cell's window: its dips refined alike
    k, m = full.revolutions[-1], full.n[-1]
    assert m > 0
    window = slice(k - m, k)
    for column in (REV_GRAZE, REV_EPS_MIN, REV_T_FREE):
        got = duty_work.revs[window, column]
        assert got.tobytes() == full_work.revs[window, column].tobytes(), column
    assert np.isfinite(full_work.revs[window, REV_GRAZE]).any()  # a dip was refined
    # its transient revolutions (not refined) kept fewer steps: no maxima, no Pn peaks
    kept_full = full_work.kept[: k - m, DEFERRED].sum()
    kept_duty = duty_work.kept[: k - m, DEFERRED].sum()
    assert 0 < kept_duty < kept_full
