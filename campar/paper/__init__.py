"""The study of one paper: its set-ups, its claims, its figure set, the report.

The source study (a cam with a flat-bottomed follower and Hunt–Crossley
contact) is reproduced with the library below; nothing in the library depends
on this package.

- ``setups``: the paper's planes, lines, portraits and quoted numbers, as data
  and the small computations behind them;
- ``claims``, ``map_claims``: each quantitative claim with its stated test;
- ``gallery``: the whole figure set (``campar gallery``);
- ``report``: the reproduction report docs/paper.md (``campar report``).

May import: ``campar.core``, ``campar.sweep``, ``campar.views``, ``campar.errors``.
"""
