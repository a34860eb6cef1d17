"""A tabulated cam: a CSV of (θ, S) read, checked and turned into a periodic C² cubic spline.

A measured or designed cam profile is a table of the lift S (in units of the stroke h)
against the cam angle θ (radians) over one revolution: one ``θ, S`` pair a line, lines
starting with ``#`` and one header line ignored. It must start at θ = 0, rise strictly,
stay within 2π (a last point at 2π must repeat the first lift: the table closes over
the revolution), hold at least ``MIN_POINTS`` points and have no gap wider than
``MAX_GAP``: each a one-line error naming the line. The spline through it is periodic
(S, S' and S'' agree at 0 and 2π) and C² everywhere (campar.core.cam.TabulatedCam
evaluates it); it is computed here with numpy alone (a cyclic tridiagonal system for
the knots' second derivatives).

Also the check of a cam's phase angles (``check_angles``): numpy-free, so that job files
are validated without the compiled kernel.
"""

import functools
import hashlib
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .files import read_bounded

TWO_PI = 2.0 * math.pi
ANGLE_TOL = 1e-9  # the four phase angles must sum to 2π within this
MIN_POINTS = 16
MAX_GAP = TWO_PI / 32  # the widest spacing of a table (≈ 11°)
CLOSURE_TOL = 1e-9  # a point at 2π repeats the first lift to this (in units of the stroke)
MAX_TABLE_BYTES = 1 << 20  # ~40,000 lines of θ, S: far more than a cam needs
_KNOWN: dict[str, "CamTable"] = {}  # tables by sha256 that stores keep (``remember_table``)
ANGLE_NAMES = ("phi1 (rise)", "phi2 (far dwell)", "phi3 (fall)", "phi4 (near dwell)")


def check_angles(angles) -> tuple[float, float, float, float]:
    """The four phase angles as floats; ValueError unless rise and fall are > 0, the dwells
    ≥ 0 and their sum 2π (within ANGLE_TOL)."""
    phi = tuple(float(a) for a in angles)
    for i, (name, a) in enumerate(zip(ANGLE_NAMES, phi, strict=True)):
        positive = i in (0, 2)
        if not math.isfinite(a) or a < 0.0 or (positive and a == 0.0):
            raise ValueError(f"{name} must be {'> 0' if positive else '≥ 0'}, got {a:.12g}")
    total = sum(phi)
    if abs(total - TWO_PI) > ANGLE_TOL:
        raise ValueError(
            f"the cam angles phi1 … phi4 must sum to 2π = {TWO_PI:.12g}, they sum to {total:.12g}"
        )
    return phi


def phase_bounds(angles) -> tuple[float, float, float, float, float]:
    """0, Φ1, Φ1+Φ2, Φ1+Φ2+Φ3, 2π, as campar.core.cam computes them for the kernel."""
    p1, p2, p3, _ = check_angles(angles)
    return (0.0, p1, p1 + p2, p1 + p2 + p3, TWO_PI)


@dataclass(frozen=True)
class CamTable:
    theta: np.ndarray  # knots in [0, 2π), strictly increasing, theta[0] = 0
    lift: np.ndarray
    sha256: str  # of the file's bytes
    name: str = "cam table"
    text: str = ""  # the file's text, as a store keeps it

    def spline(self, joins: str = "smooth", bounds=None) -> tuple[np.ndarray, np.ndarray]:
        """(knots with 2π appended, coefficients (a, b, c, e) a knot interval). ``joins``:
        smooth, one periodic C² spline (``periodic_spline``); phases, a C² spline on each
        cam phase between ``bounds`` (``phase_splines``: S continuous at the phase
        boundaries, its acceleration free to jump there, as a cam made of segments)."""
        if joins == "smooth":
            return periodic_spline(self.theta, self.lift)
        return phase_splines(self.theta, self.lift, bounds, self.name)


def read_table(path: str | Path, sha256: str | None = None) -> CamTable:
    """The checked table at ``path`` (ValueError with one line naming the problem); the
    table of that ``sha256`` a store keeps if one was read (``remember_table``): a stored
    job reads as it was computed with, wherever the file is and whatever it holds."""
    if sha256 is not None and sha256 in _KNOWN:
        return _KNOWN[sha256]
    path = Path(path)
    try:
        stat = path.stat()
    except OSError as exc:
        raise ValueError(f"cannot read cam table {path}: {exc.strerror}") from None
    except ValueError as exc:  # a NUL byte in the path
        raise ValueError(f"cannot read cam table {str(path)!r}: {exc}") from None
    return _read(str(path.resolve()), stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=16)
def _read(path: str, mtime_ns: int, size: int) -> CamTable:
    data = read_bounded(path, MAX_TABLE_BYTES, "cam table")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ValueError(
            f"cam table {path}: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start})"
        ) from None
    return parse_table(text, path, data)


def remember_table(text: str, name: str = "cam table") -> CamTable:
    """A table a store keeps (its file's text), known by its sha256 from now on in this
    process: ``read_table`` of that digest returns it without reading the file."""
    table = parse_table(text, name, text.encode())
    _KNOWN[table.sha256] = table
    return table


def parse_table(text: str, name: str = "cam table", raw: bytes | None = None) -> CamTable:
    """The checked table in ``text`` (CSV lines ``θ, S``)."""
    rows, lines = [], []
    header_seen = False
    for number, line in enumerate(text.splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        fields = [f.strip() for f in line.split(",")]
        try:
            values = [float(f) for f in fields]
        except ValueError:
            if not rows and not header_seen:
                header_seen = True
                continue
            raise ValueError(f"{name} line {number}: not two numbers θ, S: {line[:60]!r}") from None
        if len(values) != 2 or not all(math.isfinite(v) for v in values):
            raise ValueError(
                f"{name} line {number}: want two finite numbers θ, S, got {line[:60]!r}"
            )
        rows.append(values)
        lines.append(number)
    if len(rows) < MIN_POINTS:
        raise ValueError(f"{name}: {len(rows)} points; a cam table needs at least {MIN_POINTS}")
    table = np.array(rows)
    theta, lift = table[:, 0], table[:, 1]
    if theta[0] != 0.0:
        raise ValueError(f"{name} line {lines[0]}: the table starts at θ = 0, got {theta[0]:.12g}")
    steps = np.diff(theta)
    if np.any(steps <= 0.0):
        i = int(np.argmax(steps <= 0.0)) + 1
        raise ValueError(
            f"{name} line {lines[i]}: θ must rise strictly, {theta[i]:.12g} "
            f"follows {theta[i - 1]:.12g}"
        )
    if theta[-1] > TWO_PI + ANGLE_TOL:
        hint = " (θ is in radians, not degrees)" if theta[-1] > 7.0 else ""
        raise ValueError(f"{name} line {lines[-1]}: θ = {theta[-1]:.12g} is beyond 2π{hint}")
    if abs(theta[-1] - TWO_PI) <= ANGLE_TOL:
        if abs(lift[-1] - lift[0]) > CLOSURE_TOL:
            raise ValueError(
                f"{name} line {lines[-1]}: the cam does not close over the revolution: "
                f"S(2π) = {lift[-1]:.12g}, S(0) = {lift[0]:.12g}"
            )
        theta, lift = theta[:-1], lift[:-1]
    gaps = np.diff(np.append(theta, TWO_PI))
    widest = int(np.argmax(gaps))
    if gaps[widest] > MAX_GAP:
        raise ValueError(
            f"{name} line {lines[widest]}: a gap of {gaps[widest]:.4g} rad after "
            f"θ = {theta[widest]:.6g}; a cam table's points are at most "
            f"2π/32 = {MAX_GAP:.4g} rad apart"
        )
    digest = hashlib.sha256(raw if raw is not None else text.encode()).hexdigest()
    return CamTable(theta, lift, digest, name, text)


def periodic_spline(theta: np.ndarray, lift: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The periodic cubic spline through (theta, lift) over [0, 2π): knots (theta and 2π)
    and per interval (a, b, c, e) with S = ((a d + b) d + c) d + e, d = θ − knot."""
    x = np.append(np.asarray(theta, float), TWO_PI)
    y = np.append(np.asarray(lift, float), lift[0])
    n = len(theta)
    h = np.diff(x)
    slope = np.diff(y) / h
    # h[i-1] M[i-1] + 2 (h[i-1] + h[i]) M[i] + h[i] M[i+1] = 6 (slope[i] − slope[i-1]), cyclic
    lower = np.roll(h, 1)
    diag = 2.0 * (lower + h)
    upper = h
    rhs = 6.0 * (slope - np.roll(slope, 1))
    m = solve_cyclic(lower, diag, upper, rhs)
    m_next = np.roll(m, -1)
    coef = np.empty((n, 4))
    coef[:, 0] = (m_next - m) / (6.0 * h)
    coef[:, 1] = 0.5 * m
    coef[:, 2] = slope - h * (2.0 * m + m_next) / 6.0
    coef[:, 3] = y[:-1]
    return x, coef


def phase_splines(theta, lift, bounds, name: str = "cam table"):
    """A clamped cubic spline on each phase [bounds[i], bounds[i+1]] (the end slopes of a
    quartic through the phase's five end points): C² inside a phase, S continuous across
    the boundaries, which must be points of the table (ValueError otherwise)."""
    x = np.append(np.asarray(theta, float), TWO_PI)
    y = np.append(np.asarray(lift, float), lift[0])
    coef = np.zeros((len(theta), 4))
    for lo_b, hi_b in zip(bounds[:-1], bounds[1:], strict=True):
        if hi_b == lo_b:
            continue  # a dwell of no length
        ends = []
        for b in (lo_b, hi_b):
            i = int(np.argmin(np.abs(x - b)))
            if abs(x[i] - b) > ANGLE_TOL:
                raise ValueError(
                    f"{name}: no point at the phase boundary θ = {b:.12g}; with "
                    "table_joins: phases every boundary is a point of the table"
                )
            ends.append(i)
        i0, i1 = ends
        if i1 - i0 < 4:
            raise ValueError(
                f"{name}: {i1 - i0} intervals in the phase from θ = {lo_b:.6g}; "
                "with table_joins: phases each phase needs at least 4"
            )
        coef[i0:i1] = clamped_spline(x[i0 : i1 + 1], y[i0 : i1 + 1])
    return x, coef


def clamped_spline(x, y) -> np.ndarray:
    """Coefficients (a, b, c, e) of the cubic spline through (x, y) whose end slopes are
    those of the quartic through the five points at each end."""
    slopes = [
        np.polyval(np.polyder(np.polyfit(x[:5] - x[0], y[:5], 4)), 0.0),
        np.polyval(np.polyder(np.polyfit(x[-5:] - x[-1], y[-5:], 4)), 0.0),
    ]
    h = np.diff(x)
    slope = np.diff(y) / h
    n = len(x)
    lower, diag, upper, rhs = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    diag[0], upper[0], rhs[0] = 2 * h[0], h[0], 6 * (slope[0] - slopes[0])
    diag[-1], lower[-1], rhs[-1] = 2 * h[-1], h[-1], 6 * (slopes[1] - slope[-1])
    lower[1:-1], diag[1:-1], upper[1:-1] = h[:-1], 2 * (h[:-1] + h[1:]), h[1:]
    rhs[1:-1] = 6 * (slope[1:] - slope[:-1])
    m = thomas(lower, diag, upper, rhs)
    coef = np.empty((n - 1, 4))
    coef[:, 0] = (m[1:] - m[:-1]) / (6 * h)
    coef[:, 1] = 0.5 * m[:-1]
    coef[:, 2] = slope - h * (2 * m[:-1] + m[1:]) / 6
    coef[:, 3] = y[:-1]
    return coef


def solve_cyclic(lower, diag, upper, rhs) -> np.ndarray:
    """Solve the cyclic tridiagonal system lower[i] x[i-1] + diag[i] x[i] + upper[i] x[i+1]
    = rhs[i] (indices mod n) by Sherman–Morrison around the Thomas algorithm."""
    n = len(diag)
    gamma = -diag[0]
    d = diag.astype(float)
    d[0] -= gamma
    d[-1] -= lower[0] * upper[-1] / gamma
    u = np.zeros(n)
    u[0], u[-1] = gamma, upper[-1]
    x = thomas(lower, d, upper, rhs)
    z = thomas(lower, d, upper, u)
    factor = (x[0] + lower[0] * x[-1] / gamma) / (1.0 + z[0] + lower[0] * z[-1] / gamma)
    return x - factor * z


def thomas(lower, diag, upper, rhs) -> np.ndarray:
    """Tridiagonal solve (lower[0] and upper[-1] ignored)."""
    n = len(diag)
    c = np.empty(n)
    d = np.empty(n)
    c[0] = upper[0] / diag[0]
    d[0] = rhs[0] / diag[0]
    for i in range(1, n):
        denom = diag[i] - lower[i] * c[i - 1]
        c[i] = upper[i] / denom
        d[i] = (rhs[i] - lower[i] * d[i - 1]) / denom
    x = np.empty(n)
    x[-1] = d[-1]
    for i in range(n - 2, -1, -1):
        x[i] = d[i] - c[i] * x[i + 1]
    return x
