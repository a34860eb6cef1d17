"""The store interface: what a run writes (``Store``) and what views read (``StoreReader``).

For developers — a backend implements:

- ``create(path, job)``: build a complete new store, atomically (a killed
  creation leaves no store, only a temporary name ``clean_leftovers`` removes);
- ``read_attrs(path)``: the store's attributes, or None if ``path`` is not a
  campar store of this backend;
- ``clean_leftovers(path)``: remove what a killed writer left behind and
  finish any commit it left half done;
- a ``Store`` subclass with ``_write_tile``, ``_write_runs`` and ``_close``;
- a ``StoreReader`` subclass with ``_read``, ``_done`` and ``close`` (and
  ``journaled`` if committed tiles can wait outside the store's arrays);
- the layout and attributes of ``_schema.store_arrays`` and ``initial_attrs``,
  so that xarray opens every backend to the same Dataset.

The commit protocol every backend keeps: a tile's arrays are durable before
its ``done`` flag is, so ``done`` never claims a tile whose data a kill lost.
"""

from abc import ABC, abstractmethod
from pathlib import Path

import numpy as np

from ..job import Job
from ..plan import Tile, plan_tiles
from ._lock import StoreLock
from ._schema import cell_arrays, check_tile_arrays, coordinates


class StoreReader(ABC):
    """Read-only view of a store: no lock, safe while a run writes it."""

    def __init__(self, path: Path, attrs: dict):
        self.path = path
        self.attrs = attrs
        self.job = Job.from_dict(attrs["job"], source=f"job stored in {path}")
        self.format = attrs.get("campar_store")
        self.names = [a.name for a in cell_arrays(self.job)]
        self.coords = coordinates(self.job)

    @property
    def done(self) -> np.ndarray:
        """Commit flag per tile (bool, one per tile of ``plan_tiles(job)``)."""
        return self._done()

    def read(self, name: str) -> np.ndarray:
        """A per-cell array over (second, omega[, tail]); uncomputed cells hold the fill."""
        if name not in self.names:
            raise KeyError(f"{self.path} has no array {name!r}; it has {', '.join(self.names)}")
        return self._read(name)

    @property
    def journaled(self) -> dict[int, dict[str, np.ndarray]]:
        """Committed tiles whose arrays are not in the store's own arrays yet, by tile
        index (HDF5 between checkpoints); ``read`` and ``done`` include them already."""
        return {}

    @abstractmethod
    def _done(self) -> np.ndarray: ...

    @abstractmethod
    def _read(self, name: str) -> np.ndarray: ...

    @abstractmethod
    def close(self) -> None: ...

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class Store(ABC):
    """A store opened for one run: holds the lock; the only writer."""

    def __init__(self, path: Path, job: Job, lock: StoreLock, runs: list):
        self.path = path
        self.job = job
        self.tiles = plan_tiles(job)
        self._lock = lock
        self._runs = list(runs)
        self._closed = False

    @property
    @abstractmethod
    def done(self) -> np.ndarray:
        """Commit flag per tile (a copy)."""

    def write_tile(self, tile: Tile, arrays: dict[str, np.ndarray]) -> None:
        """Store a tile's arrays (as ``run_tile`` returns them), then commit its flag."""
        if tile != self.tiles[tile.index]:
            raise ValueError(f"{tile} is not tile {tile.index} of job {self.job.name}")
        check_tile_arrays(self.job, tile, arrays)
        self._write_tile(tile, arrays)

    def log_run(self, entry: dict) -> None:
        """Append one entry to the store's run log (attribute ``runs``)."""
        self._runs.append(dict(entry))
        self._write_runs(self._runs)

    @property
    def runs(self) -> list[dict]:
        return list(self._runs)

    def close(self) -> None:
        """Flush everything and release the lock; idempotent."""
        if self._closed:
            return
        self._closed = True
        try:
            self._close()
        finally:
            self._lock.release()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    @abstractmethod
    def _write_tile(self, tile: Tile, arrays: dict[str, np.ndarray]) -> None: ...

    @abstractmethod
    def _write_runs(self, runs: list[dict]) -> None: ...

    @abstractmethod
    def _close(self) -> None: ...
