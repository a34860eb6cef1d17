"""A stored label run on: ``campar point --from STORE --run-on N`` and
``StoredCell.run_on`` continue a cell's motion from its stored final state with no early
verdict, so a chaotic label given at revolution 96 that was a chaotic transient's is seen
to settle — on the cycle SciPy's shooting finds stable there."""

import json
from pathlib import Path

import numpy as np
import pytest

import campar
import campar.cli
from campar.sweep.job import load_job
from campar.sweep.overrides import with_settings

JOBS = Path(__file__).resolve().parents[1] / "jobs"
# A 12 × 8 piece of the (ω, μcn) plane in its chaotic region (ω 5.2 → 4.6, μcn 0.95 → 0.9).
PIECE = {
    "sweep.omega.from": 5.2,
    "sweep.omega.to": 4.6,
    "sweep.omega.points": 12,
    "sweep.mu_cn.to": 0.9,
    "sweep.mu_cn.points": 8,
    "tiles.rows": 4,
}
TRANSIENT = (3, 10)  # (row, column): chaos at revolution 96, a 5-4 cycle later
CHAOTIC = (0, 0)  # chaos that stays chaos for 1000 more revolutions
PERIODIC = (4, 0)  # a 5-cycle, which holds


@pytest.fixture(scope="module")
def piece(tmp_path_factory):
    job = with_settings(load_job(JOBS / "mu_cn.yaml"), PIECE)
    path = tmp_path_factory.mktemp("run_on") / "piece.zarr"
    campar.run(job, store=path)
    return job, path


def cell_at(job, path, where):
    row, col = where
    return campar.cell(path, omega=job.first_values[col], mu_cn=job.second_values[row])


def argv_of(job, path, where, *flags):
    row, col = where
    coords = [
        "--omega",
        repr(float(job.first_values[col])),
        "--mu-cn",
        repr(float(job.second_values[row])),
    ]
    return ["point", "--from", str(path), *coords, *flags]


def test_a_transient_chaos_label_does_not_hold_and_a_sustained_one_does(piece, capsys):
    job, path = piece
    assert cell_at(job, path, TRANSIENT).label == "chaos"
    assert campar.cli.main(argv_of(job, path, TRANSIENT, "--run-on", "1000", "--json")) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["label"] == "5-4" and data["kind"] == "periodic"
    assert data["revolutions"] < 1000
    assert data["cell"]["stored_label"] == "chaos" and data["cell"]["stored_revolutions"] >= 96
    assert data["cell"]["holds"] is False and data["cell"]["run_on"] == 1000
    assert campar.cli.main(argv_of(job, path, TRANSIENT, "--run-on", "1000")) == 0
    assert "does not hold: the motion is 5-4 after" in capsys.readouterr().out

    assert cell_at(job, path, CHAOTIC).label == "chaos"
    assert campar.cli.main(argv_of(job, path, CHAOTIC, "--run-on", "1000")) == 0
    out = capsys.readouterr().out
    assert "stored: chaos after" in out and "the stored label holds (1000 revolutions" in out


def test_a_cycle_run_on_stays_on_its_cycle(piece):
    job, path = piece
    stored = cell_at(job, path, PERIODIC)
    n = int(stored.stored["n"])
    assert n >= 1
    again = stored.run_on(200)
    assert again.label == stored.label
    assert again.revolutions <= 3 * n  # it starts on the cycle: a few periods confirm it
    np.testing.assert_allclose(again.state, stored.state, atol=1e-6)


@pytest.mark.slow  # SciPy's shooting of a 5-cycle at rtol 1e-12: ~10 s
def test_the_settled_cycle_is_scipys_stable_five_cycle(piece):
    from campar.bench import scipy_shooting

    job, path = piece
    stored = cell_at(job, path, TRANSIENT)
    settled = stored.run_on(1000)
    assert settled.n == 5
    x, jac = scipy_shooting.fixed_point(stored.model.parameters, settled.state, 5)
    np.testing.assert_allclose(settled.state, x, atol=1e-6)
    assert np.max(np.abs(np.linalg.eigvals(jac))) < 1.0  # stable: the motion's attractor
    one = scipy_shooting.section_map(stored.model.parameters, x, 1)
    assert np.max(np.abs(one - x)) > 1e-3  # of least period 5, not a 1-cycle's


def test_run_on_is_refused_where_it_means_nothing(piece, capsys):
    job, path = piece
    assert campar.cli.main(["point", "--omega", "3", "--run-on", "100"]) == 2
    assert "--run-on go with --from STORE" in capsys.readouterr().err
    assert campar.cli.main(argv_of(job, path, TRANSIENT, "--run-on", "0")) == 2
    assert "--run-on must be an integer from 1 to" in capsys.readouterr().err
    assert campar.cli.main(argv_of(job, path, TRANSIENT, "--run-on", "9", "--cycle", "1")) == 2
    assert "without --cycle and --attractors" in capsys.readouterr().err
    assert campar.cli.main(argv_of(job, path, TRANSIENT, "--revolutions", "3000")) == 2
    assert "--run-on N runs the stored cell on" in capsys.readouterr().err
