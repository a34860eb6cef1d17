"""Test modules' own compiled helpers, kept in numba's on-disk cache and kept honest.

A test module that drives the core through a small ``@njit`` function of its own (a step,
a probe, a reference) compiles it, and the core's functions it calls into it, in every
session: 5–10 CPU seconds a helper. ``cached_njit`` caches it on disk like the core's own
functions. numba invalidates a cached function when its own source file changes, not when
a core function it compiled in does, so the first ``cached_njit`` of a process compares
the core's digest (``campar.core.jitcache.core_digest``, the one the core's cache is kept
by) with the one the tests' cache directory was built from, and on a mismatch drops that
directory's entries: a test never runs a helper compiled against an older core.

For helpers that take no jitted function as an argument: one that does misses numba's
on-disk cache in every new process anyway (STYLE.md, numba caching).
"""

import functools
import os
from pathlib import Path

from numba import njit

from campar.core import numba_internals
from campar.core.jitcache import core_digest

STAMP = "campar-core.digest"


@functools.cache
def _fresh(directory: Path) -> None:
    want = core_digest()
    stamp = directory / STAMP
    try:
        if stamp.read_text() == want:
            return
    except OSError:
        pass
    if directory.is_dir():
        for entry in directory.iterdir():
            if entry.suffix in (".nbi", ".nbc"):
                entry.unlink(missing_ok=True)
    try:
        directory.mkdir(parents=True, exist_ok=True)
        tmp = directory / f"{STAMP}.{os.getpid()}"
        tmp.write_text(want)
        tmp.replace(stamp)
    except OSError:
        pass  # nowhere to write: numba then compiles in this process only


def cached_njit(function):
    """``numba.njit(cache=True)(function)``, its cache dropped whenever the core changed."""
    dispatcher = njit(cache=True)(function)
    directory = numba_internals.cache_path(dispatcher)
    if directory is not None:
        _fresh(directory)
    return dispatcher
