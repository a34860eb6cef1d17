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
    command: str = ""  # the command that reproduces the number ("": the claim's own)


@dataclass(frozen=True)
class Claim:
    key: str  # "P1", "M3", … (P point, E eigenvalues, T time series, M maps)
    source: str  # where in the paper
    text: str  # what the paper claims
    test: str  # how campar tests it
    evaluate: Callable | None  # (Evidence) -> Verdict; None: not tested
    sized: bool = False  # True: evidence is a map, the row depends on its resolution
    # reproduces the number: a text in which "{law}" stands for the force-law flags, or a
    # function (Evidence, flags) -> text
    command: str | Callable = ""
    untested: str = ""  # why the claim is not tested (then evaluate is None)


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
    """campar's results under one force law (and, with ``options``, the law's options:
    duty_cycle, cam_velocity), computed on first use and kept."""

    def __init__(self, tensile: str, size: str = "small", stores=None, options=None):
        from .gallery import default_stores

        self.tensile, self.size = tensile, size
        self.stores = stores or default_stores(size)
        self.options = dict(options or {})  # ModelSettings options that differ from default
        self._kept = {}

    @property
    def suffix(self) -> str:
        """The store-name suffix of the options ("" without): "-dc-force", "-cam-literal"."""
        return "".join(f"-{OPTION_NAMES[k]}-{v}" for k, v in sorted(self.options.items()))

    def _keep(self, key, compute):
        if key not in self._kept:
            self._kept[key] = compute()
        return self._kept[key]

    def job(self, job):
        """``job`` with this evidence's model options (renamed when there are some)."""
        if not self.options:
            return job
        from ..sweep.job import Job

        data = job.to_dict()
        data["model"].update(self.options)
        data["name"] = f"{data['name']}{self.suffix}"
        return Job.from_dict(data, source=f"{job.name} with {self.options}")

    def plane(self, name: str) -> Plane:
        return self._keep(("plane", name), lambda: self._read_plane(name))

    def _read_plane(self, name: str) -> Plane:
        from ..sweep.store import read_store

        job = self.job(setups.plane_job(name, self.size, self.tensile))
        with read_store(setups.run_plane(job, self.stores)) as reader:
            if not reader.done.all():
                raise RuntimeError(f"{reader.path} is not complete")
            arrays = {k: reader.read(k) for k in ("kind", "n", "p", "dc", "eps_max", "eps_min")}
        return Plane(job.omega, job.second_values, job.second, arrays)

    def point(self, omega: float, **settings):
        """``simulate_point`` with this evidence's force law and options."""
        from ..views.point import simulate_point

        return simulate_point(omega, tensile=self.tensile, **self.options, **settings)

    def line(self, omega, points: int, **options):
        """A continuation line (``campar.views.line``) with this evidence's law and options."""
        from ..views.line import compute_line, line_spec

        spec = line_spec(omega, points, tensile=self.tensile, **self.options, **options)
        return compute_line(spec)

    def continued(self, omega: float, mu_kn: float):
        """The orbit at ω reached by continuation along ω from 6.0 in steps ≤ 0.005 (as
        ``setups.continued_point``): ``Continued`` with the line and the traced result."""

        def compute():
            from ..views.line import PAPER_START, continuation_points

            points = continuation_points(omega, PAPER_START)
            line = self.line((PAPER_START, omega), points, sections=1, mu_kn=mu_kn)
            y, v = (float(x) for x in line.state[-1])
            result = self.point(
                omega, y0=y, v0=v, multipliers=True, lyapunov=True, trace=True, mu_kn=mu_kn
            )
            return Continued(result, line)

        return self._keep(("continued", omega, mu_kn), compute)

    def steady(self, omega: float, **params):
        """The orbit at ω from rest, traced (``setups.steady_point``)."""
        key = ("steady", omega, *sorted(params.items()))
        return self._keep(key, lambda: self.point(omega, trace=True, **params))

    def rest(self, omega: float, **params):
        """The cell at ω from rest, with multipliers (no trace)."""
        key = ("rest", omega, *sorted(params.items()))
        return self._keep(key, lambda: self.point(omega, multipliers=True, **params))

    def long_run(self, omega: float, state, **params):
        """LONG_RUN revolutions from ``state`` as a fixed transient, then the read window:
        the verdict a quasi-periodic or chaotic label must survive."""
        key = ("long", omega, tuple(state), *sorted(params.items()))
        return self._keep(
            key,
            lambda: self.point(
                omega,
                y0=float(state[0]),
                v0=float(state[1]),
                transient="fixed",
                revolutions=LONG_RUN,
                multipliers=True,
                lyapunov=True,
                **params,
            ),
        )

    def fine_line(self, mu_kn: float):
        """The line at μkn from ω = 6.0 down to 2.0 in steps of 0.001 (context for P rows)."""
        hi, lo, points = setups.FINE_LINE
        return self._keep(("line", mu_kn), lambda: self.line((hi, lo), points, mu_kn=mu_kn))

    def path_row(self, second: float, low: float, plane: str = setups.FIG6_PLANE):
        """The paper's path (``setups.plane_path_job``: the plane's 2-D continuation from its
        corner, ``chains: {start: continue}``) down to ω = ``low`` at ``second``: the cells
        of its last row, on the plane's full grid spacing."""
        return self._keep(("path", second, low, plane), lambda: self._path_row(second, low, plane))

    def _path_row(self, second, low, plane) -> "PathRow":
        from ..core.codes import Kind, cell_label
        from ..sweep.plan import Tile
        from ..sweep.tile import run_tile

        job = self.job(setups.plane_path_job(low, second, self.tensile, plane))
        rows = job.shape[0]
        cells = {k: v[0] for k, v in run_tile(job, Tile(0, rows - 1, rows)).items()}
        codes = zip(cells["kind"], cells["n"], cells["p"], strict=True)
        labels = [
            cell_label(Kind(int(k)), int(n), int(p), job.classify.chatter_p) for k, n, p in codes
        ]
        return PathRow(job.omega, labels, cells["state"], job)


LONG_RUN = 4000  # revolutions a quasi-periodic or chaotic verdict must survive
OPTION_NAMES = {"duty_cycle": "dc", "cam_velocity": "cam"}


@dataclass(frozen=True)
class Continued:
    """A point reached by continuation along ω from 6.0: the traced result, and the line."""

    result: object  # PointResult with trace, multipliers, Lyapunov exponent
    line: object  # BifurcationLine


@dataclass(frozen=True)
class PathRow:
    """The last row of a plane's path job: ω (decreasing), labels and final states."""

    omega: np.ndarray
    labels: list
    state: np.ndarray  # (N, 2)
    job: object


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
    """T5, undecided (None) where it cannot fail: a cycle of one revolution that touches
    the cam at all touches it in every revolution."""
    worst, one_cycles = [], True
    for omega in setups.SPEEDS:
        for r in fig3(ev, omega):
            one_cycles &= r.kind == "periodic" and r.n == 1 and r.eps_max > 0
            tr = r.trace
            rev = np.floor((tr.t - tr.t[0]) / tr.period + 1e-9).astype(int)
            for k in range(max(1, r.n)):
                worst.append(float(tr.eps[rev == k].max()) if np.any(rev == k) else math.nan)
    low = min(worst)
    text = f"smallest per-revolution max ε = {fmt(low)}"
    if one_cycles:
        return Verdict(
            text + "; every orbit is a 1-cycle in contact, so the test cannot fail "
            "(trivial at these settings)",
            None,
        )
    return Verdict(text, bool(low > 0))


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


# T11's windows of cam angle: "the beginning of the far dwell" (its first 30°) and "from
# the fall to the near dwell" (the last 30° of the fall and the first 30° of the near
# dwell). Together 90° of 360°: a detachment at a random angle passes with chance 1/4.
FAR_DWELL_START = (60.0, 90.0)
FALL_TO_NEAR_DWELL = (210.0, 270.0)


def detachment_phases(ev: Evidence) -> Verdict:
    parts, ok = [], []
    for omega in setups.SPEEDS:
        r = ev.steady(omega, f0=setups.FIG9_F0)
        angles = cam_angle(r.trace, r.trace.events_named("detachment")[:, 0])
        ok += [
            any(lo <= a <= hi for lo, hi in (FAR_DWELL_START, FALL_TO_NEAR_DWELL)) for a in angles
        ]
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
