"""Numerical continuation of periodic orbits: what lies between the attractors of a map.

A periodic orbit of period n revolutions is a fixed point of the stroboscopic map Pⁿ at
θ = 0 (campar.core.shooting gives Pⁿ with its exact Jacobian DPⁿ). On top of that:

- ``section_map``: Pⁿ, DPⁿ and the parameter derivative ∂Pⁿ/∂λ (central differences)
  for any parameter of the model;
- ``orbit``: a periodic orbit, stable or not, by Newton's method (``find_cycle``);
- ``branch``: pseudo-arclength continuation of an orbit along one parameter, through
  folds, with its multipliers, stability and n-p label at every point;
- ``branch_result``: a continued branch as a record (``Branch``) and its JSON;
- ``special``: the test functions of period doubling (PD), fold (SN), branch point
  (BP), Neimark–Sacker (NS) and grazing (G), and their location on a branch;
- ``switching``: branch switching at a PD onto the doubled branch, recursively;
- ``curves``: two-parameter curves of PD, SN, NS and G points (augmented systems);
- ``mapscale``: curves seeded from a map store's typed edges, run as tasks, stored
  beside the map.

May import: campar.core, campar.sweep, campar.errors.
"""
