"""The paper's quantitative claims, each with a stated test, evaluated on campar's results.

A ``Claim`` names its source in the paper, quotes or condenses what the paper
says, states how campar tests it, and evaluates that test on ``Evidence``
(campar's results under one force law) into a ``Verdict``: what the model
gives, and whether that matches (True, False, or None when the test cannot
decide). Claims whose evidence is a two-parameter map depend on the map's
resolution (``sized``); all others (point labels, multipliers, orbits) are
computed the same way at every size, so their rows must not change with it.

Vague words of the paper are made testable by a stated threshold (a rank
correlation ≥ 0.8 for "increases with", a majority for "mainly", …); the
thresholds are in each claim's ``test`` text, so a reader can disagree with
them openly.
"""

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..core.codes import PERIODIC
from . import setups

TREND = 0.8  # |Spearman ρ| from which "increases/decreases with" counts as shown


@dataclass(frozen=True)
class Verdict:
    found: str  # what campar gives, short
    match: bool | None  # None: the test cannot decide


@dataclass(frozen=True)
class Claim:
    key: str  # "P1", "M3", … (P point, E eigenvalues, T time series, M maps)
    source: str  # where in the paper
    text: str  # what the paper claims
    test: str  # how campar tests it
    evaluate: Callable  # (Evidence) -> Verdict
    sized: bool = False  # True: evidence is a map, the row depends on its resolution


@dataclass(frozen=True)
class Plane:
    """A computed plane: axes (cell centres) and per-cell arrays over (second, omega)."""

    omega: np.ndarray
    second: np.ndarray
    name: str  # the second parameter
    arrays: dict

    def grid(self):
        """(ω, second) of every cell, each shaped like the arrays."""
        return np.meshgrid(self.omega, self.second)

    @property
    def periodic(self) -> np.ndarray:
        return self.arrays["kind"] == PERIODIC


class Evidence:
    """campar's results under one force law, computed on first use and kept."""

    def __init__(self, tensile: str, size: str = "small", stores=None):
        from .gallery import default_stores

        self.tensile, self.size = tensile, size
        self.stores = stores or default_stores(size)
        self._kept = {}

    def _keep(self, key, compute):
        if key not in self._kept:
            self._kept[key] = compute()
        return self._kept[key]

    def plane(self, name: str) -> Plane:
        return self._keep(("plane", name), lambda: self._read_plane(name))

    def _read_plane(self, name: str) -> Plane:
        from ..sweep.store import read_store

        job = setups.plane_job(name, self.size, self.tensile)
        with read_store(setups.run_plane(job, self.stores)) as reader:
            if not reader.done.all():
                raise RuntimeError(f"{reader.path} is not complete")
            arrays = {k: reader.read(k) for k in ("kind", "n", "p", "dc", "eps_max", "eps_min")}
        return Plane(job.omega, job.second_values, job.second, arrays)

    def continued(self, omega: float, mu_kn: float):
        """The orbit at ω reached by continuation from 6.0 (``setups.continued_point``)."""
        return self._keep(
            ("continued", omega, mu_kn),
            lambda: setups.continued_point(omega, self.tensile, mu_kn=mu_kn),
        )

    def steady(self, omega: float, **params):
        """The orbit at ω from rest (``setups.steady_point``)."""
        key = ("steady", omega, *sorted(params.items()))
        return self._keep(key, lambda: setups.steady_point(omega, self.tensile, **params))

    def fine_line(self, mu_kn: float):
        """The line at μkn from ω = 6.0 down to 2.0 in steps of 0.001 (context for P rows)."""
        return self._keep(("line", mu_kn), lambda: setups.fine_line(mu_kn, self.tensile))


# -- helpers ---------------------------------------------------------------------


def rank_correlation(x, y) -> float:
    """Spearman's ρ (average ranks for ties); NaN pairs dropped, NaN if < 3 pairs."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    keep = np.isfinite(x) & np.isfinite(y)
    if keep.sum() < 3:
        return math.nan
    rx, ry = average_ranks(x[keep]), average_ranks(y[keep])
    if rx.std() == 0 or ry.std() == 0:
        return math.nan
    return float(np.corrcoef(rx, ry)[0, 1])


def average_ranks(values: np.ndarray) -> np.ndarray:
    _, inverse, counts = np.unique(values, return_inverse=True, return_counts=True)
    ends = np.cumsum(counts)
    return ((ends - counts + 1 + ends) / 2.0)[inverse]


def trend(rho: float, sign: int) -> bool | None:
    return None if math.isnan(rho) else bool(sign * rho >= TREND)


def monotone(values, sign: int) -> bool:
    """Strictly increasing (sign 1) or decreasing (sign −1)."""
    return bool(np.all(sign * np.diff(np.asarray(values, float)) > 0))


def fmt(x: float, digits: int = 3) -> str:
    if x is None or not math.isfinite(x):
        return "–"
    return f"{x:.{digits}g}" if abs(x) >= 1e-3 or x == 0 else f"{x:.2e}"


def row_mean(plane: Plane, values: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
    values = np.where(mask if mask is not None else True, values, np.nan)
    with np.errstate(invalid="ignore"):
        counts = np.isfinite(values).sum(axis=1)
        sums = np.nansum(values, axis=1)
    return np.where(counts > 0, sums / np.maximum(counts, 1), np.nan)


def per_revolution(plane: Plane) -> np.ndarray:
    """Detachments per revolution p/n of periodic cells (NaN elsewhere)."""
    a = plane.arrays
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(plane.periodic & (a["n"] > 0), a["p"] / np.maximum(a["n"], 1), np.nan)


def distinct_labels(plane: Plane, rows: np.ndarray) -> int:
    a = plane.arrays
    cells = plane.periodic & rows[:, None]
    return len(set(zip(a["n"][cells].tolist(), a["p"][cells].tolist(), strict=True)))


# -- point claims (Fig. 6 and the text on Fig. 4d / 5c) ----------------------------


def label_claim(omega: float, expected: str) -> Callable:
    def evaluate(ev: Evidence) -> Verdict:
        found = ev.continued(omega, setups.FIG6_MU_KN).result
        cold = ev.steady(omega, mu_kn=setups.FIG6_MU_KN)
        text = f"{found.label} ({found.kind}; from rest: {cold.label})"
        if expected in ("chaos", "QP"):
            text += "; " + nearest_cells(ev.fine_line(setups.FIG6_MU_KN), expected, omega)
        return Verdict(text, found.label == expected)

    return evaluate


def nearest_cells(line, label: str, omega: float) -> str:
    """Where the fine line has cells of ``label``: the one nearest ω and how many in all."""
    cells = np.flatnonzero(np.array(line.labels) == label)
    where = f"ω {line.omega[0]:g} → {line.omega[-1]:g}, step {line.omega[0] - line.omega[1]:.3g}"
    if not cells.size:
        return f"no {label} cell on the line {where}"
    nearest = line.omega[cells[np.argmin(np.abs(line.omega[cells] - omega))]]
    return f"{cells.size} {label} cells on the line {where}, the nearest at ω = {nearest:.4g}"


def hopf_claim(ev: Evidence) -> Verdict:
    r = ev.continued(3.208583, setups.FIG6_MU_KN).result
    mult = r.multipliers or ()
    moduli = [abs(m) for m in mult]
    complex_pair = bool(mult) and abs(mult[0].imag) > 1e-9
    text = f"{r.label}, |λ| = {', '.join(fmt(m) for m in moduli) or '–'}" + (
        " (complex pair)" if complex_pair else " (real)")  # fmt: skip
    if r.kind != "periodic":
        return Verdict(f"{r.label} (no multipliers of a cycle)", None)
    return Verdict(text, complex_pair and max(moduli) > 0.98)


def multiplier_claim(index: int) -> Callable:
    omega, quoted, _ = setups.QUOTED_MULTIPLIERS[index]

    def evaluate(ev: Evidence) -> Verdict:
        r = ev.continued(omega, setups.QUOTED_MU_KN).result
        if r.multipliers is None or r.kind != "periodic":
            return Verdict(f"{r.label}: not periodic, no multipliers", False)
        mult = ", ".join(complex_text(m) for m in r.multipliers)
        close = np.allclose(sorted(r.multipliers, key=abs), sorted(quoted, key=abs), atol=0.01)
        return Verdict(f"{r.label}: λ = {mult}", bool(close))

    return evaluate


def complex_text(z: complex) -> str:
    if abs(z.imag) < 1e-9:
        return fmt(z.real, 4)
    return f"{fmt(z.real, 4)} {'+' if z.imag > 0 else '−'} {fmt(abs(z.imag), 4)}i"


# -- time-series claims (Figs. 3, 8, 9) ------------------------------------------------


def fig3(ev: Evidence, omega: float):
    return [ev.steady(omega, f0=f0) for f0 in setups.FIG3_F0]


def fig8(ev: Evidence, omega: float, name: str):
    return [ev.steady(omega, f0=setups.FIG8_F0, **{name: v}) for v in setups.FIG8_RATIOS]


def series_trend(results_of, quantity: str, sign: int, only_detached: bool = False) -> Callable:
    """Evaluate "quantity changes with the varied parameter (sign)" at every speed."""

    def evaluate(ev: Evidence) -> Verdict:
        parts, ok = [], []
        for omega in setups.SPEEDS:
            results = results_of(ev, omega)
            values = [getattr(r, quantity) for r in results]
            if only_detached and any(v >= 0 for v in values):
                parts.append(f"ω={omega:g}: " + "/".join(fmt(v) for v in values) + " (n/a)")
                continue
            ok.append(monotone(values, sign))
            parts.append(f"ω={omega:g}: " + "/".join(fmt(v) for v in values))
        return Verdict("; ".join(parts), all(ok) if ok else None)

    return evaluate


def speed_trend(quantity: str) -> Callable:
    """ "quantity increases with ω" for each f0 of Fig. 3."""

    def evaluate(ev: Evidence) -> Verdict:
        parts, ok = [], []
        for i, f0 in enumerate(setups.FIG3_F0):
            values = [fig3(ev, omega)[i].__getattribute__(quantity) for omega in setups.SPEEDS]
            ok.append(monotone(values, 1))
            parts.append(f"f0={f0:g}: " + "/".join(fmt(v) for v in values))
        return Verdict("; ".join(parts), all(ok))

    return evaluate


def never_fully_detached(ev: Evidence) -> Verdict:
    worst = []
    for omega in setups.SPEEDS:
        for r in fig3(ev, omega):
            tr = r.trace
            rev = np.floor((tr.t - tr.t[0]) / tr.period + 1e-9).astype(int)
            for k in range(max(1, r.n)):
                worst.append(float(tr.eps[rev == k].max()) if np.any(rev == k) else math.nan)
    low = min(worst)
    return Verdict(f"smallest per-revolution max ε = {fmt(low)}", bool(low > 0))


def stiffness_beats_damping(ev: Evidence) -> Verdict:
    parts, ok = [], []
    for omega in setups.SPEEDS:
        dk = fig8(ev, omega, "mu_kn")[0].eps_max - fig8(ev, omega, "mu_kn")[-1].eps_max
        dc = fig8(ev, omega, "mu_cn")[0].eps_max - fig8(ev, omega, "mu_cn")[-1].eps_max
        ok.append(dk > dc)
        parts.append(f"ω={omega:g}: Δ(μkn) {fmt(dk)} vs Δ(μcn) {fmt(dc)}")
    return Verdict("; ".join(parts), all(ok))


def cam_angle(trace, times) -> np.ndarray:
    """Cam angle θ ∈ [0, 360°) at trace times (t = 0 at θ = 0)."""
    return np.degrees((2 * math.pi * np.asarray(times) / trace.period) % (2 * math.pi))


def detachment_phases(ev: Evidence) -> Verdict:
    parts, ok = [], []
    for omega in setups.SPEEDS:
        r = ev.steady(omega, f0=setups.FIG9_F0)
        angles = cam_angle(r.trace, r.trace.events_named("detachment")[:, 0])
        ok += [60 <= a <= 120 or a >= 180 for a in angles]
        parts.append(f"ω={omega:g}: " + ", ".join(f"{a:.0f}°" for a in angles))
    return Verdict("θ at detachment " + "; ".join(parts), all(ok) if ok else None)


def force_peak_phase(ev: Evidence) -> Verdict:
    parts, ok = [], []
    for omega in setups.SPEEDS:
        tr = ev.steady(omega, f0=setups.FIG9_F0).trace
        theta = float(cam_angle(tr, [tr.t[int(np.argmax(tr.pn))]])[0])
        ok.append(abs(theta - 60.0) <= 10.0)
        parts.append(f"ω={omega:g}: {theta:.0f}°")
    return Verdict("θ at max Pn " + "; ".join(parts), all(ok))
