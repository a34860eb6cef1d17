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
from . import continued, setups
from . import map_claims as mc
from .claims import (
    LONG_RUN,
    Claim,
    Evidence,
    Verdict,
    detachment_phases,
    fig3,
    fig8,
    force_peak_phase,
    multiplier_claim,
    never_fully_detached,
    series_trend,
    speed_trend,
    stiffness_beats_damping,
)
from .liouville import cell, divergence_integral, liouville_bound, liouville_rows, liouville_table
from .robust import NEIGHBOURS, STEP, WIDTH, label_claim
from .structure_report import structure_section

__all__ = ["CLAIMS", "build_report", "divergence_integral", "liouville_bound", "write_report"]

F6 = "Fig. 6 / 5c"
REPORT = "campar report docs/paper.md --size full"
# The force law's options, each evaluated under the clamp against the clamp's verdicts.
OPTIONS = {
    "duty_cycle: force": {"duty_cycle": "force"},
    "cam_velocity: literal": {"cam_velocity": "literal"},
}
STATUSES = ("reproduced", "not reproduced", "depends on the force law", "not tested")


def continued_command(omega: float, mu_kn: float):
    """The commands of a point reached by continuation along ω from 6.0 (Evidence.continued)."""

    def command(ev: Evidence, law: str) -> str:
        line = ev.continued(omega, mu_kn).line
        y, v = line.state[-1]
        return (
            f"campar line --omega {omega:g}:6 --points {len(line.omega)} --mu-kn {mu_kn:g}"
            f"{law} (the continuation), then campar point --omega {omega:g} --mu-kn "
            f"{mu_kn:g} --y0 {y:.9g} --v0 {v:.9g} --multipliers{law}"
        )

    return command


SPEEDS = "W in 1, 3, 5"
FIG3 = f"campar point --omega W --f0 F{{law}} ({SPEEDS}, F in 0.5, 1.5, 2.5; from rest)"
FIG8 = "campar point --omega W --f0 2.5 --{name} M{{law}} (" + SPEEDS + ", M in 0.7, 0.8, 0.9)"
FIG9 = f"campar point --omega W --f0 0.5 --plot pn-W.png{{law}} ({SPEEDS}: Pn, yc, events)"


def map_command(plane: str, what: str = "labels") -> str:
    return (
        f"campar run jobs/{plane}.yaml (allow: model.tensile: allow in a copy), then "
        f"campar plot results/{plane}.zarr --what {what}; the number: {REPORT}"
    )


def _claims() -> list[Claim]:
    rows = [
        Claim(
            f"P{i + 1}",
            F6,
            f"μkn = 0.91, ω = {omega}: {label}",
            f"robust label: the same at all {2 * NEIGHBOURS + 1} cells ω ± {WIDTH:g} (step "
            f"{STEP:g}) along the paper's path and from rest; a QP/chaos label also after "
            f"{LONG_RUN} revolutions; and not campar's label at the paper's other Fig. 6 "
            "speeds where it claims another label",
            label_claim(omega, label),
        )
        for i, (omega, label) in enumerate(setups.FIG6_CLAIMS)
    ]
    w1, w2 = setups.QUOTED_MULTIPLIERS[0][0], setups.QUOTED_MULTIPLIERS[1][0]
    mu = setups.QUOTED_MU_KN
    rows += [
        Claim(
            "P7",
            "text on Figs. 4d, 5c",
            "μkn = 0.91: Hopf (Neimark–Sacker) bifurcation of the period-1 motion at ω = 3.208583",
            "an NS point (a complex pair of "
            "multipliers crossing the unit circle, located on the cycles themselves) on any "
            "branch between ω 3.1 and 3.3: every periodic attractor of the paper's path and "
            "of a census of 8 starts at 9 speeds, continued over ω 2…6 with switching",
            continued.ns_claim,
            command=continued.structure_command,
        ),
        Claim(
            "E1",
            "Fig. 5b1",
            f"μkn = 0.90, ω = {w1}: λ1,2 = −0.354351 ± 0.263715i, "
            "'satisfies the period-doubling condition'",
            "campar's multipliers at ω (continuation) within 0.01 of the quoted ones",
            multiplier_claim(0),
            command=continued_command(w1, mu),
        ),
        Claim(
            "E2",
            "Fig. 5b1",
            f"μkn = 0.90, ω = {w2}: λ = 0.263516, 0.374650, 'the system becomes chaotic'",
            "as E1",
            multiplier_claim(1),
            command=continued_command(w2, mu),
        ),
        Claim(
            "T1",
            "Fig. 3",
            "intrusion depth max ε grows with preload f0",
            "max ε strictly increasing over f0 = 0.5, 1.5, 2.5 at each ω = 1, 3, 5 (from rest)",
            series_trend(fig3, "eps_max", 1),
            command=FIG3,
        ),
        Claim(
            "T2",
            "Fig. 3",
            "detachment height (−min ε) falls as f0 grows",
            "min ε strictly increasing over f0 at each ω where all three orbits detach",
            series_trend(fig3, "eps_min", 1, only_detached=True),
            command=FIG3,
        ),
        Claim(
            "T3",
            "Fig. 3",
            "contact turns into detachment as ω grows",
            "duty cycle strictly increasing over ω = 1, 3, 5 for each f0",
            speed_trend("dc"),
            command=FIG3,
        ),
        Claim(
            "T4",
            "Fig. 3, conclusion",
            "intrusion depth grows with cam speed",
            "max ε strictly increasing over ω = 1, 3, 5 for each f0",
            speed_trend("eps_max"),
            command=FIG3,
        ),
        Claim(
            "T5",
            "Fig. 3",
            "the follower is never separated for a whole revolution",
            "every revolution of every Fig. 3 orbit has ε > 0 somewhere; undecided where "
            "every orbit is a 1-cycle in contact (then it cannot fail)",
            never_fully_detached,
            command=FIG3.replace("(", "--plot orbit.png ("),
        ),
        Claim(
            "T6",
            "Fig. 8",
            "raising μkn reduces the intrusion depth (f0 = 2.5)",
            "max ε strictly decreasing over μkn = 0.7, 0.8, 0.9 at each ω",
            series_trend(lambda ev, w: fig8(ev, w, "mu_kn"), "eps_max", -1),
            command=FIG8.format(name="mu-kn"),
        ),
        Claim(
            "T7",
            "Fig. 8",
            "raising μcn reduces the intrusion depth (f0 = 2.5)",
            "max ε strictly decreasing over μcn = 0.7, 0.8, 0.9 at each ω",
            series_trend(lambda ev, w: fig8(ev, w, "mu_cn"), "eps_max", -1),
            command=FIG8.format(name="mu-cn"),
        ),
        Claim(
            "T8",
            "Fig. 8",
            "detachment height grows with μkn",
            "min ε strictly decreasing over μkn at each ω where all three orbits detach",
            series_trend(lambda ev, w: fig8(ev, w, "mu_kn"), "eps_min", -1, True),
            command=FIG8.format(name="mu-kn"),
        ),
        Claim(
            "T9",
            "Fig. 8",
            "detachment height grows with μcn",
            "as T8 over μcn",
            series_trend(lambda ev, w: fig8(ev, w, "mu_cn"), "eps_min", -1, True),
            command=FIG8.format(name="mu-cn"),
        ),
        Claim(
            "T10",
            "Fig. 8, conclusion",
            "raising μkn reduces the intrusion depth more than raising μcn",
            "drop of max ε from 0.7 to 0.9 larger for μkn than for μcn at each ω",
            stiffness_beats_damping,
            command=FIG8.format(name="mu-kn / --mu-cn"),
        ),
        Claim(
            "T11",
            "Fig. 9, conclusion",
            "detachment happens at the beginning of the far "
            "dwell or from the fall to the near dwell (f0 = 0.5)",
            "every detachment at cam "
            "angle θ ∈ [60°, 90°] (the far dwell's first 30°) or θ ∈ [210°, 270°] (the fall's "
            "last 30°, the near dwell's first 30°), ω = 1, 3, 5 (from rest); the windows "
            "cover 90° of 360°",
            detachment_phases,
            command=FIG9,
        ),
        Claim(
            "T12",
            "Fig. 9, conclusion",
            "Pn is largest at the end of the rise",
            "θ at max Pn within 10° of 60°, ω = 1, 3, 5",
            force_peak_phase,
            command=FIG9,
        ),
    ]
    maps = [
        (
            "M1",
            "Fig. 2",
            "very low ω: 1-0 motion with DC = 0",
            "≥ 95 % of the cells with ω ≤ 0.3 on the (ω, f0) plane are 1-0 with DC = 0",
            mc.lowest_speeds_rest,
            "omega_f0",
        ),
        (
            "M2",
            "Fig. 2",
            "ω < 1: mainly 1-p and chattering 1-p̃ motion",
            "≥ 50 % of the cells with ω < 1 are 1-p with p ≥ 1",
            mc.low_speeds_period_one,
            "omega_f0",
        ),
        (
            "M3",
            "Fig. 2b",
            "ω > 5: DC approaches 1",
            "median DC of the cells with ω > 5 ≥ 0.9",
            mc.high_speed_dc,
            "omega_f0",
        ),
        (
            "M4",
            "Fig. 2b",
            "the higher the preload f0, the smaller DC",
            "Spearman ρ(f0, row-mean DC) ≤ −0.8",
            mc.dc_trend_second("omega_f0", -1),
            "omega_f0",
        ),
        (
            "M5",
            "Fig. 2b",
            "DC increases with ω",
            "ρ(ω, column-mean DC) ≥ 0.8",
            mc.dc_trend_speed,
            "omega_f0",
        ),
        (
            "M6",
            "Fig. 4",
            "n-0 lies at very small ω or small μkn",
            "n-0 at ω ≤ 1 is M1 again; "
            "so: n-0 cells at ω > 1 exist and ≥ 90 % of them lie at μkn < 0.8",
            mc.rest_region,
            "mu_kn",
        ),
        (
            "M7",
            "Fig. 4",
            "subharmonic n-0 (n ≥ 2) exist for μkn < 0.8 and vanish for μkn > 0.8",
            "n-0 cells with n ≥ 2: some at μkn < 0.8, none at μkn > 0.8",
            mc.subharmonic_rest,
            "mu_kn",
        ),
        (
            "M8",
            "Fig. 4b",
            "DC grows with μkn",
            "ρ(μkn, row-mean DC) ≥ 0.8",
            mc.dc_trend_second("mu_kn", 1),
            "mu_kn",
        ),
        (
            "M9",
            "Fig. 4",
            "the number of detachments grows with μkn",
            "ρ(μkn, row-mean p/n of periodic cells) ≥ 0.8",
            mc.detachment_trend("mu_kn"),
            "mu_kn",
        ),
        (
            "M10",
            "Fig. 4",
            "richer n-p structure as μkn rises",
            "more distinct periodic n-p "
            "labels in the upper half of the μkn range than in the lower half",
            mc.richer_structure("mu_kn"),
            "mu_kn",
        ),
        (
            "M11",
            "Fig. 7b",
            "DC grows with μcn",
            "ρ(μcn, row-mean DC) ≥ 0.8",
            mc.dc_trend_second("mu_cn", 1),
            "mu_cn",
        ),
        (
            "M12",
            "Fig. 7",
            "the number of detachments grows with μcn",
            "as M9 over μcn",
            mc.detachment_trend("mu_cn"),
            "mu_cn",
        ),
        (
            "M13",
            "Fig. 7",
            "the n-0 domain shrinks and the n-1 domain grows with μcn",
            "ρ(μcn, n-0 cells per row) ≤ −0.8 and ρ(μcn, n-1 cells per row) ≥ 0.8",
            mc.rest_shrinks_damping,
            "mu_cn",
        ),
        (
            "M14",
            "Fig. 7",
            "richer n-p structure as μcn rises",
            "as M10 over μcn",
            mc.richer_structure("mu_cn"),
            "mu_cn",
        ),
        (
            "M15",
            "Fig. 7b",
            "detachment is concentrated at high speed and μcn > 0.9",
            "≥ 50 % of the top-decile DC cells at ω > 3 and μcn > 0.9",
            mc.damping_hot_corner,
            "mu_cn",
        ),
        (
            "M16",
            "Fig. 7",
            "low-speed 1-p have more detachments than high-speed n-p (n ≥ 2), but lower DC",
            "mean p and DC of 1-p (p ≥ 1) cells at ω < 1 against n-p (n ≥ 2, p ≥ 1) cells at ω > 3",
            mc.low_speed_many_detachments,
            "mu_cn",
        ),
    ]
    rows += [
        Claim(
            key,
            src,
            text,
            test,
            fn,
            sized=True,
            command=map_command(plane, "dc" if "DC" in test else "labels"),
        )
        for key, src, text, test, fn, plane in maps
    ]
    never = [
        (
            "N1",
            "eqs. 29–30, Fig. 2c",
            "the routes between neighbouring 1-p and 1-(p+1) "
            "(grazing G and saddle-node SN chains; 1-2 → PD → 2-4 → … → chaos → … → 1-3)",
            "not encoded: a route is a sequence of typed transitions (G, SN, PD, period adding) "
            "along a path the paper does not give (its f0); `campar line --json` and `campar "
            "plot --bifurcations` type transitions, but no test matches them to the sequences",
        ),
        (
            "N3",
            "Fig. 2",
            "chattering 1-p̃ (p ≥ 7), with 1-0 embedded in its window along f0",
            "not encoded: M2 counts 1-p cells only; whether 1-0 sits inside a 1-p̃ window along "
            "f0 is a statement about the arrangement of regions, which no test reads",
        ),
        (
            "N5",
            "Fig. 9",
            "Pn lags yc (hysteresis from contact damping)",
            "not testable as "
            "stated: the paper names no feature whose delay it means (peak, onset, centre of "
            "mass); T12 tests the angle of the peak of Pn",
        ),
    ]
    rows += [Claim(key, src, text, "–", None, untested=why) for key, src, text, why in never]
    rows.append(
        Claim(
            "N2",
            "Figs. 2d,e, 4c",
            "tongue-shaped 'lingual' domains of subharmonic n-p between "
            "n-p and (n+1)-(p+1), bounded by PD of n-p and G of (n+1)-(p+1)",
            "the 2-2 and 2-1 "
            f"tongues of the (ω, μkn) and (ω, μcn) maps: ≥ {continued.BOUNDED_SHARE:.0%} of each "
            "tongue's boundary within a cell of continued PD and G curves (campar curves), both "
            "present",
            continued.tongue_claim,
            sized=True,
            command=continued.tongue_command,
        )
    )
    rows.append(
        Claim(
            "N4",
            "Figs. 4d, 5c",
            "the period-doubling cascade 1-1 → PD → 2-2 → PD → 4-4 → long "
            "periods → chaos at μkn = 0.91",
            "PD points in a row from the 1-cycles (a branch of "
            "period 4 switched from one of period 2 switched from the 1-cycles), on the branch "
            "structure of P7",
            continued.cascade_claim,
            command=continued.structure_command,
        )
    )
    tested_later = sorted((r for r in rows if r.key.startswith("N")), key=lambda c: int(c.key[1:]))
    return [r for r in rows if not r.key.startswith("N")] + tested_later


CLAIMS = _claims()


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
