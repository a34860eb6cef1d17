"""`campar bench revolutions`: the distribution of a map's revolutions per cell."""

from pathlib import Path

import numpy as np
import pytest

from campar import simulate_point
from campar.bench.revolutions import adjudicate, distribution, labels_differ
from campar.cli import main
from campar.core.codes import Kind

REPO = Path(__file__).resolve().parents[1]
PER, CHAOS = int(Kind.PERIODIC), int(Kind.CHAOTIC)


def test_the_distribution_and_its_shares_are_counted_by_hand():
    cells = {
        "revolutions": np.array([2, 2, 3, 100, 50, 21, 20]),
        "kind": np.array([PER, PER, PER, CHAOS, PER, PER, PER]),
        "n": np.array([1, 1, 2, 0, 8, 4, 4]),
        "p": np.array([1, 1, 2, 0, 6, 4, 4]),
    }
    found = distribution(cells)
    assert found["cells"] == 7 and found["mean"] == pytest.approx(198 / 7)
    assert found["median"] == 20 and found["max"] == 100
    assert found["non-periodic"] == 1 and found["non-periodic share"] == pytest.approx(100 / 198)
    # over 20 revolutions: 50 and 21, not 20
    assert found["periodic > 20"] == 2 and found["periodic > 20 share"] == pytest.approx(71 / 198)
    # by period: 1-cycles 2, 2; the 2-cycle 3; no 3-cycle; 8-, 4- and 4-cycles; the chaos
    assert found["mean, period 1"] == 2 and found["mean, period 2"] == 3
    assert np.isnan(found["mean, period 3"])
    assert found["mean, period 4+"] == pytest.approx(91 / 3)
    assert found["mean, non-periodic"] == 100
    other = {name: values.copy() for name, values in cells.items()}
    other["kind"][3], other["n"][3], other["p"][3] = PER, 5, 4  # chaos → 5-4
    other["p"][2] = 1  # 2-2 → 2-1
    other["revolutions"][:] = 7  # revolutions are not labels
    assert labels_differ(cells, other).tolist() == [False, False, True, True, False, False, False]


@pytest.mark.process  # computes the tiny map in child processes, this tree and a baseline
def test_revolutions_benchmark_runs_tiny_against_a_baseline(capsys, monkeypatch):
    monkeypatch.chdir(REPO)  # the job is jobs/mu_cn.yaml
    assert main(["bench", "revolutions", "--quick", "--baseline", str(REPO)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("machine: ") and "load average" in out
    for text in ("this  baseline", "kernel", "median", "p90", "p99", "non-periodic share"):
        assert text in out, text
    # the same tree twice: the same map
    assert "cells whose label differs from the baseline's: 0" in out


def test_a_changed_label_is_adjudicated_by_a_long_run_from_each_trees_hand_off():
    """Two cells along ω at μcn 0.8 (the base point's 1-1 region); both trees hand the
    second cell the first one's cycle point, the baseline calls it chaos, this tree 1-1:
    the long run from that hand-off sides with this tree."""
    sets = [
        "sweep.omega.from=3.0",
        "sweep.omega.to=2.95",
        "sweep.omega.points=2",
        "sweep.mu_cn.from=0.8",
        "sweep.mu_cn.to=0.8",
        "sweep.mu_cn.points=1",
    ]
    first = simulate_point(3.0, mu_cn=0.8, tensile="clamp")
    assert first.label == "1-1"
    this = {
        "kind": np.array([PER, PER]),
        "n": np.array([1, 1]),
        "p": np.array([1, 1]),
        "state": np.array([first.state, [np.nan, np.nan]]),
    }
    baseline = {name: values.copy() for name, values in this.items()}
    baseline["kind"][1], baseline["n"][1], baseline["p"][1] = CHAOS, 0, 0
    found = adjudicate(
        str(REPO / "jobs" / "mu_cn.yaml"),
        sets,
        {"this": this, "baseline": baseline},
        labels_differ(this, baseline),
    )
    assert found["counts"]["this right"] == 1 and found["counts"]["baseline right"] == 0
    assert found["changes"] == {("chaos", "1-1", True): 1}
