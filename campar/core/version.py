"""The numerical kernel's version.

It changes whenever a change in the numerical core changes a number that a cell stores
(a label, a duty cycle, an extremum, a final state, a revolution count), so that a store
records which kernel wrote it and `campar point --from` can tell a store computed by
another kernel from one it reproduces bit for bit.
"""

KERNEL_VERSION = 9
