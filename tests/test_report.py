"""The reproduction report, its rows checked against evidence from outside campar.

Rows P, E, T and L do not depend on the report's size, so they are checked on a report
regenerated with tiny planes (never against the committed docs/paper.md):
T and P rows against SciPy DOP853 orbits from rest (campar.bench.scipy_model, written
without campar's code), L rows against Liouville's formula in closed form, E rows
against the L rows' independent route to det DP (∮ div f along the orbit). M rows
(maps) depend on the size and are not checked here. Also the Liouville check and the
claim tests' helpers."""

import math
import re
from functools import cache

import numpy as np
import pytest
from support.jobs import reference_case

from campar.bench.scipy_model import Model, integrate
from campar.bench.scipy_peer import scipy_cell
from campar.paper import continued
from campar.paper import report as report_module
from campar.paper import setups as paper
from campar.paper.claims import average_ranks, rank_correlation
from campar.paper.report import CLAIMS, build_report, divergence_integral, liouville_bound
from campar.views.point import simulate_point

ROW = re.compile(r"^\| ([PETLMN]\d+) \| (.*) \|$")
ZETA = 0.2  # the paper's base ζ (MODEL.md), at which every P, E, T and L row is computed
# The Floquet multipliers the paper quotes (its Fig. 5b1, μkn = 0.90), by ω.
QUOTED = {
    1.162: (complex(-0.354351, 0.263715), complex(-0.354351, -0.263715)),
    1.4301: (complex(0.263516, 0.0), complex(0.374650, 0.0)),
}
# columns of a claim row after its ID: source, claim, test, status, clamp (match), allow (match)
FOUND = {"clamp": 4, "allow": 5}
MATCH = re.compile(r"^(.*) \((yes|\*\*no\*\*|–)\)$")


def table_rows(text: str) -> dict[str, list[str]]:
    """Rows of the report's tables by ID: the cells after the ID."""
    rows = {}
    for line in text.splitlines():
        match = ROW.match(line)
        if match:
            rows[match.group(1)] = match.group(2).split(" | ")
    return rows


def mark(match: bool) -> str:
    return "yes" if match else "**no**"


def found(row: list[str], tensile: str) -> tuple[str, str]:
    """(what campar found, its match mark) of a claim row under a force law."""
    m = MATCH.match(row[FOUND[tensile]])
    assert m, row[FOUND[tensile]]
    return m.group(1), m.group(2)


def number(text: str) -> float:
    return float(text.replace("−", "-"))


@pytest.fixture(scope="module")
def regenerated(tmp_path_factory):
    """The report with 6 × 6 planes and no continued curves (only its M and N2 rows
    depend on them, and a curve seeded on so coarse a map locates its point across a whole
    cell, most of the report's cost; a map's curves are checked in test_map_curves.py,
    the gallery zooms' in test_attractor_figures.py),
    without the section that evaluates every claim again under the options, and with a
    stand-in for the section on attractor structure (its rows are not claims; its numbers
    are checked against the raw arrays in test_attractor_figures.py)."""
    stores = tmp_path_factory.mktemp("stores")
    with pytest.MonkeyPatch.context() as patch:
        patch.setitem(paper.SIZES, "small", paper.Size(plane=6, line=60))
        patch.setattr(continued, "map_curves", lambda ev, plane: [])
        patch.setattr(report_module, "structure_section", lambda size, stores, log: [STRUCTURE])
        return build_report("small", stores=stores, log=lambda _: None, options=False)


STRUCTURE = "the section on attractor structure"


@pytest.mark.slow  # the report of two tiny planes, computed once a module
def test_the_report_holds_the_section_on_attractor_structure(regenerated):
    assert STRUCTURE in regenerated.splitlines()


@pytest.fixture
def report(regenerated) -> dict[str, list[str]]:
    return table_rows(regenerated)


@cache
def steady_from_rest(omega: float, tensile: str, **params) -> tuple:
    """SciPy's steady orbit from (y, y') = (0, 0) at θ = 0 (the reference cells' recipe:
    revolutions until the section repeats, at most 500): (n, p, DC, a point of the cycle)."""
    model = Model(omega, clamp=tensile == "clamp", zeta=ZETA, **params)
    x = (0.0, 0.0)
    for _ in range(500 // 20):
        cell = scipy_cell(model, x, 0, 20, rtol=1e-9)
        if cell.n:
            return cell.n, cell.p, cell.dc, cell.sections[-1]
        x = tuple(cell.sections[-1])
    return 0, 0, math.nan, x


@pytest.mark.slow  # the report of two tiny planes, computed once a module
def test_every_claim_and_quoted_pair_has_a_row(report):
    assert set(report) == {c.key for c in CLAIMS} | {"L1", "L2"}
    for claim in CLAIMS:
        assert len(report[claim.key]) == 6, claim.key
        status = report[claim.key][3]
        assert status.startswith(
            ("*reproduced*", "*not reproduced*", "*depends on the force law*", "*not tested*")
        ), claim.key
        if claim.untested:  # listed, with why, never marked
            assert status == f"*not tested*: {claim.untested}", claim.key


@pytest.mark.slow  # the report of two tiny planes, computed once a module
def test_liouville_rows_obey_the_closed_form_bound(report):
    """λ1λ2 of a return map over n revolutions is exp(∮ div f dt) ≤ exp(−4πζn/ω)."""
    for key in ("L1", "L2"):
        omega, _, product, bound, *models, verdict = report[key]
        omega = float(omega)
        quoted = np.prod(QUOTED[omega]).real
        closed_form = math.exp(-4 * math.pi * ZETA / omega)
        assert number(product) == pytest.approx(quoted, abs=5e-5)
        assert number(bound) == pytest.approx(closed_form, abs=5e-5)
        assert verdict.startswith("**impossible**") == (quoted > closed_form), key
        for model in models:  # label, exp(∮ div f dt), λ1λ2 of campar's multipliers
            label, via_divergence, via_multipliers = model.split(", ")
            n = int(label.split("-")[0])
            assert number(via_divergence) == pytest.approx(number(via_multipliers), rel=2e-3)
            assert 0 < number(via_multipliers) <= math.exp(-4 * math.pi * ZETA * n / omega)
    assert report["L1"][-1].startswith("**impossible**")  # 0.1951 > exp(−4π 0.2/1.162)


def multipliers(text: str) -> list[complex]:
    """λ of an E row's found cell, e.g. "1-2: λ = -0.0331 + 0.0145i, -0.0331 − 0.0145i"."""
    values = []
    for part in text.split("λ = ")[1].split(", "):
        m = re.fullmatch(r"(\S+)(?: ([+−]) (\S+)i)?", part)
        im = number(m.group(3)) * (1 if m.group(2) == "+" else -1) if m.group(2) else 0.0
        values.append(complex(number(m.group(1)), im))
    return values


@pytest.mark.parametrize("tensile", ["clamp", "allow"])
@pytest.mark.slow  # the report of two tiny planes, computed once a module
def test_multiplier_rows_have_the_determinant_of_the_liouville_rows(report, tensile):
    """E rows: campar's multipliers from the variational equations; L rows: exp(∮ div f dt)
    integrated along the same orbit. Liouville's formula makes λ1λ2 equal to it."""
    column = {"clamp": 4, "allow": 5}[tensile]  # of the L row: label, exp(∮ div f), λ1λ2
    for e, l_row in (("E1", "L1"), ("E2", "L2")):
        text, match = found(report[e], tensile)
        label, via_divergence, _ = report[l_row][column].split(", ")
        assert text.startswith(label + ":")
        lam = multipliers(text)
        assert np.prod(lam).real == pytest.approx(number(via_divergence), rel=2e-3)
        # the claim: within 0.01 of the paper's quoted pair
        close = np.allclose(
            sorted(lam, key=abs), sorted(QUOTED[float(report[l_row][0])], key=abs), atol=0.01
        )
        assert match == mark(close)


def series(text: str) -> dict[str, list[float]]:
    """ "f0=0.5: 0.0987/0.48/0.494; f0=1.5: …" → {"f0=0.5": [0.0987, 0.48, 0.494], …}"""
    return {
        head: [number(v) for v in values.split(" ")[0].split("/")]
        for head, values in (part.split(": ") for part in text.split("; "))
    }


@pytest.mark.parametrize("tensile", ["clamp", "allow"])
@pytest.mark.slow  # the report of two tiny planes, computed once a module
def test_duty_cycle_trend_and_detachment_angles_agree_with_scipy(report, tensile):
    """T3 (DC over ω = 1, 3, 5 for each f0) and T11 (cam angle of every detachment at
    f0 = 0.5) from SciPy orbits from rest."""
    dc = series(found(report["T3"], tensile)[0])
    increasing = []
    for f0 in paper.FIG3_F0:
        ours = dc[f"f0={f0:g}"]
        theirs = [steady_from_rest(omega, tensile, f0=f0)[2] for omega in paper.SPEEDS]
        np.testing.assert_allclose(ours, theirs, rtol=5e-3, atol=1e-6, err_msg=f"f0={f0}")
        increasing.append(bool(np.all(np.diff(theirs) > 0)))
    assert found(report["T3"], tensile)[1] == mark(all(increasing))
    angles = dict(
        part.split(": ")
        for part in found(report["T11"], tensile)[0].split("detachment ")[1].split("; ")
    )
    for omega in paper.SPEEDS:
        n, p, _, x = steady_from_rest(omega, tensile, f0=paper.FIG9_F0)
        model = Model(omega, f0=paper.FIG9_F0, zeta=ZETA, clamp=tensile == "clamp")
        _, events, _ = integrate(model, x, n, rtol=1e-10, atol=1e-12)
        times = [t for t, kind in events if kind == "detachment"]
        assert len(times) == p
        theirs = np.degrees((omega * np.array(times)) % (2 * math.pi))
        ours = [float(a.rstrip("°")) for a in angles[f"ω={omega:g}"].split(", ")]
        np.testing.assert_allclose(sorted(ours), sorted(theirs), atol=0.51, err_msg=f"ω={omega}")


@pytest.mark.parametrize("tensile", ["clamp", "allow"])
@pytest.mark.slow  # the report of two tiny planes, computed once a module
def test_point_rows_from_rest_agree_with_scipy(report, tensile):
    """P rows' label from rest at μkn = 0.91 (the claimed ω, the centre of the row's
    neighbourhood), from SciPy orbits from rest (and P5 under the clamp from reference
    cell 112)."""
    labels = {}
    for key, (omega, _) in zip(
        ("P1", "P2", "P3", "P4", "P5", "P6"), paper.FIG6_CLAIMS, strict=True
    ):
        labels[key] = re.search(r"^path \S+, rest ([^;]+);", report[key][FOUND[tensile]]).group(1)
        n, p, _, _ = steady_from_rest(omega, tensile, mu_kn=paper.FIG6_MU_KN)
        if re.fullmatch(r"\d+-\d+", labels[key]):  # a cycle: SciPy reaches the same n-p
            assert labels[key] == f"{n}-{p}", (key, omega)
        else:  # chaos, QP: SciPy finds no cycle in 500 revolutions
            assert n == 0, (key, omega, f"{n}-{p}")
    if tensile == "clamp":
        case = reference_case(112)
        assert (case["omega"], case["mu_kn"], case["clamp"]) == (3.15, 0.91, True)
        assert labels["P5"] == case["expected"]["label"]


@pytest.mark.parametrize("tensile", ["clamp", "allow"])
@pytest.mark.parametrize("omega", [1.162, 1.4301, 3.0])
def test_divergence_integral_gives_the_multipliers_determinant(tensile, omega):
    """Liouville on campar's own orbits: exp(∮ div f dt) = λ1 λ2 ≤ exp(−2ζ n T)."""
    r = simulate_point(omega, mu_kn=0.9, tensile=tensile, rtol=1e-10, multipliers=True, trace=True)
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
