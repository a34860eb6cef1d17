"""Compile the map kernel with an empty cache on two cores instead of one.

numba compiles in one process, one function after the other: a cold ``campar point``
compiled for ~12 s on one core while the other idled. The chain calls one revolution
through its address (campar.core.revolution_call), so the two halves of the kernel
compile apart: a forked helper compiles one revolution (``run_revolution`` with the
integrator, the field and the events under it) into numba's on-disk cache while this
process compiles the chain (the cell's transient and classification); then this
process waits for the helper (``CompiledCallersOnly.awaiting``) and loads its
revolution from the cache. Both halves take ~6 s here (benchmarks/RESULTS.md).

The helper compiles the signature ``revolution_args`` computes, the one the chain is
linked with, so what it caches is what this process loads (tests/test_split_compile).

Forking is safe only in a process with one thread and without MPI (``campar point``,
``campar warm-up``, a serial run before its lane starts). MPI ranks on one node that
share a cache split the same way without a fork (``share_with_ranks``): ranks of even
index there compile the chain first, those of odd index the revolution, and each then
waits for the other half to reach the cache and loads it. With a warm cache nothing is
forked and nobody waits.
"""

import os
import signal
import sys
import threading
import time

from . import jitcache
from .kernel import chain_compiled, make_chain_work
from .revolution import run_revolution
from .revolution_call import revolution_args

HELPER_SECONDS = 300.0  # a helper takes ~5 s here; one still running after this is stuck
POLL_SECONDS = 0.05  # between looks into the cache for another rank's half


def cache_is_cold() -> bool:
    """No compiled chain where numba will look for it (after jitcache dropped stale entries):
    under NUMBA_CACHE_DIR, a chain cached beside the sources does not count."""
    return not any(jitcache.located_cache_dir().glob("kernel.chain_compiled-*.nbi"))


def can_fork() -> bool:
    """One thread, no MPI, two cores: a fork copies nothing that runs."""
    if not hasattr(os, "fork") or threading.active_count() != 1:
        return False
    if len(os.sched_getaffinity(0)) < 2:
        return False
    mpi = sys.modules.get("mpi4py.MPI")
    return mpi is None or not mpi.Is_initialized()


def start_helper(solver, cs) -> int | None:
    """Fork the helper that compiles one revolution into the cache; its pid, or None
    (nothing forked) when the cache is warm or forking is unsafe. The caller compiles the
    chain next, then links it to the revolution, waiting for the helper there."""
    jitcache.ensure_fresh_cache()
    if not (can_fork() and cache_is_cold()):
        return None
    cw = make_chain_work(cs)
    pid = os.fork()
    if pid == 0:  # the helper: compile, then leave without running the parent's exit code
        status = 1
        try:
            run_revolution.compile(revolution_args(solver, cs, cw))
            status = 0
        finally:
            os._exit(status)

    run_revolution.awaiting = lambda: wait_for(pid)
    return pid


def wait_for(pid: int) -> None:
    """Until the helper exits, or HELPER_SECONDS: a helper that hangs is killed and this
    process compiles what it did not deliver. Its exit status does not matter either way:
    whatever is missing from the cache is compiled here."""
    deadline = time.monotonic() + HELPER_SECONDS
    while os.waitpid(pid, os.WNOHANG) == (0, 0):
        if time.monotonic() > deadline:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            return
        time.sleep(0.005)


def reap(pid: int | None) -> None:
    """Wait for the helper if linking the revolution did not (it was loaded meanwhile)."""
    if pid is not None and run_revolution.awaiting is not None:
        run_revolution.awaiting = None
        wait_for(pid)


def share_with_ranks(share, solver, cs, chain_signature) -> None:
    """Split a cold compile with the other ranks of this node that share the cache.

    ``share``: (this rank's index, how many) among them (``wire.cache_sharers``), or None.
    Ranks of odd index compile the revolution here and then wait for the chain; ranks of
    even index return at once and wait for the revolution where they link the chain to it
    (``CompiledCallersOnly.awaiting``). The caller compiles the chain next either way:
    compiled here, or loaded from the cache. Nothing is split for one rank, or when the
    cache holds a chain already."""
    if share is None or share[1] < 2 or not cache_is_cold():
        return
    args = revolution_args(solver, cs, make_chain_work(cs))
    if share[0] % 2 == 0:
        run_revolution.awaiting = lambda: until_cached(run_revolution, args)
        return
    run_revolution.compile(args)
    until_cached(chain_compiled, chain_signature)


def until_cached(dispatcher, signature) -> None:
    """Wait until numba's cache serves ``signature`` to ``dispatcher`` (another rank
    compiles it), or HELPER_SECONDS: then the caller compiles it here instead. numba
    writes a cache entry's data before it is read, so a half-written one is not found."""
    deadline = time.monotonic() + HELPER_SECONDS
    while dispatcher._cache.load_overload(signature, dispatcher.targetctx) is None:
        if time.monotonic() > deadline:
            return
        time.sleep(POLL_SECONDS)
