"""The numerical core: the model, its integration and the analysis of one cell, compiled.

Everything here is numba code (or constants it folds) and knows nothing of
jobs, files, MPI or figures:

- ``codes``: status, kind and flag codes of a cell, and their text;
- ``jit``, ``jitcache``: how the core is compiled, and keeping numba's cache honest;
- ``model``: the cam law, Hunt–Crossley contact force, the vector field;
- ``hermite``: cubic Hermite models over one step (event roots, extremes);
- ``integrator``: DP5(4), DOP853 and RK4 with dense output, breakpoints and events
  (knows no cam: it sees a field, breakpoints and event functions);
- ``dop853``: the Dormand–Prince 8(5,3) tableau, its step, error estimate and dense output;
- ``analysis``: section maps, period and detachments, multipliers, Lyapunov exponent;
- ``revolution``: one cam revolution of the hybrid system, and its trace;
- ``kernel``: one cell, a continuation chain of cells, one traced orbit;
- ``split_compile``: a cold compile of the kernel on two cores (a forked helper).

May import: numpy, numba, ``campar.errors`` and itself. Nothing else of campar.
"""
