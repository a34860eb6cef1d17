"""Keep numba's on-disk cache honest across edits of the numerical core.

numba invalidates a cached function when *its own* source file changes, not
when a function it inlined from another file does: after an edit of
core/integrator.py, kernel.run_chain would still load the old integrator from the
cache. So before the kernel is first used, a digest of every compiled module
is compared with the one the cache was built from, and a mismatch clears the
cached entries of those modules.
"""

import functools
import hashlib
import os
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent
COMPILED_MODULES = (
    "jit", "codes", "hermite", "dop853", "entry_steps", "model", "integrator", "analysis",
    "revolution", "kernel",
)  # fmt: skip
STAMP = "campar-core.digest"


def core_digest() -> str:
    digest = hashlib.sha256()
    for name in COMPILED_MODULES:
        digest.update((PACKAGE / f"{name}.py").read_bytes())
    return digest.hexdigest()


def cache_dirs() -> list[Path]:
    """Where numba keeps this package's cache: beside the sources, or NUMBA_CACHE_DIR."""
    dirs = [PACKAGE / "__pycache__"]
    if os.environ.get("NUMBA_CACHE_DIR"):
        dirs.append(Path(os.environ["NUMBA_CACHE_DIR"]))
    return dirs


@functools.cache
def ensure_fresh_cache() -> None:
    """Drop cached compiled functions of the core if its sources changed since.

    Called explicitly before the kernel first runs in a process (``run_tile``,
    the CLI); once per process, later calls return at once.
    """
    want = core_digest()
    for directory in cache_dirs():
        stamp = directory / STAMP
        try:
            if stamp.read_text() == want:
                continue
        except OSError:
            pass
        if not directory.is_dir():
            continue
        for entry in directory.iterdir():
            module = entry.name.split(".", 1)[0]
            if module in COMPILED_MODULES and entry.suffix in (".nbi", ".nbc"):
                entry.unlink(missing_ok=True)
        try:
            tmp = directory / f"{STAMP}.{os.getpid()}"
            tmp.write_text(want)
            tmp.replace(stamp)
        except OSError:
            pass  # a read-only install: numba then caches elsewhere or not at all
