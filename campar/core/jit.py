"""How campar compiles its numerical core (see jitcache for keeping the cache honest).

Two decorators: ``compiled`` for functions that allocate (NRT on), ``hot`` for
the per-step path. ``hot`` turns numba's reference counting off: each array
passed down a call (and the stepper passes ~10 of them, in named tuples)
otherwise costs an atomic increment and decrement that numba's pruning pass
does not remove across calls; measured with numba 0.68 on this machine, one
revolution took 195 µs with it and 70 µs without (perf: 67 % of the time in
NRT_incref/NRT_decref). ``hot`` functions must not allocate or return arrays;
numba refuses to compile them if they do.
"""

from numba import njit

compiled = njit(cache=True)
hot = njit(cache=True, _nrt=False)
