"""The rules that decide a claim's status, on synthetic data where the answer is known.

A label claim is reproduced only if robust (campar.paper.robust.judge_label): one lucky
cell, a label that holds only along the path or only from rest, a quasi-periodic label a
long run does not confirm, or a label that never changes, must not count.
"""

from types import SimpleNamespace

import numpy as np
import pytest

from campar.paper import robust
from campar.paper.claims import Claim, Verdict
from campar.paper.report import status_of
from campar.paper.robust import NEIGHBOURS, STEP, WIDTH, Neighbourhood, judge_label

OMEGA0 = 3.0
CELLS = 2 * NEIGHBOURS + 1


def hood(path, rest=None, long=(), omega0=OMEGA0) -> Neighbourhood:
    omegas = tuple(omega0 + (NEIGHBOURS - i) * STEP for i in range(CELLS))
    rest = path if rest is None else rest
    return Neighbourhood(
        omega0, omegas, tuple(path), tuple(rest), ((0.0, 0.0),) * CELLS, tuple(long)
    )


def around(centre: str, others: str) -> list[str]:
    """``centre`` at the claimed ω only, ``others`` at the other cells."""
    return [centre if i == NEIGHBOURS else others for i in range(CELLS)]


def test_the_neighbourhood_is_two_cells_of_step_on_either_side():
    assert NEIGHBOURS == 2 and abs(WIDTH - 2 * STEP) < 1e-15 and CELLS == 5


def test_a_label_holding_around_the_claimed_speed_is_reproduced():
    ok, reasons = judge_label("2-2", hood(["2-2"] * CELLS), [(2.83, "4-4", "4-4")])
    assert ok and reasons == []


def test_a_single_lucky_cell_does_not_count():
    lucky = around("2-2", "1-1")
    ok, reasons = judge_label("2-2", hood(lucky), [])
    assert not ok and "path: 1/5 cells 2-2" in reasons[0]
    # lucky along the path only, or from rest only
    assert not judge_label("2-2", hood(["2-2"] * CELLS, rest=lucky), [])[0]
    assert not judge_label("2-2", hood(lucky, rest=["2-2"] * CELLS), [])[0]
    # one cell off at the neighbourhood's edge is enough to fail
    edge = ["1-1"] + ["2-2"] * (CELLS - 1)
    assert not judge_label("2-2", hood(edge), [])[0]


def test_a_label_that_never_changes_is_not_specific():
    everywhere = hood(["2-2"] * CELLS)
    # the paper claims 4-4 at 2.83 and 1-1 at 3.15; campar has 2-2 there too
    ok, reasons = judge_label("2-2", everywhere, [(2.83, "4-4", "2-2"), (3.15, "1-1", "2-2")])
    assert not ok and reasons[0].startswith("not specific") and "ω = 2.83" in reasons[0]
    # a rival inside the neighbourhood is the neighbourhood's business, not specificity's
    assert judge_label("2-2", everywhere, [(OMEGA0 + 0.001, "chaos", "2-2")])[0]
    # where campar's label does change as the paper's does, the claim stands
    assert judge_label("2-2", everywhere, [(2.83, "4-4", "2-4"), (3.15, "1-1", "1-1")])[0]


def test_a_quasi_periodic_label_needs_the_long_run_to_agree():
    qp = ["QP"] * CELLS
    assert judge_label("QP", hood(qp, long=qp), [])[0]
    ok, reasons = judge_label("QP", hood(qp, long=around("QP", "2-1")), [])
    assert not ok and reasons[0].startswith(f"{robust.LONG_RUN} revolutions")
    assert not judge_label("QP", hood(qp), [])[0]  # no long run: no verdict for it
    assert not judge_label("chaos", hood(["chaos"] * CELLS, long=["2-2"] * CELLS), [])[0]


def claim(untested: str = "") -> Claim:
    return Claim("X1", "Fig. 0", "a claim", "a test", None, untested=untested)


@pytest.mark.parametrize(
    "clamp, allow, status",
    [
        (True, True, "reproduced"),
        (False, False, "not reproduced"),
        (True, False, "depends on the force law"),
        (False, True, "depends on the force law"),
        (True, None, "reproduced"),
        (None, False, "not reproduced"),
        (None, None, "not tested"),
    ],
)
def test_status_from_the_two_force_laws(clamp, allow, status):
    verdicts = {"clamp": Verdict("", clamp), "allow": Verdict("", allow)}
    assert status_of(claim(), verdicts) == status


def test_a_claim_without_a_test_is_not_tested_whatever_the_verdicts():
    verdicts = {"clamp": Verdict("", True), "allow": Verdict("", True)}
    assert status_of(claim("no test of the shapes"), verdicts) == "not tested"


class SyntheticEvidence:
    """Evidence whose every computation reads a synthetic line: ``path(ω)`` is the label the
    paper's path reaches at ω, ``rest(ω)`` the label from rest (no kernel runs)."""

    tensile, options = "clamp", {}

    def __init__(self, path, rest=None):
        self.path_label, self.rest_label = path, rest or path
        self._kept = {}

    def _keep(self, key, compute):
        return self._kept.setdefault(key, compute())

    def path_row(self, second, low, plane=None):
        return SimpleNamespace(state=np.array([[0.1, -0.2]]))

    def line(self, omega, points, **options):
        w = np.linspace(max(omega), min(omega), points)
        return SimpleNamespace(
            omega=w, state=np.zeros((points, 2)), labels=[self.path_label(x) for x in w]
        )

    def rest(self, omega, **params):
        return SimpleNamespace(label=self.rest_label(omega), kind="periodic", multipliers=())

    def long_run(self, omega, state, **params):
        return SimpleNamespace(label=self.path_label(omega))

    def fine_line(self, mu_kn):
        return self.line((6.0, 2.0), 4001)


def window(label, lo, hi, other="1-1"):
    return lambda w: label if lo <= w <= hi else other


@pytest.mark.parametrize(
    "path, rest, reproduced",
    [
        (window("2-2", 2.95, 3.05), None, True),  # robust, and 1-1 at the other speeds
        (window("2-2", 2.9995, 3.0005), None, False),  # one lucky cell at ω = 3.0
        (window("2-2", 2.95, 3.05), window("2-2", 2.9995, 3.0005), False),  # lucky from rest
        (lambda w: "2-2", None, False),  # 2-2 everywhere: not specific
    ],
)
def test_label_claims_run_the_neighbourhood_rule(path, rest, reproduced):
    verdict = robust.label_claim(3.0, "2-2")(SyntheticEvidence(path, rest))
    assert verdict.match is reproduced, verdict.found
    assert "--omega 3 --mu-kn 0.91 --y0" in verdict.command
