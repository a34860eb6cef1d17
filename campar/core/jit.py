"""How campar compiles its numerical core (see jitcache for keeping the cache honest).

Three decorators. ``hot`` for the per-step path: numba's reference counting off.
Each array passed down a call (and the stepper passes ~10 of them, in named
tuples) otherwise costs an atomic increment and decrement that numba's pruning
pass does not remove across calls: with reference counting on, a revolution
takes several times as long, most of it in NRT_incref/NRT_decref (numba 0.68).
``hot`` functions must not allocate or return
arrays; numba refuses to compile them if they do. Buffers are allocated in
Python (``make_work``, ``make_chain_work``) and handed down.

``inlined`` for the kernel's per-cell layer (a cell, its transient, one
revolution's bookkeeping): inlined into the chain at numba's IR level, so it is
typed and compiled once, as part of the entry point. A separate function is
compiled on its own and then again, LLVM-optimised and turned into machine code,
inside every caller (numba links callees into the caller's module), and numba
compiles literal-argument variants of some: inlining them shortens a cold compile
(numba 0.68). Only for functions with few call sites: inlining the
integrator too makes the entry point's compilation slower.

``hot`` functions have no CPython wrapper and no C callback (numba's ``@overload``
default, for functions only compiled code calls). A dispatcher otherwise compiles both,
which unbox every argument (named tuples of ~10 arrays): more IR for LLVM to optimise
and turn into machine code in every library; leaving them out shortens a cold
``campar point``'s compile (numba 0.68). Without a wrapper numba's entry
pointer is null and a call from Python would crash the interpreter, so a ``hot``
function raises TypeError there: Python calls ``entry`` functions, and tests reach
the others through ``through_numba``.

``entry`` for the few ``hot``-like functions Python calls (the buffers' set-up); the
kernel's entry points (``kernel.chain_compiled``, ``tracer.trace_compiled``) have their own options.
"""

import contextlib
import functools
import gc

from numba import njit
from numba.core.registry import CPUDispatcher


class CompiledCallersOnly(CPUDispatcher):
    """A dispatcher without a Python entry: compiled callers only.

    ``awaiting``: while set, called with the signature before this dispatcher compiles it
    (the split compile waits there for a helper or another rank that puts it into the
    on-disk cache)."""

    awaiting = None

    def compile(self, sig):
        if self.awaiting is not None:
            self.awaiting(sig)
        return super().compile(sig)

    def __call__(self, *args, **kwargs):
        raise TypeError(
            f"{self.py_func.__qualname__} is compiled for compiled callers only "
            "(campar.core.jit.hot): call it through through_numba"
        )


def hot(function):
    options = {
        "nopython": True,
        "_nrt": False,
        "no_cpython_wrapper": True,
        "no_cfunc_wrapper": True,
    }
    dispatcher = CompiledCallersOnly(py_func=function, locals={}, targetoptions=options)
    dispatcher.enable_caching()
    return dispatcher


@contextlib.contextmanager
def collector_paused():
    """Python's cyclic garbage collector off while numba compiles. A cold kernel compile
    builds millions of objects (types, IR, LLVM wrappers) that live until it ends, and the
    collector's full passes walk them again and again: with it paused a cold
    ``campar point`` is faster, at a higher memory peak (numba 0.68). The cycles it
    leaves are collected once it is back on."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


inlined = njit(_nrt=False, inline="always")
entry = njit(cache=True, _nrt=False)


@functools.cache
def through_numba(function):
    """``function`` (a ``hot`` one) callable from Python: a compiled trampoline to it."""

    @njit
    def trampoline(*args):
        return function(*args)

    return trampoline
