"""The browser explorer of result stores (``campar explore STORE [STORE2]``).

- ``fields``: what a map can show of a cell (labels, kinds, duty cycle, ε, Pn, Lyapunov
  exponent, multipliers, flags), computed from a tile's stored arrays;
- ``source``: a store as the explorer reads it — its committed tiles verified against
  their checksums as ``campar.open`` does (damaged ones masked, not drawn), kept in memory
  at a stride that bounds the server's memory, the tiles a run commits taken in as they
  come, and a view's cells chosen one per screen pixel;
- ``render``: a view's cells as an image (the maps' palette, hatched gaps) and its legend;
- ``cells``: one cell computed again as ``campar point`` computes it (``cell_at``), and the
  page's other computations (a census, a cycle, branches, typed edges);
- ``lines``: bifurcation lines through the map — a row, a column, a segment between two
  cells — each one warm-started chain as ``campar line`` runs one;
- ``worker``: the process they run in, which a time limit can end;
- ``zoom``: a rectangle of a map recomputed at full resolution by the runner, a store of
  its own beside the map (a small one in a process kept warm for zooms);
- ``server``: the HTTP server (standard library) and its routes; ``static/``: the page;
- ``chromium``: the headless browser the page's tests and benchmark drive.

May import: ``campar.core``, ``campar.sweep``, ``campar.continuation``, ``campar.views``,
``campar.errors`` and itself.
"""
