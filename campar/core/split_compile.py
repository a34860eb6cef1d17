"""Compile the map kernel with an empty cache on two cores instead of one.

numba compiles in one process, one function after the other, on one core while the
other idles. The chain calls one revolution
through its address (campar.core.revolution_call), so the two halves of the kernel
compile apart: a forked helper compiles one revolution (``run_revolution`` with the
integrator, the field and the events under it) into numba's on-disk cache while this
process compiles the chain (the cell's transient and classification); then this
process waits for the helper's cache entry (``CompiledCallersOnly.awaiting``) and loads
it. Where the command will trace an orbit, the helper compiles the revolution with a
recorder next, for the tracer. The halves take about as long as each other (benchmarks/
RESULTS.md has a cold ``campar point``'s time).

The helper compiles the signatures ``revolution_args`` computes, those the chain and the
tracer are linked with, so what it caches is what this process loads
(tests/test_split_compile).

Forking is safe only in a process with one thread and without MPI (``campar point``,
``campar warm-up``, a serial run before its lane starts). MPI ranks on one node that
share a cache split the same way without a fork (``share_with_ranks``): ranks of even
index there compile the chain first, those of odd index the revolution, and each then
waits for the other half to reach the cache and loads it. With a warm cache nothing is
forked and nobody waits. The cache is cold for a job when it lacks the revolution that
job's laws need (``numba_internals.cache_indexes``): a job of another cam or contact law
splits its own cold compile even where the paper's kernel is cached.
"""

import os
import signal
import sys
import threading
import time

from numba import typeof, types

from . import jitcache, numba_internals
from .kernel import chain_compiled, make_chain_work
from .model import PAPER_LAW
from .revolution import make_trace, run_revolution
from .revolution_call import revolution_args

HELPER_SECONDS = 300.0  # far beyond a compile on a loaded machine: a helper still running is stuck
POLL_SECONDS = 0.05  # between looks into the cache for another rank's half


def cold_for(dispatcher, signatures) -> bool:
    """numba's cache lacks ``dispatcher`` for one of ``signatures`` (its index does not name
    it); False where the cache cannot be asked (``numba_internals``): nothing is split then."""
    if not numba_internals.split_available(dispatcher):
        return False
    found = [numba_internals.cache_indexes(dispatcher, s) for s in signatures]
    return None not in found and not all(found)


def can_fork() -> bool:
    """One thread, no MPI, two cores: a fork copies nothing that runs."""
    if not hasattr(os, "fork") or threading.active_count() != 1:
        return False
    if len(os.sched_getaffinity(0)) < 2:
        return False
    mpi = sys.modules.get("mpi4py.MPI")
    return mpi is None or not mpi.Is_initialized()


class Helper:
    """A forked process compiling into numba's cache, seen from the process that forked it."""

    def __init__(self, pid: int):
        self.pid, self.exited = pid, False

    def running(self) -> bool:
        if not self.exited and os.waitpid(self.pid, os.WNOHANG) != (0, 0):
            self.exited = True
        return not self.exited

    def wait(self) -> None:
        """Until it exits, or HELPER_SECONDS: a helper that hangs is killed. Its exit status
        does not matter: whatever is missing from the cache is compiled here."""
        deadline = time.monotonic() + HELPER_SECONDS
        while self.running():
            if time.monotonic() > deadline:
                self.kill()
                return
            time.sleep(0.005)

    def kill(self) -> None:
        if self.running():
            os.kill(self.pid, signal.SIGKILL)
            os.waitpid(self.pid, 0)
            self.exited = True


def start_helper(solver, cs, trace: bool = False, law=PAPER_LAW) -> Helper | None:
    """Fork the helper that compiles the revolution for ``law`` (model.Law) into the cache,
    then with ``trace`` its variant with a recorder (the orbit tracer's); None (nothing
    forked) when the cache holds them or forking is unsafe. The caller compiles the chain
    (and the tracer) next, then links them to the revolution: it waits there for the
    helper's cache entries."""
    jitcache.ensure_fresh_cache()
    if not can_fork():
        return None
    work = make_chain_work(cs).w6
    recorders = [types.none, typeof(make_trace(0, 0, 1))] if trace else [types.none]
    signatures = [revolution_args(solver, cs, work, recorder, law) for recorder in recorders]
    if not cold_for(run_revolution, signatures):
        return None
    pid = os.fork()
    if pid == 0:  # the helper: compile, then leave without running the parent's exit code
        status = 1
        try:
            for signature in signatures:
                run_revolution.compile(signature)
            status = 0
        finally:
            os._exit(status)

    helper = Helper(pid)
    await_revolutions(signatures, helper)
    return helper


def await_revolutions(signatures, helper: Helper | None = None) -> None:
    """Before this process compiles run_revolution for one of ``signatures`` (those the
    helper, or another rank, delivers), wait for it in the cache (``until_cached``)."""

    def awaiting(signature):
        if tuple(signature) in signatures:
            until_cached(run_revolution, signature, helper)

    run_revolution.awaiting = awaiting


def reap(helper: Helper | None) -> None:
    """Stop waiting for cache entries, and for the helper once it has exited."""
    run_revolution.awaiting = None
    if helper is not None:
        helper.wait()


def share_with_ranks(share, solver, cs, chain_signature, law=PAPER_LAW) -> None:
    """Split a cold compile with the other ranks of this node that share the cache.

    ``share``: (this rank's index, how many) among them (``wire.cache_sharers``), or None.
    Ranks of odd index compile the revolution here and then wait for the chain; ranks of
    even index return at once and wait for the revolution where they link the chain to it
    (``CompiledCallersOnly.awaiting``). The caller compiles the chain next either way:
    compiled here, or loaded from the cache. Nothing is split for one rank, or when the
    cache holds this chain already."""
    if share is None or share[1] < 2 or not cold_for(chain_compiled, [chain_signature]):
        return
    revolution = revolution_args(solver, cs, make_chain_work(cs).w6, law=law)
    if share[0] % 2 == 0:
        await_revolutions([revolution])
        return
    run_revolution.compile(revolution)
    until_cached(chain_compiled, chain_signature)


def until_cached(dispatcher, signature, helper: Helper | None = None) -> None:
    """Wait until numba's cache serves ``signature`` to ``dispatcher`` (a helper or another
    rank compiles it), the helper has exited, or HELPER_SECONDS have passed (a helper still
    running is killed): then the caller compiles what is missing here. numba names an
    entry in its index before it writes the entry's data, whole, under a temporary name
    that it then renames: an entry whose data is not there yet is not found. Where numba's
    cache cannot be asked (``numba_internals``) it returns at once."""
    deadline = time.monotonic() + HELPER_SECONDS
    while numba_internals.cache_serves(dispatcher, signature) is False:
        if helper is not None and not helper.running():
            return
        if time.monotonic() > deadline:
            if helper is not None:
                helper.kill()
            return
        time.sleep(POLL_SECONDS)
