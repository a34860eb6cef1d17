"""The chain's call of one revolution through its address (campar.core.revolution_call)."""

import numpy as np
import pytest
from numba import typeof

from campar.core import revolution
from campar.core.kernel import chain_compiled, make_chain_work
from campar.core.model import kernel_law
from campar.core.revolution import make_trace
from campar.core.revolution_call import fingerprint, revolution_args, revolution_link
from campar.core.tracer import trace_arguments, trace_compiled, tracer_link
from campar.sweep.job import cell_job
from campar.sweep.tile import allocate_outputs, cell_settings, solver_options
from campar.views.point import POINT_OUTPUTS


def chain_arguments(method="dop853"):
    job = cell_job(outputs=POINT_OUTPUTS, omega=3.0, method=method)
    solver, settings = solver_options(job), cell_settings(job)
    out = allocate_outputs(1, settings.output_bits, job.n_sections)
    one = np.ones(1)
    cells = (np.array([3.0]), 0.2 * one, 0.5 * one, 0.8 * one, 0.8 * one)
    return cells, solver, settings, out


@pytest.mark.parametrize("method", ["dop853", "dp54", "rk4"])
def test_the_linked_signature_is_the_one_the_chain_calls_with(method):
    """The chain raises if the fingerprint it was typed with differs from its link's; a
    run that computes a cell shows that revolution_args matches the call site."""
    cells, solver, settings, out = chain_arguments(method)
    cw = make_chain_work(settings)
    link = revolution_link(solver, settings, cw.w6)
    args = revolution_args(solver, settings, cw.w6)
    assert link[1] == fingerprint(args) and link[0] != 0
    np.testing.assert_array_equal(revolution_link(solver, settings, cw.w6), link)
    assert args in revolution.run_revolution.overloads
    cw.revolution[:] = link
    chain_compiled(*cells, kernel_law(True), np.zeros(2), solver, settings, out, cw)
    assert out.status[0] == 0 and out.n[0] >= 1


def test_a_chain_linked_for_other_arguments_raises_instead_of_calling():
    cells, solver, settings, out = chain_arguments()
    cw = make_chain_work(settings)
    cw.revolution[:] = revolution_link(solver, settings, cw.w6)
    cw.revolution[1] ^= 1
    with pytest.raises(RuntimeError, match="other argument types"):
        chain_compiled(*cells, kernel_law(True), np.zeros(2), solver, settings, out, cw)
    assert out.revolutions[0] == 0  # nothing was computed


def test_the_tracer_links_the_revolution_with_a_recorder_and_checks_it_too():
    _, solver, settings, _ = chain_arguments()
    rec = make_trace(100, 10, 1)
    args = trace_arguments(3.0, 0.2, 0.5, 0.8, 0.8, True, np.zeros(2), solver, settings, 2, rec)
    link = tracer_link(solver, settings, rec, args[5])
    assert link[1] == fingerprint(revolution_args(solver, settings, args[11], typeof(rec)))
    assert link[1] != revolution_link(solver, settings, args[11])[1]  # the chain's variant
    status, y, _ = trace_compiled(*args, link)
    assert status == 0 and rec.count[0] > 2 and y == rec.samples[rec.count[0] - 1, 1]
    link[1] ^= 1
    with pytest.raises(RuntimeError, match="other argument types"):
        trace_compiled(*args, link)
