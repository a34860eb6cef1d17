"""Every cell of tests/data/reference_cases.json (SciPy DOP853 at rtol 1e-10).

n-p exact, duty cycle and ε extremes within 0.0025, Pn max within 1 %, from
both the stated and the alternative initial state.
"""

import json

import pytest
from support.jobs import REFERENCE_CASES

from campar import simulate_point

CASES = json.loads(REFERENCE_CASES.read_text())["cases"]


def runs():
    for case in CASES:
        yield pytest.param(case, case["initial_state"], case["expected"], id=f"{case['id']}")
        yield pytest.param(
            case, case["alt_initial_state"], case["alt_expected"], id=f"{case['id']}-alt"
        )


@pytest.mark.parametrize("case, start, expected", list(runs()))
@pytest.mark.parametrize("transient", ["converged", "fixed"])
def test_reference_cell(case, start, expected, transient):
    result = simulate_point(
        case["omega"],
        f0=case["f0"],
        mu_kn=case["mu_kn"],
        mu_cn=case["mu_cn"],
        zeta=case["zeta"],
        tensile="clamp" if case["clamp"] else "allow",
        y0=start["y"],
        v0=start["yd"],
        transient=transient,
        revolutions=500 if transient == "converged" else 300,
        rtol=1e-9,
    )
    assert result.status == "ok"
    assert result.label == expected["label"]
    assert result.dc == pytest.approx(expected["DC"], abs=0.0025)
    if "eps_min" in expected:
        assert result.eps_min == pytest.approx(expected["eps_min"], abs=0.0025)
        assert result.eps_max == pytest.approx(expected["eps_max"], abs=0.0025)
        assert result.pn_max == pytest.approx(expected["Pn_max"], rel=0.01)
