"""What a figure can be asked for: the views by name, a zoom range, and the error when it
cannot be drawn as asked. Cheap to import (no matplotlib): the CLI names the views with it."""

import argparse
import math

from ...errors import CamparError


class PlotError(CamparError):
    """A figure cannot be drawn as asked (unknown view, empty zoom, array missing)."""


# What ``plot_map`` / ``campar plot --what`` can draw.
MAP_VIEWS = (
    "labels",
    "kind",
    "n",
    "p",
    "dc",
    "eps_max",
    "eps_min",
    "pn_max",
    "revolutions",
    "lyapunov",
    "hysteresis",
    "multistability",
    "attractor_sets",
)
# What ``campar plot --what`` can draw of a store: the map views, and a basin store's one.
STORE_VIEWS = (*MAP_VIEWS, "basin")


def parse_range(text: str) -> tuple[float, float]:
    """A range of ``campar plot --omega/--second`` and ``campar line --omega``: "2.5:3" →
    (2.5, 3.0); either order (the users sort it), two different finite numbers."""
    parts = text.split(":")
    try:
        if len(parts) != 2:
            raise ValueError
        low, high = float(parts[0]), float(parts[1])
        if not (math.isfinite(low) and math.isfinite(high)):
            raise ValueError
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected A:B with two finite numbers, got {text!r}"
        ) from None
    if low == high:
        raise argparse.ArgumentTypeError(f"expected A:B with A != B (an interval), got {text!r}")
    return low, high
