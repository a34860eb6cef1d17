"""`campar bench revolutions`: the distribution of a map's revolutions per cell."""

from pathlib import Path

import numpy as np
import pytest

from campar.bench.revolutions import distribution, labels_differ
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
    other = {name: values.copy() for name, values in cells.items()}
    other["kind"][3], other["n"][3], other["p"][3] = PER, 5, 4  # chaos → 5-4
    other["p"][2] = 1  # 2-2 → 2-1
    other["revolutions"][:] = 7  # revolutions are not labels
    assert labels_differ(cells, other) == 2


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
