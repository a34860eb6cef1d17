"""The gallery's file naming: which figure a plane's map is, the planes' symbols, and the
YAML written beside every figure (its caption, force law, axes and recipe)."""

from pathlib import Path

import yaml

MAP_FIGURES = {"omega_f0": "fig2", "mu_kn": "fig4", "mu_cn": "fig7"}  # the paper's numbering
PLANE_SYMBOLS = {"omega": "ω", "f0": "f0", "mu_kn": "μkn", "mu_cn": "μcn", "zeta": "ζ"}


def write_yaml(path: Path, data: dict) -> None:
    """``data`` as block YAML, keys in their order, Greek letters as they are."""
    path.write_text(yaml.safe_dump(data, sort_keys=False, allow_unicode=True, width=100))
