"""Output files of the views, checked before anything is computed or drawn.

A figure or an array file is written at the very end of a command, after
minutes of computing perhaps: a directory that cannot be written, or a suffix
no writer knows, must be found out first. ``writable_file`` creates a probe
file in the target folder, then removes the probe; a folder that does not
exist is refused, never created (a typo in a path must not make folders
anywhere); ``figure_file`` also checks that matplotlib writes the suffix.
Both raise OutputError (exit 73) with one line saying what to change.
"""

import os
import tempfile
from pathlib import Path

from ..errors import OutputError


def writable_file(path: str | Path, what: str = "output") -> Path:
    """``path`` if a file can be written there (its folder must exist)."""
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"cannot write the {what} {path}: it is a directory; name a file")
    if path.exists() and not os.access(path, os.W_OK):
        raise OutputError(f"cannot write the {what} {path}: the file is read-only")
    folder = path.parent
    if not folder.is_dir():
        why = (
            f"{folder} is a file, not a folder"
            if folder.exists()
            else (f"the folder {folder} does not exist; create it, or choose another path")
        )
        raise OutputError(f"cannot write the {what} {path}: {why}")
    try:
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".campar-probe-"):
            pass
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise OutputError(
            f"cannot write the {what} {path}: {reason} ({folder}); choose another path"
        ) from None
    return path


def figure_file(path: str | Path) -> Path:
    """``path`` if matplotlib writes its format (from the suffix) and the file can be written."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    path = Path(path)
    formats = FigureCanvasAgg.get_supported_filetypes()
    suffix = path.suffix.lower().lstrip(".")
    if suffix not in formats:
        known = ", ".join(f".{s}" for s in ("png", "pdf", "svg") if s in formats)
        got = f"a .{suffix} file" if suffix else "a file without a suffix"
        raise OutputError(
            f"cannot write the figure {path}: {got} has no image format matplotlib knows; "
            f"name it {known} (or another of {', '.join(sorted(formats))})"
        )
    return writable_file(path, "figure")
