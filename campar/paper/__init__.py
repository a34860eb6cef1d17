"""The study of one paper: its set-ups, its claims, its figure set, the report.

The source study (a cam with a flat-bottomed follower and Hunt–Crossley
contact) is reproduced with the library below; nothing in the library depends
on this package.

- ``setups``: the paper's planes, lines, portraits and quoted numbers, as data
  and the small computations behind them;
- ``claims``, ``map_claims``: each quantitative claim's test; ``claim_list``: the
  claims (``CLAIMS``) in the report's order;
- ``robust``, ``liouville``: how a label claim is judged robust; the multipliers'
  determinant against Liouville's formula;
- ``gallery``: the whole figure set (``campar gallery``); ``figure_files`` names its
  files and writes the YAML beside each figure;
- ``structure``: the attractor-structure jobs of the three planes (both sweep
  directions, censuses, recomputed zooms); ``structure_stats`` counts jumps, tongues
  and irreversible transitions from their stores, ``structure_figures`` draws them,
  ``structure_report`` writes their section of the report;
- ``report``: the reproduction report docs/paper.md (``campar report``).

May import: ``campar.core``, ``campar.sweep``, ``campar.views``, ``campar.errors``.
"""
