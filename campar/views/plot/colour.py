"""Colour science for the map palettes: sRGB → CIE L*a*b* (D65) and the CIEDE2000 difference.

CIEDE2000 follows G. Sharma, W. Wu, E. N. Dalal, "The CIEDE2000 color-difference
formula: implementation notes, supplementary test data, and mathematical
observations", Color Res. Appl. 30 (2005) 21–30, eqs. (1)–(20), with kL = kC = kH = 1;
tests/test_palette.py checks it against the paper's 34 published test pairs. A
ΔE00 of about 1 is just noticeable side by side; campar's map palettes keep every
two colours shown on one map ≥ 10 apart (``labels.MIN_DELTA_E00``).
"""

import numpy as np
from matplotlib.colors import to_rgba

# sRGB (IEC 61966-2-1) primaries to CIE XYZ, and the D65 white point (Y = 1).
SRGB_TO_XYZ = np.array(
    [
        [0.4124564, 0.3575761, 0.1804375],
        [0.2126729, 0.7151522, 0.0721750],
        [0.0193339, 0.1191920, 0.9503041],
    ]
)
D65_WHITE = np.array([0.95047, 1.0, 1.08883])
_EPSILON = 216 / 24389  # CIE's (6/29)^3
_KAPPA = 24389 / 27


def srgb_to_lab(rgb) -> np.ndarray:
    """CIE L*a*b* (D65, 2° observer) of sRGB colours in [0, 1], shape (..., 3 or 4) → (..., 3)."""
    rgb = np.asarray(rgb, float)[..., :3]
    linear = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    xyz = linear @ SRGB_TO_XYZ.T / D65_WHITE
    f = np.where(xyz > _EPSILON, np.cbrt(xyz), (_KAPPA * xyz + 16) / 116)
    return np.stack(
        [116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])],
        axis=-1,
    )


def ciede2000(lab1, lab2) -> np.ndarray:
    """CIEDE2000 colour difference ΔE00 of L*a*b* colours (..., 3), broadcast (Sharma 2005)."""
    lab1, lab2 = np.broadcast_arrays(np.asarray(lab1, float), np.asarray(lab2, float))
    L1, a1, b1 = np.moveaxis(lab1, -1, 0)
    L2, a2, b2 = np.moveaxis(lab2, -1, 0)
    # (2)–(6): a' rescaled by G, C' and h' in degrees in [0, 360)
    c_bar = 0.5 * (np.hypot(a1, b1) + np.hypot(a2, b2))
    c7 = c_bar**7
    g = 0.5 * (1 - np.sqrt(c7 / (c7 + 25.0**7)))
    a1p, a2p = (1 + g) * a1, (1 + g) * a2
    c1p, c2p = np.hypot(a1p, b1), np.hypot(a2p, b2)
    h1p = np.where((a1p == 0) & (b1 == 0), 0.0, np.degrees(np.arctan2(b1, a1p)) % 360)
    h2p = np.where((a2p == 0) & (b2 == 0), 0.0, np.degrees(np.arctan2(b2, a2p)) % 360)
    # (8)–(10): ΔL', ΔC', ΔH'
    d_l = L2 - L1
    d_c = c2p - c1p
    dh = h2p - h1p
    dh = np.where(dh > 180, dh - 360, np.where(dh < -180, dh + 360, dh))
    dh = np.where(c1p * c2p == 0, 0.0, dh)
    d_h = 2 * np.sqrt(c1p * c2p) * np.sin(np.radians(dh) / 2)
    # (12)–(14): means, with the hue mean taken on the shorter arc
    l_bar = 0.5 * (L1 + L2)
    c_bar_p = 0.5 * (c1p + c2p)
    h_sum = h1p + h2p
    h_bar = np.where(
        c1p * c2p == 0,
        h_sum,
        np.where(
            np.abs(h1p - h2p) <= 180,
            h_sum / 2,
            np.where(h_sum < 360, (h_sum + 360) / 2, (h_sum - 360) / 2),
        ),
    )
    # (15)–(20): weighting functions and the rotation term
    t = (
        1
        - 0.17 * np.cos(np.radians(h_bar - 30))
        + 0.24 * np.cos(np.radians(2 * h_bar))
        + 0.32 * np.cos(np.radians(3 * h_bar + 6))
        - 0.20 * np.cos(np.radians(4 * h_bar - 63))
    )
    d_theta = 30 * np.exp(-(((h_bar - 275) / 25) ** 2))
    c7p = c_bar_p**7
    r_c = 2 * np.sqrt(c7p / (c7p + 25.0**7))
    s_l = 1 + 0.015 * (l_bar - 50) ** 2 / np.sqrt(20 + (l_bar - 50) ** 2)
    s_c = 1 + 0.045 * c_bar_p
    s_h = 1 + 0.015 * c_bar_p * t
    r_t = -np.sin(np.radians(2 * d_theta)) * r_c
    return np.sqrt(
        (d_l / s_l) ** 2 + (d_c / s_c) ** 2 + (d_h / s_h) ** 2 + r_t * (d_c / s_c) * (d_h / s_h)
    )


def delta_e00(colour_a, colour_b) -> float:
    """ΔE00 of two matplotlib colours ("#4e79a7", (r, g, b), "0.5", …)."""
    lab = srgb_to_lab(np.array([to_rgba(colour_a), to_rgba(colour_b)]))
    return float(ciede2000(lab[0], lab[1]))


def pairwise_delta_e00(colours) -> np.ndarray:
    """(k, k) ΔE00 between every two of k matplotlib colours (0 on the diagonal)."""
    lab = srgb_to_lab(np.array([to_rgba(c) for c in colours]).reshape(-1, 4))
    return ciede2000(lab[:, None, :], lab[None, :, :])
