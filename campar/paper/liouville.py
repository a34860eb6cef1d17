"""The Liouville check of the Floquet multipliers the paper quotes (docs/paper.md, rows L).

For the flow of y'' + 2ζy' + y = Pn − f0 the Jacobian of a return map over time T has

    det DP = exp(∮ div f dt),   div f = −2ζ − k c ε^{3/2} in pushing contact, −2ζ otherwise,

so λ1 λ2 ≤ exp(−2ζ T) for every orbit, and equals exp(∮ div f dt) along it.
"""

import math

import numpy as np

from ..core.model import make_params
from ..sweep.job import PAPER_VALUES
from . import setups
from .claims import Evidence, complex_text, fmt


def cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def divergence_integral(result) -> float:
    """∮ div f dt along a result's traced orbit (trapezoid rule on its dense samples)."""
    par = result.parameters
    zeta = par["zeta"]
    # The contact stiffness k and damping c as the model derives them from μkn, μcn, ζ.
    p = make_params(
        par["omega"], zeta, par["f0"], par["mu_kn"], par["mu_cn"], par["tensile"] == "clamp"
    )
    tr = result.trace
    # Samples inside a step share its contact mode, and a step ends on every mode switch,
    # so the interval (t_i, t_i+1] lies in the mode of sample i+1: evaluating both ends in
    # that mode keeps the jump of div f at a switch out of the trapezoids.
    pushing = tr.contact[1:] == 1
    depth = np.clip(tr.eps, 0.0, None) ** 1.5
    left = np.where(pushing, depth[:-1], 0.0)
    right = np.where(pushing, depth[1:], 0.0)
    contact = 0.5 * np.sum((left + right) * np.diff(tr.t))
    return float(-2.0 * zeta * (tr.t[-1] - tr.t[0]) - p.k * p.c * contact)


def liouville_bound(omega: float, zeta: float = PAPER_VALUES["zeta"], n: int = 1) -> float:
    """Largest det DP any orbit of n revolutions can have: div f ≤ −2ζ everywhere."""
    return math.exp(-2.0 * zeta * n * 2.0 * math.pi / omega)


def liouville_rows(evidence: dict[str, Evidence]) -> list[dict]:
    rows = []
    for omega, quoted, conclusion in setups.QUOTED_MULTIPLIERS:
        product = (quoted[0] * quoted[1]).real
        row = {
            "omega": omega,
            "quoted": quoted,
            "conclusion": conclusion,
            "product": product,
            "bound": liouville_bound(omega),
            "models": {},
        }
        for tensile, ev in evidence.items():
            r = ev.continued(omega, setups.QUOTED_MU_KN).result
            if r.kind != "periodic" or r.trace is None:
                row["models"][tensile] = (r.label, math.nan, math.nan, math.nan)
                continue
            det = float(np.prod(r.multipliers).real)
            row["models"][tensile] = (
                r.label,
                math.exp(divergence_integral(r)),
                det,
                liouville_bound(omega, n=r.n),
            )
        rows.append(row)
    return rows


def liouville_verdict(row: dict) -> str:
    if row["product"] > row["bound"]:
        return (
            f"**impossible**: λ1λ2 = {row['product']:.4f} exceeds exp(−4πζ/ω) = "
            f"{row['bound']:.4f}, the largest det DP of any orbit of this flow"
        )
    found = [m for m in row["models"].values() if math.isfinite(m[1])]
    near = [m for m in found if abs(row["product"] - m[1]) <= 0.05 * m[1]]
    if near:
        return "consistent with campar's orbit (within 5 %)"
    return (
        f"allowed by the bound ({row['bound']:.4f}) but not the det DP of campar's orbit "
        "under either force law"
    )


def liouville_table(rows) -> list[str]:
    lines = [
        "| ID | ω | quoted λ1, λ2 (the paper's conclusion) | λ1λ2 | bound exp(−4πζ/ω) | "
        "campar clamp: label, exp(∮div f), λ1λ2 | campar allow: label, exp(∮div f), λ1λ2 | "
        "verdict |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for i, row in enumerate(rows):
        quoted = ", ".join(complex_text(z) for z in row["quoted"])
        models = [
            f"{m[0]}, {fmt(m[1], 4)}, {fmt(m[2], 4)}"
            for m in (row["models"][t] for t in setups.TENSILE)
        ]
        fields = (
            f"L{i + 1}",
            f"{row['omega']}",
            f"{quoted} ({row['conclusion']})",
            f"{row['product']:.4f}",
            f"{row['bound']:.4f}",
            *models,
            liouville_verdict(row),
        )
        lines.append("| " + " | ".join(cell(x) for x in fields) + " |")
    return lines
