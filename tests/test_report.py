"""The reproduction report: regenerated at small size, its size-independent rows equal the
committed docs/paper.md (full size); the Liouville check and the claim tests' helpers."""

import math
import re
from pathlib import Path

import numpy as np
import pytest

from campar.paper import setups as paper
from campar.paper.claims import average_ranks, rank_correlation
from campar.paper.report import CLAIMS, build_report, divergence_integral, liouville_bound
from campar.views.point import simulate_point

COMMITTED = Path(__file__).resolve().parents[1] / "docs" / "paper.md"
ROW = re.compile(r"^\| ([PETLM]\d+) \| (.*) \|$")
REGENERATE = "docs/paper.md is stale: regenerate it with `campar report docs/paper.md --size full`"


def table_rows(text: str) -> dict[str, list[str]]:
    """Rows of the report's tables by ID: the cells after the ID."""
    rows = {}
    for line in text.splitlines():
        match = ROW.match(line)
        if match:
            rows[match.group(1)] = match.group(2).split(" | ")
    return rows


@pytest.fixture(scope="module")
def regenerated(tmp_path_factory):
    stores = tmp_path_factory.mktemp("stores")
    return build_report("small", stores=stores, log=lambda _: None)


def test_size_independent_rows_equal_the_committed_report(regenerated):
    committed, new = table_rows(COMMITTED.read_text()), table_rows(regenerated)
    assert set(new) == set(committed) == {c.key for c in CLAIMS} | {"L1", "L2"}, REGENERATE
    for key, cells in new.items():
        if key.startswith("M"):  # maps: the claim and its test, not the numbers
            assert cells[:3] == committed[key][:3], f"{key}: {REGENERATE}"
        else:  # points, multipliers, time series, Liouville: computed alike at every size
            assert cells == committed[key], f"{key}: {REGENERATE}"


def test_committed_report_is_the_full_size_one():
    text = COMMITTED.read_text()
    assert "--size full" in text and "400 × 400 cells" in text


def test_every_claim_is_evaluated_under_both_force_laws(regenerated):
    rows = table_rows(regenerated)
    for claim in CLAIMS:
        cells = rows[claim.key]
        assert cells[4] in ("yes", "**no**", "–") and cells[6] in ("yes", "**no**", "–")


@pytest.mark.parametrize("tensile", ["clamp", "allow"])
@pytest.mark.parametrize("omega", [1.162, 1.4301, 3.0])
def test_divergence_integral_gives_the_multipliers_determinant(tensile, omega):
    """Liouville on campar's own orbits: exp(∮ div f dt) = λ1 λ2 ≤ exp(−2ζ n T)."""
    r = simulate_point(omega, mu_kn=0.9, tensile=tensile, rtol=1e-10, multipliers=True,
                       trace=True)  # fmt: skip
    det = np.prod(r.multipliers).real
    assert math.exp(divergence_integral(r)) == pytest.approx(det, rel=1e-3)
    assert det <= liouville_bound(omega, n=r.n)


def test_the_first_quoted_pair_breaks_the_liouville_bound():
    omega, quoted, _ = paper.QUOTED_MULTIPLIERS[0]
    assert (
        (quoted[0] * quoted[1]).real > liouville_bound(omega) == pytest.approx(0.114993, rel=1e-5)
    )


def test_rank_correlation_is_spearmans():
    from scipy.stats import spearmanr

    rng = np.random.default_rng(1)
    x = rng.integers(0, 5, 40).astype(float)
    y = x + rng.normal(0, 2, 40)
    assert rank_correlation(x, y) == pytest.approx(spearmanr(x, y).statistic, abs=1e-12)
    np.testing.assert_array_equal(average_ranks(np.array([3.0, 1.0, 3.0])), [2.5, 1.0, 2.5])
    assert math.isnan(rank_correlation([1.0, 2.0], [2.0, 1.0]))
