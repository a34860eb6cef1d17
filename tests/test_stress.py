"""Extreme cells (the fast subset of `campar bench stress`): valid or failed, never hung.

Each cell runs in a child process with a time limit and a step budget; the
full set is ``campar bench stress`` (see benchmarks/RESULTS.md).
"""

import math

import numpy as np
import pytest

from campar.bench import stress


@pytest.fixture(scope="module")
def rows():
    return stress.measure(
        stress.QUICK_CELLS, (1e-8, 1e-10), budget=200_000, timeout=60.0, check_max=4
    )


@pytest.mark.process  # stress.measure runs cells in a pool of processes
def test_no_hang_no_crash_no_invalid_result(rows):
    for row in rows:
        for r in row.results:
            assert r.outcome not in stress.BAD, (row.cell, row.start, r.outcome, r.detail)


@pytest.mark.process  # stress.measure runs cells in a pool of processes
def test_work_per_cell_is_bounded(rows):
    assert max(r.wall for row in rows for r in row.results) < 20.0
    assert max(int(r.arrays["steps"]) for row in rows for r in row.results) <= 200_000 + 100


@pytest.mark.process  # stress.measure runs cells in a pool of processes
def test_labels_disagree_with_scipy_only_where_flagged_grazing(rows):
    compared = [row for row in rows if "SciPy agrees" in row.scipy or "DISAGREES" in row.scipy]
    # not vacuous: the quick cells include periodic ones SciPy can afford (q5 agrees; the
    # grazing rest on ε = 0 at ω = 0.01 disagrees on p), so a verdict exists to check
    assert len(compared) >= 2, [(row.cell.name, row.scipy) for row in rows]
    assert any("SciPy agrees" in row.scipy for row in compared)
    for row in compared:
        if "DISAGREES" in row.scipy:
            assert "grazing" in stress.flags(row.results[-1]), (row.cell, row.scipy)


def valid_cell(**changes):
    cell = {
        "n": 1,
        "p": 0,
        "kind": 0,
        "status": 0,
        "flags": 0,
        "dc": 0.0,
        "eps_min": 0.1,
        "eps_max": 0.3,
        "pn_max": 1.0,
        "state": np.array([0.1, 0.0]),
    }
    return {**cell, **changes}


@pytest.mark.parametrize(
    "changes, clamp, problem",
    [
        ({}, True, None),
        ({"dc": 1.5}, True, "outside [0, 1]"),
        ({"pn_max": -1.0}, True, "< 0 under the clamp"),
        ({"pn_max": -1.0}, False, None),
        ({"dc": 0.2}, True, "ε > 0 throughout"),
        ({"state": np.array([math.nan, 0.0])}, True, "non-finite"),
        ({"status": 3, "kind": 4}, True, "finite numbers"),
        (
            {
                "status": 3,
                "kind": 4,
                "dc": math.nan,
                "eps_min": math.nan,
                "eps_max": math.nan,
                "pn_max": math.nan,
                "state": np.array([math.nan, math.nan]),
            },
            True,
            None,
        ),
    ],
)
def test_validity_check(changes, clamp, problem):
    found = stress.check(valid_cell(**changes), clamp)
    if problem is None:
        assert found == []
    else:
        assert any(problem in text for text in found), found
