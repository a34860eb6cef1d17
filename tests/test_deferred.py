"""The chain's deferred extrema (campar.core.deferred) are the extrema refined at once.

The reference is the same chain with statistics rows of N_REV_STATS columns, where every
step's extremum is refined on the dense output as the step is taken (extrema.step_extremes,
checked against SciPy in test_extrema): every output of every cell, bit for bit, for the
paper's law and others — a law that keeps the impact velocity, another cam law, each
integrator — on chains that reach cycles and non-periodic motions. A map that stores the
duty cycle but no extremum keeps and refines ε's dips alone (revolution.DUTY_STATS): the
same outputs, dips and time separated as the map that refines every extremum. A
non-periodic cell's window (64 revolutions) refines only the steps whose models come near
its extremes, with the numbers of refining every step.
"""

import numpy as np
import pytest

from campar.core.analysis import N_REV_STATS, REV_EPS_MIN, REV_GRAZE, REV_T_FREE
from campar.core.codes import CHAOTIC
from campar.core.deferred import (
    DEFER_COLUMNS,
    DEFERRED,
    DIP_DONE,
    EPS_MARGIN,
    FIRST_SLOT,
    MODEL_DIP,
    MODEL_PEAK,
    MODEL_PN,
    PEAK_DONE,
    PN_DONE,
    REFINED,
    SLOT,
    SLOTS,
    H,
)
from campar.core.kernel import OUT_EXTREMA, OUT_STATS, chain_compiled, make_chain_work
from campar.core.model import kernel_law, start_chain
from campar.core.revolution_call import revolution_link
from campar.model.compute import output_bits
from campar.sweep.job import Job
from campar.sweep.plan import chain_parameters
from campar.sweep.tile import allocate_outputs, cell_settings, chain_starts, solver_options


def job_of(
    model=None,
    integrator=None,
    outputs=("label", "dc", "eps", "pn", "multipliers"),
    omega=(3.0, 0.6, 9),
    mu_cn=0.8,
):
    spec = {
        "name": "deferred",
        "sweep": {
            "omega": dict(zip(("from", "to", "points"), omega, strict=True)),
            "mu_cn": {"from": mu_cn, "to": mu_cn, "points": 1},
        },
        "fixed": {"zeta": 0.2, "mu_kn": 0.8, "f0": 0.5},
        "chains": {"start": "continue"},
        "outputs": list(outputs),
        "model": model or {},
        "integrator": integrator or {},
    }
    return Job.from_dict(spec)


def assert_same_outputs(got, expected):
    """Every output array of ``got`` byte for byte ``expected``'s."""
    for name, values in got._asdict().items():
        assert values.tobytes() == getattr(expected, name).tobytes(), name


def run(job, deferring):
    """(outputs, chain work) of the job's chain 0, statistics rows wide (deferring) or
    of N_REV_STATS columns (each extremum refined at once)."""
    par = chain_parameters(job, 0)
    cs = cell_settings(job)
    out = allocate_outputs(len(par["omega"]), cs.output_bits, job.n_sections)
    solver = solver_options(job)
    law = kernel_law(job.law(0))
    cw = make_chain_work(cs)
    if not deferring:
        cw = cw._replace(revs=np.zeros((cw.revs.shape[0], N_REV_STATS)))
    cw.revolution[:] = revolution_link(solver, cs, cw.w6, law=law)
    start_chain(law)
    args = [par[name] for name in ("omega", "zeta", "f0", "mu_kn", "mu_cn")]
    chain_compiled(*args, law, chain_starts(job)[0], solver, cs, out, cw)
    return out, cw


CASES = {
    "paper": ({}, {}),
    "restitution": ({"contact": {"law": "lankarani-nikravesh", "restitution": 0.7}}, {}),
    "dp54": ({}, {"method": "dp54", "rtol": 1e-8}),
    # long free flights across a cycloidal fall, where the models are off by up to 2 % of
    # ε's range: the windows widen their margins
    "cycloidal": ({"cam": {"rise": "cycloidal", "fall": "cycloidal"}}, {}),
}


@pytest.mark.parametrize(
    "case",
    # the impact velocity a restitution law keeps, a method whose step prepares its own
    # dense output, a cam law the models fit worst; each compiles a kernel of its own
    # (cold: slow)
    [c if c == "paper" else pytest.param(c, marks=pytest.mark.slow) for c in CASES],
)
def test_deferred_extrema_are_the_extrema_refined_at_once(case):
    model, integrator = CASES[case]
    job = job_of(model, integrator)
    deferred, cw = run(job, True)
    at_once, narrow = run(job, False)
    assert cw.revs.shape[1] == DEFER_COLUMNS
    assert_same_outputs(deferred, at_once)
    assert np.isfinite(deferred.eps_min).all() and np.isfinite(deferred.pn_max).all()
    assert (deferred.eps_min < 0.0).any()  # some cells fly: dips were refined
    # steps were deferred (some are left in transient revolutions' rows, or DOP853
    # evaluated the field to prepare the windows' dense outputs); the narrow chain none
    assert (cw.revs[:, DEFERRED] > 0).any() or cw.refine.counts[2] > 0
    if integrator.get("method", "dop853") == "dop853":
        assert cw.refine.counts[2] > 0
    assert narrow.refine.counts[2] == 0


def test_a_map_without_statistics_defers_and_refines_nothing():
    job = job_of(outputs=("label", "multipliers"))
    out, cw = run(job, True)
    assert (out.n > 0).any()
    assert np.isnan(out.dc).all() and np.isnan(out.eps_min).all()
    assert not cw.revs[:, DEFERRED].any()
    assert not cw.refine.counts.any()


def test_output_bits_ask_for_extrema_only_with_eps_pn_or_separation():
    assert output_bits(("label", "dc")) == OUT_STATS
    for name in ("eps", "pn", "separation"):
        assert output_bits(("label", name)) == OUT_STATS | OUT_EXTREMA
    assert output_bits(("label", "multipliers")) & (OUT_STATS | OUT_EXTREMA) == 0


def test_a_duty_cycle_map_refines_the_dips_alone_with_the_same_numbers():
    full, full_work = run(job_of(), True)
    duty, duty_work = run(job_of(outputs=("label", "dc", "multipliers")), True)
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
    kept_full = full_work.revs[: k - m, DEFERRED].sum()
    kept_duty = duty_work.revs[: k - m, DEFERRED].sum()
    assert 0 < kept_duty < kept_full


def window_slots(out, cw, count):
    """The kept-step slots (revolutions × SLOTS × SLOT) of the one-cell chain's window of
    ``count`` revolutions, and which of them hold a step."""
    k = out.revolutions[0]
    slots = cw.revs[k - count : k, FIRST_SLOT:].reshape(count, SLOTS, SLOT)
    return slots, slots[:, :, H] > 0.0


def test_a_chaotic_window_refines_only_the_steps_near_its_extremes():
    # ω 4.5, μcn 0.97: chaos (test_early_verdicts); one cell, so every row holds the slots
    # of its own revolution
    job = job_of(omega=(4.5, 4.5, 1), mu_cn=0.97)
    deferred, cw = run(job, True)
    at_once, _ = run(job, False)
    assert_same_outputs(deferred, at_once)
    assert deferred.kind[0] == CHAOTIC  # a 64-revolution window
    slots, kept = window_slots(deferred, cw, 64)
    refined = slots[:, :, REFINED].astype(int)
    counts = []
    for column, bit in ((MODEL_DIP, DIP_DONE), (MODEL_PEAK, PEAK_DONE), (MODEL_PN, PN_DONE)):
        candidates = kept & np.isfinite(slots[:, :, column])
        done = candidates & (refined & bit > 0)
        counts.append((int(candidates.sum()), int(done.sum())))
        assert done.any()
    # far fewer refined than candidates: the window's extremes, not its 64 revolutions
    assert sum(done for _, done in counts) < 0.5 * sum(c for c, _ in counts), counts
    k = deferred.revolutions[0]
    assert not cw.revs[k - 64 : k, DEFERRED].any()


@pytest.mark.slow  # a kernel of its own (cycloidal law): a cold compile
def test_a_window_whose_models_are_far_off_widens_its_margin():
    # a free flight across a cycloidal fall (f0 0.5, ω 1.5, a 1-cycle): the quintic's dip
    # is off by more than its first margin allows, so the window refines a second dip too
    job = job_of({"cam": {"rise": "cycloidal", "fall": "cycloidal"}}, omega=(1.5, 1.5, 1))
    deferred, cw = run(job, True)
    at_once, _ = run(job, False)
    assert_same_outputs(deferred, at_once)
    assert deferred.n[0] == 1
    slots, kept = window_slots(deferred, cw, 1)
    dips = slots[:, :, MODEL_DIP][kept & np.isfinite(slots[:, :, MODEL_DIP])]
    peaks = slots[:, :, MODEL_PEAK][kept & np.isfinite(slots[:, :, MODEL_PEAK])]
    window_min = cw.revs[deferred.revolutions[0] - 1, REV_EPS_MIN]  # its refined dips too
    lo, hi = min(dips.min(), window_min), peaks.max()
    first_margin = EPS_MARGIN * (hi - lo)
    within = (dips <= lo + first_margin).sum()
    refined = (slots[:, :, REFINED].astype(int) & DIP_DONE > 0)[kept].sum()
    assert 1 <= within < refined < len(dips)  # widened, yet not every dip refined
