"""Keep numba's on-disk cache honest across edits of the numerical core.

numba invalidates a cached function when *its own* source file changes, not
when a function it inlined from another file does: after an edit of
core/integrator.py, kernel.run_chain would still load the old integrator from the
cache. So before the kernel is first used, a digest of every compiled module
is compared with the one the cache was built from, and a mismatch clears the
cached entries of those modules. jit.py is part of the digest: numba's index keys
an entry by signature and CPU only, not by the options it was compiled with (a
``hot`` function's entry without a CPython wrapper would load into an ``entry``).
"""

import functools
import hashlib
import os
from pathlib import Path

from . import numba_internals

PACKAGE = Path(__file__).resolve().parent
COMPILED_MODULES = (
    "jit",
    "codes",
    "hermite",
    "dop853",
    "dopri5",
    "entry_steps",
    "cam",
    "contact",
    "model",
    "stages",
    "event_roots",
    "integrator",
    "analysis",
    "extrema",
    "deferred",
    "revolution",
    "revolution_call",
    "transient",
    "kernel",
    "tracer",
    "shooting",
)
STAMP = "campar-core.digest"


def core_digest() -> str:
    digest = hashlib.sha256()
    for name in COMPILED_MODULES:
        digest.update((PACKAGE / f"{name}.py").read_bytes())
    return digest.hexdigest()


def cache_dirs() -> list[Path]:
    """Where numba keeps the core's compiled functions: the directory its cache locator
    chose for the core's sources (beside them; under NUMBA_CACHE_DIR, a subdirectory named
    after the source directory and its hash; numba's user-wide cache for a read-only
    install), and the in-tree ``__pycache__``. Every module of the core shares it. Where
    numba's cache cannot be asked (``numba_internals``), the directories numba documents."""
    from .kernel import chain_compiled  # defines the dispatchers, compiles nothing

    located, in_tree = numba_internals.cache_path(chain_compiled), PACKAGE / "__pycache__"
    if located is None:
        return numba_internals.documented_cache_dirs(PACKAGE)
    return [in_tree] if located == in_tree else [in_tree, located]


def located_cache_dir() -> Path | None:
    """The one directory numba reads the core's compiled functions from in this process;
    None where numba's cache cannot be asked (``numba_internals``)."""
    from .kernel import chain_compiled  # defines the dispatchers, compiles nothing

    return numba_internals.cache_path(chain_compiled)


@functools.cache
def ensure_fresh_cache() -> None:
    """Drop cached compiled functions of the core if its sources changed since.

    Called explicitly before the kernel first runs in a process (``run_tile``,
    the CLI); once per process, later calls return at once.
    """
    numba_internals.check_blas_without_scipy()  # before numba's first load: see there
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
