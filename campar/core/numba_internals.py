"""The private numba calls campar makes, in one place, each with a fallback.

campar looks into a dispatcher's on-disk cache (``Dispatcher._cache``, numba's
``FunctionCache``) for two things no public API gives:

- where the cache keeps a function's compiled code (``cache_path``), so that stale entries
  of the numerical core can be cleared (``campar.core.jitcache``);
- whether the cache serves a signature yet (``load_overload``), so that a process can wait
  for the half of a cold compile another process is compiling
  (``campar.core.split_compile``), and whether its index names one (``_index_key`` and
  the cache file's ``_load_index``), so that a job whose laws are not cached yet splits
  its cold compile.

Both have kept their names and meaning across the numba versions pyproject.toml allows
(``SUPPORTED``). A numba that changes them must not break a fresh install: then
``cache_path`` returns None (jitcache falls back to the directories numba documents) and
``cache_serves`` returns None, ``split_available`` is False, and campar compiles the
whole kernel in every process, as numba alone would — slower on a cold cache, the same
results.
"""

import os
from pathlib import Path

SUPPORTED = ">=0.60,<0.69"  # the numba range pyproject.toml allows and the tests run
CACHE_ATTRIBUTE = "_cache"  # Dispatcher._cache: its FunctionCache (None without cache=True)


def function_cache(dispatcher):
    """The dispatcher's FunctionCache, or None where this numba has none we know."""
    cache = getattr(dispatcher, CACHE_ATTRIBUTE, None)
    if cache is None or not hasattr(cache, "cache_path") or not hasattr(cache, "load_overload"):
        return None
    return cache


def cache_path(dispatcher) -> Path | None:
    """The directory numba reads ``dispatcher``'s compiled code from, or None."""
    cache = function_cache(dispatcher)
    return None if cache is None else Path(cache.cache_path)


def cache_serves(dispatcher, signature) -> bool | None:
    """Whether numba's on-disk cache holds ``signature`` of ``dispatcher`` whole (numba
    indexes an entry before it writes the entry's data, under a temporary name it then
    renames: an entry whose data is not there yet is not served); None where this numba
    cannot be asked."""
    cache = function_cache(dispatcher)
    if cache is None:
        return None
    try:
        return cache.load_overload(signature, dispatcher.targetctx) is not None
    except (AttributeError, TypeError):  # a signature of its arguments it no longer takes
        return None


def cache_indexes(dispatcher, signature) -> bool | None:
    """Whether numba's on-disk cache names ``signature`` of ``dispatcher`` in its index
    (nothing is loaded: ``FunctionCache._index_key`` and its cache file's index); None
    where this numba cannot be asked."""
    cache = function_cache(dispatcher)
    try:
        key = cache._index_key(tuple(signature), dispatcher.targetctx.codegen())
        return key in cache._cache_file._load_index()
    except (AttributeError, TypeError):
        return None


def split_available(dispatcher) -> bool:
    """Whether a cold compile may be split between processes: this numba's cache can be
    asked for ``dispatcher``'s entries."""
    return function_cache(dispatcher) is not None


def documented_cache_dirs(source_dir: Path) -> list[Path]:
    """Where numba's documentation says it caches the functions of ``source_dir``: the
    ``__pycache__`` beside the sources, and under ``NUMBA_CACHE_DIR`` the subdirectories
    that hold entries of this package (numba names them after the source directory)."""
    dirs = [source_dir / "__pycache__"]
    root = os.environ.get("NUMBA_CACHE_DIR")
    if root and Path(root).is_dir():
        dirs += sorted({p.parent for p in Path(root).rglob("kernel.chain_compiled-*.nbi")})
    return dirs


def check_blas_without_scipy() -> None:
    """Let numba's first load of compiled code skip importing scipy.linalg.

    numba's CPU target imports ``numba.np.arraymath`` the first time a process types or
    loads a function, and that module imports scipy.linalg (through ``numba.np.linalg``'s
    ``ensure_blas``) only to set ``_HAVE_BLAS``, which picks np.convolve's and
    np.correlate's inner product; the import is about half of loading the cached kernel
    (benchmarks/RESULTS.md). Here ``_HAVE_BLAS`` is set from whether SciPy is installed,
    without importing it. numba's linear algebra still imports scipy.linalg, and checks
    its BLAS, when a function that uses it is compiled. A numba without these names, or a
    process that has imported either module already, is left as it is."""
    import importlib.util
    import sys

    if "numba.np.arraymath" in sys.modules or "scipy.linalg" in sys.modules:
        return
    try:
        from numba.np import linalg
    except ImportError:
        return
    check = getattr(linalg, "ensure_blas", None)
    if check is None:
        return

    def unasked() -> None:
        raise ImportError("asked without importing SciPy")

    linalg.ensure_blas = unasked
    try:
        from numba.np import arraymath
    finally:
        linalg.ensure_blas = check
    if getattr(arraymath, "ensure_blas", None) is unasked:
        arraymath.ensure_blas = check
    if hasattr(arraymath, "_HAVE_BLAS"):
        arraymath._HAVE_BLAS = importlib.util.find_spec("scipy") is not None
