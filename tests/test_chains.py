"""Where chains start (``chains.start``) and which way they run (``chains.direction``).

The paper computes each plane from one starting corner by 2-D continuation:
``continue`` solves the first column as one chain along the second axis, then
every row starts from the attractor found there. Checked here against the
independent SciPy model (each row's start lies on a cycle of its first cell),
against single cells from rest (``up`` ends where ``down`` starts), and for
independence from which tiles a process computed and from the rank count.
"""

import subprocess
import sys
import textwrap

import numpy as np
import pytest
from support.jobs import SMALL_JOB, assert_same_map, merge, reference_arrays
from support.processes import MPIRUN

from campar.bench.scipy_model import Model
from campar.bench.scipy_peer import scipy_cell
from campar.core.codes import PERIODIC
from campar.sweep.job import Job
from campar.sweep.plan import chain_order, plan_tiles
from campar.sweep.store import read_store
from campar.sweep.tile import chain_starts, run_tile
from campar.views.point import simulate_point

CONTINUE = merge(SMALL_JOB, {"name": "cont", "chains": {"start": "continue"}})


def job_of(data: dict) -> Job:
    return Job.from_dict(data)


def test_rest_starts_every_chain_from_the_initial_state():
    job = job_of(merge(SMALL_JOB, {"initial": {"y": 0.25, "v": -0.5}}))
    np.testing.assert_array_equal(chain_starts(job), np.tile([0.25, -0.5], (job.shape[0], 1)))


def test_chains_run_in_the_asked_direction_and_are_stored_in_the_job_order():
    data = merge(SMALL_JOB, {"sweep": {"omega": {"from": 1.0, "to": 3.0, "points": 9}}})
    down, up = (job_of(merge(data, {"chains": {"direction": d}})) for d in ("down", "up"))
    np.testing.assert_array_equal(down.omega[chain_order(down)], np.sort(down.omega)[::-1])
    np.testing.assert_array_equal(up.omega[chain_order(up)], np.sort(up.omega))
    tile = plan_tiles(up)[0]
    for job, first in ((down, -1), (up, 0)):  # the stored column where the chain started
        cell = run_tile(job, tile)
        alone = simulate_point(float(job.omega[first]), mu_cn=float(job.second_values[0]))
        assert (cell["n"][0, first], cell["p"][0, first]) == (alone.n, alone.p)
        np.testing.assert_allclose(cell["state"][0, first], alone.state, atol=1e-9)


def test_continue_starts_each_row_on_a_cycle_of_its_first_cell_by_scipy():
    job = job_of(CONTINUE)
    starts = chain_starts(job)
    first = run_tile(job, plan_tiles(job)[0])  # row 0's cells, as a check of the seed
    assert first["kind"][0, 0] == PERIODIC
    omega0 = float(job.omega[chain_order(job)[0]])
    for row in (1, 3, 5):
        cell = scipy_cell(
            Model(omega0, mu_cn=float(job.second_values[row])), starts[row], 0, 8, rtol=1e-10
        )
        assert cell.n >= 1, row  # SciPy sees a cycle from the start at once: no transient
        np.testing.assert_allclose(cell.sections[cell.n], starts[row], atol=1e-6)
    assert not np.allclose(starts, starts[0])  # the rows do not all start alike


@pytest.mark.process
def test_continue_gives_the_same_tile_in_a_process_that_computed_no_other():
    job = job_of(CONTINUE)
    last = plan_tiles(job)[-1]
    expected = reference_arrays(job)
    code = textwrap.dedent(f"""
        import sys, numpy as np
        from campar.sweep.job import Job
        from campar.sweep.plan import plan_tiles
        from campar.sweep.tile import run_tile
        job = Job.from_dict({CONTINUE!r})
        out = run_tile(job, plan_tiles(job)[{last.index}])
        np.savez(sys.argv[1], **out)
    """)
    path = "/tmp/campar-test-chains-tile.npz"
    subprocess.run([sys.executable, "-c", code, path], check=True, timeout=300)
    got = np.load(path)
    for name, values in expected.items():
        assert np.array_equal(got[name], values[last.rows], equal_nan=True), name


@pytest.mark.mpi
@pytest.mark.skipif(not MPIRUN.exists(), reason=f"no mpirun at {MPIRUN}")
@pytest.mark.process
def test_a_continued_map_under_mpirun_equals_the_serial_one(write_job):
    from support.processes import run_campar_mpi

    path, job = write_job(name="cont", chains={"start": "continue"})
    result = run_campar_mpi(2, "run", path)
    assert result.returncode == 0, result.stderr
    with read_store(job.store) as reader:
        assert reader.attrs["job"]["chains"]["start"] == "continue"
        assert_same_map(reader, job)


def test_a_both_job_runs_each_direction_as_its_one_direction_job_with_its_own_seeds():
    """``chains.direction: both`` with ``continue``: every up tile starts from the first
    column solved at the smallest ω (up's start), every down tile from the largest."""
    both = job_of(merge(CONTINUE, {"chains": {"direction": "both"}}))
    half = len(plan_tiles(both)) // 2
    for direction, tiles in (("down", plan_tiles(both)[:half]), ("up", plan_tiles(both)[half:])):
        one = job_of(
            merge(CONTINUE, {"chains": {"direction": direction}, "outputs": list(both.outputs)})
        )
        np.testing.assert_array_equal(
            chain_starts(both.one_direction(direction)), chain_starts(one)
        )
        for tile, alone in zip(tiles, plan_tiles(one), strict=True):
            assert tile.direction == direction and tile.rows == alone.rows
            got, expected = run_tile(both, tile), run_tile(one, alone)
            for name, values in expected.items():
                assert np.array_equal(got[name], values, equal_nan=True), (direction, name)
    assert not np.array_equal(
        chain_starts(both.one_direction("down")), chain_starts(both.one_direction("up"))
    )
    with pytest.raises(ValueError, match="take one_direction first"):
        chain_starts(both)
