"""How campar compiles its numerical core (see jitcache for keeping the cache honest).

Two decorators. ``hot`` for the per-step path: numba's reference counting off.
Each array passed down a call (and the stepper passes ~10 of them, in named
tuples) otherwise costs an atomic increment and decrement that numba's pruning
pass does not remove across calls; measured with numba 0.68 on this machine,
one revolution took 195 µs with it and 70 µs without (perf: 67 % of the time
in NRT_incref/NRT_decref). ``hot`` functions must not allocate or return
arrays; numba refuses to compile them if they do. Buffers are allocated in
Python (``make_work``, ``make_chain_work``) and handed down.

``inlined`` for the kernel's per-cell layer (a cell, its transient, one
revolution's bookkeeping): inlined into the chain at numba's IR level, so it is
typed and compiled once, as part of the entry point. As separate functions each
of them was compiled on its own and then again, LLVM-optimised and turned into
machine code, inside every caller (numba links callees into the caller's
module), and numba compiled literal-argument variants of some (four of
``step_revolution``): 22.7 → 17.9 CPU s of compilation with an empty cache
(measured with numba 0.68). Only for functions with few call sites: inlining
the integrator too made the entry point's compilation slower (27.6 s).
"""

from numba import njit

hot = njit(cache=True, _nrt=False)
inlined = njit(_nrt=False, inline="always")
