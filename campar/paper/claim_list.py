"""The paper's claims, each with its test and the evidence that decides it (``CLAIMS``),
in the order of the reproduction report (``campar.paper.report``): points (P),
multipliers (E), time series (T), Liouville (L), maps (M), then those the continued
branches decide (N)."""

from . import continued, setups
from . import map_claims as mc
from .claims import (
    LONG_RUN,
    Claim,
    Evidence,
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
from .robust import NEIGHBOURS, STEP, WIDTH, label_claim

F6 = "Fig. 6 / 5c"
REPORT = "campar report docs/paper.md --size full"


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
