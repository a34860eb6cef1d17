"""``campar report``: the reproduction report docs/paper.md, generated, never typed.

For every claim of the paper (``CLAIMS``) the report states the test, campar's
result under both force laws (``tensile: clamp``, the product's definition, and
``tensile: allow``, the paper's literal formula), a status — *reproduced*, *not
reproduced*, *depends on the force law* or *not tested* (with why) — and the
command that reproduces the number. A label claim (rows P) counts only when it
is robust (``campar.paper.robust``). Claims the report does not test are listed
with the reason. A last section states which claims each option of the force
law (duty cycle by force, the paper's literal cam velocity) changes, computed.
A section on jumps, tongues and irreversible transitions counts, from each plane
swept both ways and from its attractor census, what the model gives about the
paper's Figs. 2c–e and 4c–e (``campar.paper.structure_report``).
The Floquet multipliers the paper quotes are checked against Liouville's formula
(``campar.paper.liouville``).

Rows keyed P (points), E (multipliers), T (time series) and L (Liouville) do
not depend on the report's size; M rows (maps) do.
"""

import time

from .. import __version__
from . import setups
from .claim_list import CLAIMS, REPORT
from .claims import (
    LONG_RUN,
    Claim,
    Evidence,
    Verdict,
)
from .liouville import cell, divergence_integral, liouville_bound, liouville_rows, liouville_table
from .robust import NEIGHBOURS, STEP, WIDTH
from .structure_report import structure_section

__all__ = ["CLAIMS", "build_report", "divergence_integral", "liouville_bound", "write_report"]

# The force law's options, each evaluated under the clamp against the clamp's verdicts.
OPTIONS = {
    "duty_cycle: force": {"duty_cycle": "force"},
    "cam_velocity: literal": {"cam_velocity": "literal"},
}
STATUSES = ("reproduced", "not reproduced", "depends on the force law", "not tested")

# -- statuses -----------------------------------------------------------------------------


def status_of(claim: Claim, verdicts: dict[str, Verdict]) -> str:
    """reproduced (under both laws), not reproduced (under neither), depends on the force
    law, or not tested (no test, or neither law's test can decide)."""
    if claim.untested:
        return "not tested"
    decided = {t: v.match for t, v in verdicts.items() if v.match is not None}
    if not decided:
        return "not tested"
    values = set(decided.values())
    if len(values) == 2:
        return "depends on the force law"
    return "reproduced" if values == {True} else "not reproduced"


def status_text(claim: Claim, verdicts: dict[str, Verdict]) -> str:
    status = status_of(claim, verdicts)
    if claim.untested:
        return f"*not tested*: {claim.untested}"
    if status == "not tested":
        return "*not tested*: neither law's test can decide (see the rows' values)"
    undecided = [t for t, v in verdicts.items() if v.match is None]
    text = f"*{status}*"
    if status == "depends on the force law":
        text += " (holds under " + ", ".join(t for t, v in verdicts.items() if v.match) + ")"
    if undecided:
        text += f" ({', '.join(undecided)}: undecided)"
    return text


def evaluate_all(evidence: dict[str, Evidence], keys=None) -> list[tuple[Claim, dict]]:
    out = []
    for claim in CLAIMS:
        if keys is not None and claim.key not in keys:
            continue
        if claim.untested:
            out.append((claim, {t: Verdict("–", None) for t in evidence}))
            continue
        out.append((claim, {t: claim.evaluate(ev) for t, ev in evidence.items()}))
    return out


def mark(match: bool | None) -> str:
    return "yes" if match else "–" if match is None else "**no**"


def claims_table(results) -> list[str]:
    lines = [
        "| ID | source | the paper claims | test | status | campar, clamp (match) | "
        "campar, allow (match) |",
        "|---|---|---|---|---|---|---|",
    ]
    for claim, verdicts in results:
        found = [
            f"{v.found} ({mark(v.match)})" if not claim.untested else "–"
            for v in (verdicts["clamp"], verdicts["allow"])
        ]
        lines.append(
            "| "
            + " | ".join(
                cell(x)
                for x in (
                    claim.key,
                    claim.source,
                    claim.text,
                    claim.test,
                    status_text(claim, verdicts),
                    *found,
                )
            )
            + " |"
        )
    return lines


def tally(results) -> list[str]:
    counts = {s: [] for s in STATUSES}
    for claim, verdicts in results:
        counts[status_of(claim, verdicts)].append(claim.key)
    return [f"- *{s}*: {len(keys)} — {', '.join(keys) or 'none'}" for s, keys in counts.items()]


def law_flags(tensile: str) -> str:
    return "" if tensile == "clamp" else f" --tensile {tensile}"


def command_of(claim: Claim, verdict: Verdict, ev: Evidence) -> str:
    if verdict.command:
        return verdict.command
    if callable(claim.command):
        return claim.command(ev, law_flags(ev.tensile))
    return claim.command.replace("{law}", law_flags(ev.tensile))


def commands(results, evidence) -> list[str]:
    lines = []
    for claim, verdicts in results:
        if claim.untested:
            continue
        clamp, allow = (command_of(claim, verdicts[t], evidence[t]) for t in ("clamp", "allow"))
        if clamp == allow:
            lines.append(f"- {claim.key}: `{clamp}`")
        else:
            lines.append(f"- {claim.key}: clamp `{clamp}`; allow `{allow}`")
    return lines


# -- the options of the force law -----------------------------------------------------------


def option_effects(results, size: str, stores, log=print) -> list[str]:
    """Every tested claim under each option (with the clamp) against the clamp's verdict."""
    base = {claim.key: verdicts["clamp"] for claim, verdicts in results}
    lines = []
    for title, options in OPTIONS.items():
        start = time.perf_counter()
        ev = Evidence("clamp", size, stores, options)
        changed, numbers, same = [], [], []
        for claim in CLAIMS:
            if claim.untested:
                continue
            new, old = claim.evaluate(ev), base[claim.key]
            if new.match != old.match:
                changed.append(
                    f"{claim.key} ({mark(old.match)} → {mark(new.match)}: {cell(new.found)})"
                )
            elif new.found != old.found:
                numbers.append(claim.key)
            else:
                same.append(claim.key)
        log(f"report: option {title} evaluated in {time.perf_counter() - start:.1f} s")
        flag = next(iter(options)).replace("_", "-")
        lines += [
            f"### `{title}` (`campar point … --{flag} {next(iter(options.values()))}`)",
            "",
            f"- verdict changed: {len(changed)}" + ("" if changed else " (none)"),
            *[f"  - {c}" for c in changed],
            f"- numbers changed, verdict the same: {', '.join(numbers) or 'none'}",
            f"- unchanged: {', '.join(same) or 'none'}",
            "",
        ]
    return lines


# -- the document ------------------------------------------------------------------------


def build_report(size: str = "small", stores=None, log=print, options: bool = True) -> str:
    """The whole Markdown document at a size ("small" or "full"); ``options``: include the
    section on the force law's options (it evaluates every claim twice more)."""
    start = time.perf_counter()
    evidence = {t: Evidence(t, size, stores) for t in setups.TENSILE}
    results = evaluate_all(evidence)
    liouville = liouville_rows(evidence)
    grid = setups.plane_job("omega_f0", size).shape
    log(f"report: {len(results)} claims evaluated in {time.perf_counter() - start:.1f} s")
    effects = option_effects(results, size, stores, log) if options else ["(not computed)"]
    structure = structure_section(size, stores, log)
    text = [
        "# Reproduction report: cam with flat-bottomed follower (seed paper)",
        "",
        f"Generated by `campar report <path> --size {size}` (campar {__version__}, maps on "
        f"{grid[0]} × {grid[1]} cells); do not edit by hand, regenerate. Model and "
        "definitions: docs/model.md. Rows P, E, T and L do not depend on the size; rows M "
        "(maps) do. The paper's figures, redrawn from the same computations: `campar gallery "
        "docs/figures --size full` (docs/figures/index.md).",
        "",
        "## Tally",
        "",
        "Each claim is *reproduced* (its test holds under both force laws), *not reproduced* "
        "(under neither), *depends on the force law* (under one), or *not tested* (no test, "
        "with why, or a test that cannot decide at these settings).",
        "",
        *tally(results),
        "",
        "## How campar tests the claims",
        "",
        f"- Maps: the job files `jobs/omega_f0.yaml`, `jobs/mu_kn.yaml`, `jobs/mu_cn.yaml` on "
        f"{grid[0]} × {grid[1]} cells (ω from 6.0 down, the paper's 2-D continuation "
        "`chains: {start: continue}`), run by the sweep runner once per force law.",
        f"- Labels (P1–P6): a label counts only if robust: the same at all "
        f"{2 * NEIGHBOURS + 1} cells ω − {WIDTH:g} … ω + {WIDTH:g} (step {STEP:g}) along the "
        "paper's path — the (ω, μkn) plane's 2-D continuation from its corner (6.0, 0.95) on "
        f"the full grid's spacing (Δω ≈ 0.015) down to ω + {WIDTH:g}, then on along ω — and "
        f"from rest at each of those ω; a quasi-periodic or chaotic label also after {LONG_RUN} "
        "revolutions (fixed transient, then the read window) from the path's states; and it "
        "must be specific: at the paper's other Fig. 6 speeds farther than "
        f"{WIDTH:g} away, where the paper claims a different label, campar's path label must "
        "differ from it (a label that never changes over ω 2.7–3.2 is no evidence for any one "
        "of them). P1 (3-2 at 2.71) and P2 (chaos at 2.709) lie 0.001 apart, inside each "
        "other's neighbourhood: at this width at most one of them can be robust.",
        "- Points (P7, E, L): continuation along ω from 6.0 in steps ≤ 0.005 to the stated "
        "ω; then the orbit is traced from the chain's last state.",
        "- Time series (T): the steady orbit from rest, (y, y') = (0, 0) at θ = 0. The paper "
        "does not give the three f0 of its Fig. 3 nor the μkn, μcn of its Fig. 8; campar uses "
        "f0 = 0.5, 1.5, 2.5 and μkn, μcn = 0.7, 0.8, 0.9 (other parameters at base values "
        "μkn = μcn = 0.8, ζ = 0.2, f0 = 0.5).",
        "- Both force laws: `clamp` (no tensile force, Pn = max(0, …); campar's default) and "
        "`allow` (the paper's literal Hunt–Crossley formula, which can pull). Both with the "
        "duty cycle by separation (ε < 0) and the cam velocity by the chain rule (ω dyc/dθ), "
        "campar's defaults; the last section evaluates the other readings.",
        "- 'increases with' means Spearman ρ ≥ 0.8 over the rows or columns of a map, or a "
        "strictly monotone sequence over the three values of a time-series figure.",
        "",
        "## Claims",
        "",
        *claims_table(results),
        "",
        "## Commands that reproduce each row's numbers",
        "",
        f"Every row is also reproduced by `{REPORT}` (P, E, T, L rows at any size). "
        "`--y0 --v0` give the state the stated path reaches, so one `campar point` reproduces "
        "the path's cell.",
        "",
        *commands(results, evidence),
        "",
        "## What the force law's options change",
        "",
        "Every tested claim evaluated again under the clamp with one option changed "
        "(docs/model.md): `duty_cycle: force` counts the time with Pn = 0 (separated, or in "
        "contact with the clamp holding the force at zero) instead of ε < 0; "
        "`cam_velocity: literal` takes the cam's velocity in the force's ε' as the paper's "
        "eq. 6 prints it, dyc/dθ without the factor ω. Maps at the report's size; compared "
        "with the clamp column above.",
        "",
        *effects,
        *structure,
        "## Liouville check of the quoted Floquet multipliers",
        "",
        "For the flow of y'' + 2ζy' + y = Pn − f0 the divergence is div f = −2ζ − k c ε^{3/2} "
        "in pushing contact and −2ζ otherwise (k = μkn/(1−μkn), c = 2ζμcn/(1−μcn)), never "
        "above −2ζ. The paper's map runs from one detachment to the next over n ≥ 1 "
        "revolutions (t = 2nπ/ω), so the product of its two eigenvalues must equal "
        "det DP = exp(∮ div f dt) ≤ exp(−4πζn/ω) ≤ exp(−4πζ/ω), whatever the orbit, the "
        "section or the force law. campar's column gives exp(∮ div f dt) integrated along "
        "its orbit at the stated ω (μkn = 0.90, continuation) and, independently, the product "
        "of its own multipliers from the variational equations. (A map between consecutive "
        "detachments of an n-p cycle with p > 1 has no fixed point; the cycle's eigenvalues "
        "are those of the whole period, so n ≥ 1 holds there too.)",
        "",
        *liouville_table(liouville),
        "",
        "Besides, neither quoted pair shows the bifurcation the paper names: a period "
        "doubling needs a real multiplier at −1 (the first pair is complex with "
        f"|λ| = {abs(setups.QUOTED_MULTIPLIERS[0][1][0]):.3f}), and two real multipliers "
        "inside the unit circle (the second pair) belong to a stable cycle, not to the "
        "onset of chaos.",
        "",
    ]
    return "\n".join(text)


def write_report(path, size: str = "small", stores=None, log=print):
    from pathlib import Path

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(build_report(size, stores, log))
    log(f"wrote {path}")
    return path
