"""Look of every campar figure: fonts, line widths, the field's notation, saving.

Figures are made with ``matplotlib.figure.Figure`` and the Agg canvas, never
through pyplot: drawing is headless everywhere (clusters, CI) and leaves the
caller's backend and pyplot's figure registry alone.
"""

import contextlib
from pathlib import Path

import matplotlib
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

# Sizes for a journal page: 9 pt text survives reduction to one column.
STYLE = {
    "font.size": 9,
    "axes.labelsize": 9,
    "axes.titlesize": 9,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "legend.fontsize": 8,
    "legend.title_fontsize": 8,
    "legend.frameon": False,
    "legend.handlelength": 1.0,
    "legend.handleheight": 1.0,
    "legend.handletextpad": 0.5,
    "legend.labelspacing": 0.3,
    "legend.columnspacing": 1.0,
    "legend.borderaxespad": 0.0,
    "axes.linewidth": 0.6,
    "xtick.major.width": 0.6,
    "ytick.major.width": 0.6,
    "xtick.minor.width": 0.4,
    "ytick.minor.width": 0.4,
    "xtick.direction": "out",
    "ytick.direction": "out",
    "hatch.linewidth": 0.6,
    "mathtext.fontset": "dejavusans",
    "savefig.bbox": "tight",
    "savefig.pad_inches": 0.03,
}
DPI = 300  # PNG resolution; vector formats keep maps as embedded images (rasterized)

# The field's notation for the model parameters (docs/model.md), and what each one is.
SYMBOLS = {
    "omega": r"$\omega$",
    "f0": r"$f_0$",
    "mu_kn": r"$\mu_{\mathrm{kn}}$",
    "mu_cn": r"$\mu_{\mathrm{cn}}$",
    "zeta": r"$\zeta$",
    "y0": r"$y_0$",
    "ydot0": r"$\dot y_0$",
    "phi1": r"$\Phi_1$",
    "phi2": r"$\Phi_2$",
    "phi3": r"$\Phi_3$",
    "phi4": r"$\Phi_4$",
    "n": r"$n$",
    "restitution": r"$e$",
}
MEANINGS = {
    "omega": "cam speed",
    "f0": "preload",
    "mu_kn": "contact stiffness",
    "mu_cn": "contact damping",
    "zeta": "damping ratio",
    "y0": "initial displacement",
    "ydot0": "initial velocity",
    "phi1": "rise angle",
    "phi2": "far-dwell angle",
    "phi3": "fall angle",
    "phi4": "near-dwell angle",
    "n": "contact exponent",
    "restitution": "restitution",
}


# Every model parameter is dimensionless (docs/model.md): ω is the cam speed in units of
# the natural frequency ωn, f0 the preload in units of K1·h, the others are ratios.
UNITS = {
    "omega": r"dimensionless, units of $\omega_n$",
    "f0": r"dimensionless, units of $K_1 h$",
    "mu_kn": "dimensionless",
    "mu_cn": "dimensionless",
    "zeta": "dimensionless",
    "y0": "units of stroke $h$, at θ = 0",
    "ydot0": r"units of $h\,\omega_n$, at θ = 0",
    **{name: "radians" for name in ("phi1", "phi2", "phi3", "phi4")},
    "n": "dimensionless",
    "restitution": "dimensionless",
}
# Axis titles of the orbit quantities: y, yc, ε in strokes h, ẏ in h·ωn, t in 1/ωn, Pn in K1·h.
Y_LABEL = r"displacement $y$ (units of stroke $h$)"
V_LABEL = r"velocity $\dot y$ (units of $h\,\omega_n$)"
T_LABEL = r"time $t$ (units of $1/\omega_n$)"
EPS_LABEL = r"penetration $\varepsilon$ (units of $h$)"  # ε = yc − y
PN_LABEL = r"contact force $P_n$ (units of $K_1 h$)"
YC_LABEL = r"cam input $y_c$ (units of $h$)"


def axis_label(name: str) -> str:
    """Axis title of a model parameter with its units: "cam speed ω (dimensionless, …)"."""
    return f"{MEANINGS[name]} {SYMBOLS[name]} ({UNITS[name]})"


def parameter_text(values: dict[str, float]) -> str:
    """A caption line in the field's notation: "μkn = 0.8,  f0 = 0.5,  ζ = 0.2"."""
    return ",  ".join(f"{SYMBOLS[name]} = {value:g}" for name, value in values.items())


@contextlib.contextmanager
def figure_style():
    """Apply campar's rc settings while artists are created."""
    with matplotlib.rc_context(STYLE):
        yield


def new_figure(width: float, height: float) -> Figure:
    """A headless figure (Agg canvas, constrained layout), size in inches."""
    figure = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def save_figure(figure: Figure, path: str | Path, dpi: int = DPI) -> Path:
    """Write a figure; the format follows the suffix (.png, .pdf, .svg, …)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with figure_style():
        figure.savefig(path, dpi=dpi)
    return path
