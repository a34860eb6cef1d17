"""The numerical core: the model, its integration and the analysis of one cell, compiled.

Everything here is numba code (or constants it folds) and knows nothing of
jobs, files, MPI or figures:

- ``codes``: status, kind and flag codes of a cell, and their text;
- ``jit``, ``jitcache``: how the core is compiled, and keeping numba's cache honest;
- ``model``: the cam law, Hunt–Crossley contact force, the vector field;
- ``hermite``: cubic and quintic Hermite models over one step (event roots, where extremes lie);
- ``integrator``: DP5(4), DOP853 and RK4 step control, breakpoints and events (knows no
  cam: it sees a field, breakpoints and event functions);
- ``stages``: one Runge–Kutta step's stages, error norm and dense output;
- ``event_roots``: the first root of an event function inside a trial step;
- ``dop853``, ``dopri5``: the Dormand–Prince 8(5,3) and 5(4) tableaux, error estimates and
  dense outputs;
- ``analysis``: section maps, period and detachments, multipliers, Lyapunov exponent;
- ``revolution``: one cam revolution of the hybrid system, and its trace;
- ``extrema``: ε's and Pn's extremes inside a step, located on the dense output;
- ``transient``: a cell's transient under the job's policy (converged or fixed);
- ``kernel``: one cell, a continuation chain of cells, one traced orbit;
- ``split_compile``: a cold compile of the kernel on two cores (a forked helper).

May import: numpy, numba, ``campar.errors`` and itself. Nothing else of campar.
"""
