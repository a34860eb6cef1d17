"""Tests of the paper's claims about its two-parameter maps (Figs. 2, 4, 7).

Each function evaluates one claim on ``Evidence.plane(...)`` and returns a
``Verdict``; the thresholds are spelled out in the claim table
(``campar.paper.claim_list.CLAIMS``). Cells are those of the plane's job at the report's
size, ω decreasing by continuation as in the paper.
"""

import numpy as np

from .claims import (
    Evidence,
    Verdict,
    distinct_labels,
    fmt,
    per_revolution,
    rank_correlation,
    row_mean,
    trend,
)

VERY_LOW_OMEGA = 0.3  # "very low speed": the lowest 5 % of the ω range
LOW_OMEGA = 1.0  # "low speed" (the paper's "ω < 1.0")
HIGH_OMEGA = 5.0  # the paper's "ω > 5.0"


def lowest_speeds_rest(ev: Evidence) -> Verdict:
    """ω ≤ 0.3 on (ω, f0): 1-0 with DC = 0."""
    pl = ev.plane("omega_f0")
    w, _ = pl.grid()
    a = pl.arrays
    cells = w <= VERY_LOW_OMEGA
    rest = pl.periodic & (a["n"] == 1) & (a["p"] == 0) & (a["dc"] == 0) & cells
    share = rest.sum() / cells.sum()
    others = cells & ~rest
    text = f"{share:.0%} of the cells 1-0 with DC = 0"
    if others.any():
        _, f0 = pl.grid()
        text += (
            f"; the others at f0 ≤ {fmt(f0[others].max())}, "
            f"DC up to {fmt(np.nanmax(a['dc'][others]))}"
        )
    return Verdict(text, bool(share >= 0.95))


def low_speeds_period_one(ev: Evidence) -> Verdict:
    pl = ev.plane("omega_f0")
    w, _ = pl.grid()
    a = pl.arrays
    cells = w < LOW_OMEGA
    one = (pl.periodic & (a["n"] == 1) & (a["p"] >= 1) & cells).sum() / cells.sum()
    rest = (pl.periodic & (a["n"] == 1) & (a["p"] == 0) & cells).sum() / cells.sum()
    return Verdict(f"1-p (p ≥ 1) {one:.0%}, 1-0 {rest:.0%}", bool(one >= 0.5))


def high_speed_dc(ev: Evidence) -> Verdict:
    pl = ev.plane("omega_f0")
    w, _ = pl.grid()
    dc = pl.arrays["dc"][w > HIGH_OMEGA]
    median = float(np.nanmedian(dc))
    return Verdict(
        f"median DC {fmt(median)} (range {fmt(np.nanmin(dc))}–{fmt(np.nanmax(dc))})",
        bool(median >= 0.9),
    )


def dc_trend_second(plane: str, sign: int) -> callable:
    def evaluate(ev: Evidence) -> Verdict:
        pl = ev.plane(plane)
        means = row_mean(pl, pl.arrays["dc"])
        rho = rank_correlation(pl.second, means)
        hi, lo = high_low(pl, means)
        return Verdict(
            f"ρ = {fmt(rho, 2)}; mean DC {fmt(lo)} (low third) → {fmt(hi)} (high third)",
            trend(rho, sign),
        )

    return evaluate


def high_low(pl, values) -> tuple[float, float]:
    """Means of a per-row quantity over the upper and lower third of the second parameter."""
    order = np.argsort(pl.second)
    third = max(1, len(order) // 3)
    return float(np.nanmean(values[order[-third:]])), float(np.nanmean(values[order[:third]]))


def dc_trend_speed(ev: Evidence) -> Verdict:
    pl = ev.plane("omega_f0")
    means = np.nanmean(pl.arrays["dc"], axis=0)
    rho = rank_correlation(pl.omega, means)
    return Verdict(f"ρ(ω, column-mean DC) = {fmt(rho, 2)}", trend(rho, 1))


def rest_region(ev: Evidence) -> Verdict:
    """M6: n-0 at very small ω or small μkn. That n-0 cells lie at ω ≤ 1 is M1 again (every
    plane rests at low speed), so the test is on the rest: the n-0 cells at ω > 1 must exist
    and lie at μkn < 0.8 (≥ 90 % of them)."""
    pl = ev.plane("mu_kn")
    w, mu = pl.grid()
    a = pl.arrays
    rest = pl.periodic & (a["p"] == 0)
    fast = rest & (w > LOW_OMEGA)
    share = (fast & (mu < 0.8)).sum() / max(fast.sum(), 1)
    text = (
        f"{rest.sum()} n-0 cells, {(rest & (w <= LOW_OMEGA)).sum()} of them at ω ≤ 1; "
        f"{fast.sum()} at ω > 1, {share:.0%} of those at μkn < 0.8"
    )
    return Verdict(text, bool(fast.any() and share >= 0.9))


def subharmonic_rest(ev: Evidence) -> Verdict:
    pl = ev.plane("mu_kn")
    _, mu = pl.grid()
    a = pl.arrays
    sub = pl.periodic & (a["p"] == 0) & (a["n"] >= 2)
    below, above = int((sub & (mu < 0.8)).sum()), int((sub & (mu > 0.8)).sum())
    return Verdict(
        f"n-0 (n ≥ 2) cells: {below} at μkn < 0.8, {above} at μkn > 0.8",
        bool(below > 0 and above == 0),
    )


def detachment_trend(plane: str) -> callable:
    def evaluate(ev: Evidence) -> Verdict:
        pl = ev.plane(plane)
        means = row_mean(pl, per_revolution(pl))
        rho = rank_correlation(pl.second, means)
        hi, lo = high_low(pl, means)
        return Verdict(f"ρ = {fmt(rho, 2)}; mean p/n {fmt(lo)} → {fmt(hi)}", trend(rho, 1))

    return evaluate


def richer_structure(plane: str) -> callable:
    def evaluate(ev: Evidence) -> Verdict:
        pl = ev.plane(plane)
        middle = np.median(pl.second)
        upper = distinct_labels(pl, pl.second > middle)
        lower = distinct_labels(pl, pl.second <= middle)
        per_row = [
            distinct_labels(pl, np.arange(len(pl.second)) == i) for i in range(len(pl.second))
        ]
        rho = rank_correlation(pl.second, per_row)
        return Verdict(
            f"distinct n-p {lower} (lower half) vs {upper} (upper half); "
            f"ρ(distinct n-p per row) = {fmt(rho, 2)}",
            bool(upper > lower),
        )

    return evaluate


def rest_shrinks_damping(ev: Evidence) -> Verdict:
    pl = ev.plane("mu_cn")
    a = pl.arrays
    rest = (pl.periodic & (a["p"] == 0)).sum(axis=1)
    one = (pl.periodic & (a["p"] == 1)).sum(axis=1)
    rho0, rho1 = rank_correlation(pl.second, rest), rank_correlation(pl.second, one)
    ok0, ok1 = trend(rho0, -1), trend(rho1, 1)
    match = None if ok0 is None or ok1 is None else ok0 and ok1
    return Verdict(f"ρ(μcn, n-0 cells) = {fmt(rho0, 2)}, ρ(μcn, n-1 cells) = {fmt(rho1, 2)}", match)


def damping_hot_corner(ev: Evidence) -> Verdict:
    pl = ev.plane("mu_cn")
    w, mu = pl.grid()
    dc = pl.arrays["dc"]
    top = dc >= np.nanquantile(dc, 0.9)
    share = (top & (w > 3.0) & (mu > 0.9)).sum() / max(top.sum(), 1)
    text = f"{share:.0%} of the top-decile DC cells at ω > 3, μcn > 0.9"
    return Verdict(text, bool(share >= 0.5))


def low_speed_many_detachments(ev: Evidence) -> Verdict:
    pl = ev.plane("mu_cn")
    w, _ = pl.grid()
    a = pl.arrays
    low = pl.periodic & (a["n"] == 1) & (a["p"] >= 1) & (w < LOW_OMEGA)
    high = pl.periodic & (a["n"] >= 2) & (a["p"] >= 1) & (w > 3.0)
    if not low.any() or not high.any():
        return Verdict(f"{low.sum()} low-speed 1-p, {high.sum()} high-speed n-p cells", None)
    p_low, p_high = a["p"][low].mean(), a["p"][high].mean()
    dc_low, dc_high = np.nanmean(a["dc"][low]), np.nanmean(a["dc"][high])
    return Verdict(
        f"mean p {fmt(p_low)} vs {fmt(p_high)}; mean DC {fmt(dc_low)} vs {fmt(dc_high)}",
        bool(p_low > p_high and dc_low < dc_high),
    )
