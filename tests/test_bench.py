"""`campar bench`: every benchmark runs in a tiny configuration and prints its table."""

from pathlib import Path

import numpy as np
import pytest

from campar.bench import BENCHMARKS, maps, outputs, peers, precision
from campar.cli import main
from campar.core.codes import Flag, Kind
from campar.sweep.job import DEFAULT_INTEGRATOR, load_job

HEADERS = {
    "precision": ["state err", "event-time err", "Observed slopes", "DP5 state err vs rtol"],
    "peers": ["SciPy 500", "RK4 recipe / campar, periodic", "agree on 3", "map row: RK4 recipe"],
    "outputs": ["labels CPU s", "all/labels", "converged", "fixed"],
    "stress": ["labels (rtols)", "worst time per cell", "label changes"],
    "cells": ["cold ms", "warm revs", "ms/cell", "rev/cell"],
    "map": ["agree %", "adjud. %", "mu_cn     default", "mu_cn     rtol 1e-6", "audit: "],
    "scaling": [
        "cells/s",
        "speed-up",
        "paired",
        "1 process",
        "mpirun -n 2",
        "same map",
        "speed-up over one process, by round:",
    ],
    "directions": ["CPU / down", "both / down", "bit for bit: yes", "hysteretic cells"],
    "master": ["tiles/s", "capacity tiles/s", "workers", "master"],  # its stand-in kernel too
}
REPO = Path(__file__).resolve().parents[1]
QUICK = {"map": maps.QUICK, "outputs": outputs.QUICK}


def test_every_benchmark_is_registered_and_listed(capsys):
    assert set(HEADERS) <= set(BENCHMARKS)
    with pytest.raises(SystemExit):
        main(["bench", "--help"])
    listing = capsys.readouterr().out
    for name in HEADERS:
        assert name in listing


# The tiny runs of some take 5–30 s each (SciPy references, whole sub-planes): slow; some
# start campar or mpirun (a pool of child processes, the ranks of a scaling run). Their
# modules have quick tests of their own below and in test_stress.py.
MARKS = {
    "precision": [pytest.mark.slow],
    "peers": [pytest.mark.slow],
    "outputs": [pytest.mark.slow],
    "stress": [pytest.mark.slow, pytest.mark.process],
    "map": [pytest.mark.slow, pytest.mark.process],
    "scaling": [pytest.mark.mpi],
    "master": [pytest.mark.mpi],
}


# Smaller than their --quick runs where the size changes no line of the table: map's
# reference plane (at a tight tolerance, in a child process) 4 × 4 cells instead of 6 × 6,
# outputs' map one chain of 4 cells instead of two of 6.
SMALLER = {"map": {"size": 4}, "outputs": {"rows": 1, "omegas": 4}}


@pytest.mark.parametrize("name", [pytest.param(n, marks=MARKS.get(n, [])) for n in HEADERS])
def test_benchmark_runs_tiny_and_prints_its_table(name, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(REPO)  # map and scaling read the planes from jobs/
    for key, value in SMALLER.get(name, {}).items():
        monkeypatch.setitem(QUICK[name], key, value)
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
        cells=["1-0 contact", "1-2 impacts"],
        rtols=[1e-4, 1e-6, 1e-8, 1e-10],
        rk4_steps=[120, 480],
        scipy_rtols=[],
        min_seconds=0.0,
    )


def test_dp5_error_falls_with_rtol_in_proportion(precision_runs):
    runs, refs = precision_runs
    for cell in refs:
        err = {r.setting: r.state_error for r in runs if r.cell == cell and r.method == "dp54"}
        assert err[1e-10] < err[1e-6], (cell, err)
    slopes = {
        f.cell: f.slope for f in precision.fits(runs, refs) if f.what == "DP5 state err vs rtol"
    }
    assert set(slopes) == set(refs)
    for cell, slope in slopes.items():
        assert 0.7 <= slope <= 1.3, (cell, slope)


def test_event_sequences_match_the_reference(precision_runs):
    runs, _ = precision_runs
    assert all(r.events_match for r in runs if r.method == "dp54" and r.setting <= 1e-6)


def test_peers_map_row_is_a_piece_of_the_wide_mu_cn_plane():
    """The row the peers compute is chain ROW_CHAIN of jobs/mu_cn_wide.yaml, as it runs it."""
    plane = load_job(REPO / "jobs" / "mu_cn_wide.yaml")
    first, stop = peers.ROW_OMEGA
    row = peers.row_job(first, stop, DEFAULT_INTEGRATOR.method, "converged", 500, 64)
    np.testing.assert_allclose(row.omega, plane.omega[first:stop], rtol=0, atol=1e-12)
    assert row.second == plane.second
    assert row.second_values[0] == plane.second_values[peers.ROW_CHAIN]
    assert row.fixed == plane.fixed
    for section in ("model", "initial", "integrator", "transient", "classify"):
        assert getattr(row, section) == getattr(plane, section), section


def test_map_comparison_counts_cells_by_hand():
    """bench map's score on two 2 × 3 maps that differ in two cells, one of them settled
    for the candidate by a long run: 4/6 agree, 5/6 after adjudication."""
    from campar.bench import maps

    per, chaos = int(Kind.PERIODIC), int(Kind.CHAOTIC)
    ref = {
        "kind": np.array([[per, per, per], [per, chaos, per]]),
        "n": np.array([[1, 2, 1], [1, 0, 1]]),
        "p": np.array([[0, 2, 1], [1, 0, 1]]),
        "dc": np.array([[0.0, 0.5, 0.1], [0.2, np.nan, 0.3]]),
        "flags": np.zeros((2, 3), int),
    }
    cand = {name: values.copy() for name, values in ref.items()}
    cand["n"][0, 1], cand["p"][0, 1] = 1, 1  # 2-2 → 1-1
    cand["kind"][1, 1], cand["n"][1, 1], cand["p"][1, 1] = per, 3, 3  # chaos → 3-3
    cand["flags"][1, 1] = int(Flag.GRAZING)
    cand["dc"][0, 2] += 1e-3
    c = maps.compare(cand, ref, {"0,1": "1-1"})
    assert (c.cells, c.agree, c.adjudicated) == (6, 4 / 6, 5 / 6)
    # |ΔDC| over the four periodic cells that agree: 0, 1e-3, 0, 0
    assert c.dc_error_mean == pytest.approx(2.5e-4) and c.dc_error_max == pytest.approx(1e-3)
    assert [d[:5] for d in c.disagreements] == [
        (0, 1, "2-2", "1-1", "1-1"),
        (1, 1, "chaos", "3-3", None),
    ]
    assert c.flagged(Flag.GRAZING) == 1 and c.flagged(Flag.SLOW) == 0


def test_asking_for_every_output_changes_no_label():
    """bench outputs' premise on a 2 × 6 piece of its sub-plane (with a chaotic cell):
    outputs may change the cost, never n, p, kind or status, in either transient mode."""
    from campar.bench import outputs
    from campar.sweep.job import OUTPUT_NAMES

    for transient in ("converged", "fixed"):
        _, labels = outputs.run_map(outputs.make_job(2, 6, transient, ["label"], revolutions=100))
        _, every = outputs.run_map(outputs.make_job(2, 6, transient, OUTPUT_NAMES, revolutions=100))
        assert (labels["kind"] != int(Kind.PERIODIC)).any()  # not only easy cells
        for name in outputs.LABEL_ARRAYS:
            np.testing.assert_array_equal(every[name], labels[name], err_msg=(transient, name))
