"""The first step into each discrete state of a hybrid system, remembered between entries.

A step starting where the field switches (an impact, a detachment, a cam phase
boundary) sees a nonsmooth solution: right after an impact of the Hunt–Crossley
force the local error grows about like h^3, not like DOP853's h^8, so the I
controller's 1/8 power took six rejections to shrink such a step (measured on the
(ω, μcn) plane: ~5 rejected steps a revolution at ω = 5, benchmarks/RESULTS.md).
A step entering a state therefore starts from the step that state's last entry
accepted — a periodic motion enters the same states every revolution — and, when
rejected, shrinks with err^(−1/3). ``integrator.advance`` calls these; the memory
is ``StepWork.h_memory``, one slot per (mode[0], mode[1]).
"""

import math

from .jit import hot

ENTRY_ERROR_EXPONENT = 1.0 / 3.0  # the local error's growth with h at an entry: ~h^3
MEMORY_SHAPE = (8, 4)  # the states (mode[0], mode[1]) with a slot
MEMORY_SAFETY = 0.9  # aim below the tolerance, as the step control does
MEMORY_GROWTH = 1.25  # a remembered step grows at most this much an entry …
MEMORY_SHRINK = 0.8  # … and shrinks at most this much


@hot
def recall(memory, mode):
    """The step remembered for entering state ``mode`` (0: none yet)."""
    if mode[0] < memory.shape[0] and mode[1] < memory.shape[1]:
        return memory[mode[0], mode[1]]
    return 0.0


@hot
def remember(memory, mode, h, err):
    """Remember the accepted entry step h of error norm err, scaled as the step control
    would scale it for an error growing like h^3, within [MEMORY_SHRINK, MEMORY_GROWTH]."""
    if mode[0] < memory.shape[0] and mode[1] < memory.shape[1]:
        fac = MEMORY_SAFETY * math.exp(-ENTRY_ERROR_EXPONENT * math.log(max(err, 1e-10)))
        memory[mode[0], mode[1]] = h * max(MEMORY_SHRINK, min(MEMORY_GROWTH, fac))


@hot
def forget(memory):
    """Clear every slot, as at a start."""
    for i in range(memory.shape[0]):
        for j in range(memory.shape[1]):
            memory[i, j] = 0.0
