"""`campar bench`: every benchmark runs in a tiny configuration and prints its table."""

from pathlib import Path

import numpy as np
import pytest

from campar.bench import BENCHMARKS, peers, precision
from campar.cli import main
from campar.sweep.job import load_job

HEADERS = {
    "precision": ["state err", "event-time err", "Observed slopes", "DP5 state err vs rtol"],
    "peers": ["SciPy 500", "RK4 recipe / campar, periodic", "agree on 3", "map row: RK4 recipe"],
    "outputs": ["labels CPU s", "all/labels", "converged", "fixed"],
    "stress": ["labels (rtols)", "worst time per cell", "label changes"],
    "cells": ["cold ms", "warm revs", "ms/cell", "rev/cell"],
    "map": ["agree %", "adjud. %", "mu_cn     default", "mu_cn     rtol 1e-6", "audit: "],
    "scaling": ["cells/s", "speed-up", "1 process", "mpirun -n 2", "same map"],
}
REPO = Path(__file__).resolve().parents[1]


def test_every_benchmark_is_registered_and_listed(capsys):
    assert set(HEADERS) <= set(BENCHMARKS)
    with pytest.raises(SystemExit):
        main(["bench", "--help"])
    listing = capsys.readouterr().out
    for name in HEADERS:
        assert name in listing


@pytest.mark.parametrize("name", list(HEADERS))
def test_benchmark_runs_tiny_and_prints_its_table(name, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(REPO)  # map and scaling read the planes from jobs/
    extra = {"precision": ["--plot", str(tmp_path / "precision.png")], "map": ["--audit"]}
    assert main(["bench", name, "--quick", *extra.get(name, [])]) == 0
    out = capsys.readouterr().out
    assert out.startswith("machine: ") and "load average" in out
    for text in HEADERS[name]:
        assert text in out, text
    if name == "precision":
        assert (tmp_path / "precision.png").stat().st_size > 10_000
    if name == "scaling":
        assert " NO" not in out  # every launch computed the same map


@pytest.fixture(scope="module")
def precision_runs():
    return precision.measure(
        cells=["1-0 contact", "1-2 impacts"], rtols=[1e-4, 1e-6, 1e-8, 1e-10],
        rk4_steps=[120, 480], scipy_rtols=[], min_seconds=0.0,
    )  # fmt: skip


def test_dp5_error_falls_with_rtol_in_proportion(precision_runs):
    runs, refs = precision_runs
    for cell in refs:
        err = {r.setting: r.state_error for r in runs if r.cell == cell and r.method == "dp54"}
        assert err[1e-10] < err[1e-6], (cell, err)
    slopes = {f.cell: f.slope for f in precision.fits(runs, refs)
              if f.what == "DP5 state err vs rtol"}  # fmt: skip
    assert set(slopes) == set(refs)
    for cell, slope in slopes.items():
        assert 0.7 <= slope <= 1.3, (cell, slope)


def test_event_sequences_match_the_reference(precision_runs):
    runs, _ = precision_runs
    assert all(r.events_match for r in runs if r.method == "dp54" and r.setting <= 1e-6)


def test_peers_map_row_is_a_piece_of_the_mu_cn_plane():
    """The row the peers compute is chain ROW_CHAIN of jobs/mu_cn.yaml, as that job runs it."""
    plane = load_job(REPO / "jobs" / "mu_cn.yaml")
    first, stop = peers.ROW_OMEGA
    row = peers.row_job(first, stop, "dp54", "converged", 500, 64)
    np.testing.assert_allclose(row.omega, plane.omega[first:stop], rtol=0, atol=1e-12)
    assert row.second == plane.second
    assert row.second_values[0] == plane.second_values[peers.ROW_CHAIN]
    assert row.fixed == plane.fixed
    for section in ("model", "initial", "integrator", "transient", "classify"):
        assert getattr(row, section) == getattr(plane, section), section
