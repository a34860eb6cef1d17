"""The sweep machinery: from a job file to a finished, resumable store of a map.

- ``job``: the YAML schema, the paper's base values and every default, validation;
  ``job_file``: a job file read with bounds (size, encoding, keys, aliases, numbers, store
  paths), its problems in one line;
- ``plan``: tiles and continuation chains of the grid, pending tiles;
- ``arrays``: what each requested output stores (names, dtypes, shapes);
- ``tile``: one tile through the kernel (``run_tile``) and the kernel settings
  built from a job, in one place;
- ``census``: which records of one cell are one attractor (the start spread, the
  grouping rules; numpy only), for ``campar point --attractors``, maps and hysteresis;
- ``multistable``: starts run one cell at a time (``run_starts``, for basins too) and the
  census of coexisting attractors at every cell of a map (job key
  ``attractors``), through the kernel;
- ``basin``: a basin job's tile — every cell run from its own start (y0, ydot0);
- ``runner``: the serial runner and the MPI master/workers, ``tiles.rows: auto``;
- ``wire``: the master–worker protocol over MPI, workers writing their own tiles;
- ``signals``: stop signals over a run's whole life (before, during, after it);
- ``budget``: a job's store size and per-rank memory, estimated, and their limits;
- ``progress``: the live progress line, the run log, ``campar status`` and ``verify``;
- ``store``: Zarr and HDF5 backends behind one interface, commit flags and checksums,
  verification and repair, lock.

May import: ``campar.core``, ``campar.errors`` and itself. ``wire`` is the only
module of campar that imports mpi4py; ``store`` imports nothing of the
integration (``core`` beyond its codes).
"""
