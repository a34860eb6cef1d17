"""Views of the model for a person: one cell, one bifurcation line, and figures.

- ``point``: ``simulate_point`` — one cell from Python (``campar point``), with
  an optional dense trace of its steady orbit;
- ``attractors``: ``find_attractors`` — the coexisting attractors of one cell from many
  starts, with basin fractions (``campar point --attractors K``);
- ``line``: single-parameter bifurcation lines along ω by continuation (``campar line``);
- ``transitions``: ``find_transitions`` — each boundary between labels of a line typed
  (PD, SN, NS, G, chaos, jump) from its multipliers and extrema of ε;
- ``boundaries``: ``store_boundaries`` — the same typing for every edge between labels of
  a map, along both axes (``campar plot --bifurcations``);
- ``cycles``: when two sweep directions end on different cycles (``hysteresis``);
- ``basins``: the attractors of a basin store, matched across its starts;
- ``dataset``: ``open`` — a result store as a labelled, CF-annotated xarray
  Dataset, either backend, with the n-p labels as strings (``campar.open``);
- ``output``: output files checked before anything is computed (``figure_file``);
- ``plot``: figures of computed results (maps of a store, orbits, bifurcation
  diagrams); it never recomputes and never imports the kernel.

May import: ``campar.core``, ``campar.sweep``, ``campar.errors`` and itself.
"""
