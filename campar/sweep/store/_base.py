"""The store interface: what a run writes (``Store``) and what views read (``StoreReader``).

For developers — a backend implements:

- ``create(path, job)``: build a complete new store, atomically (a killed
  creation leaves no store, only a temporary name ``clean_leftovers`` removes);
- ``read_attrs(path)``: the store's attributes, or None if ``path`` is not a
  campar store of this backend;
- ``clean_leftovers(path)``: remove what a killed writer left behind and
  finish any commit it left half done;
- ``repair(path, job, report)``: rewrite the variables a verification found
  damaged from the job, record the variables' checksums where the store has
  none, and make the tiles it found damaged pending again, their cells the fill
  value (a resume then recomputes them);
- ``read_attrs`` raising StoreDamaged with ``sealed_job`` set, and
  ``set_store_aside(path)``, if the backend can tell the job of a store it
  cannot read (HDF5's seal): a resume of that job keeps it aside and restarts;
- a ``Store`` subclass with ``_write_tile``, ``_write_runs`` and ``_close``;
- a ``StoreReader`` subclass with ``_read_rows``, ``_tile_values``, ``_shapes``,
  ``_describe``, ``_fresh`` (its variables' metadata, ``_metadata``)
  and ``close`` (and ``journaled``/``journal_problems`` if
  committed tiles can wait outside the store's arrays). Reads of one tile must
  raise, never crash, on damaged bytes: ``_integrity`` turns that into a report;
- the layout and attributes of ``_schema.store_arrays`` and ``initial_attrs``,
  so that xarray opens every backend to the same Dataset.

The commit protocol every backend keeps: a tile's arrays, then its checksum,
then its ``done`` flag, so ``done`` never claims a tile whose data a kill lost,
and a tile whose data changed afterwards fails its checksum (``_integrity``).
Every path a backend touches is the store's real path (symbolic links
resolved by ``open_store``); ``path`` is the one the user gave, for messages.
Any OSError of a write reaches the caller as StoreIOError (exit 74).
"""

import contextlib
from abc import ABC, abstractmethod
from pathlib import Path

import numpy as np

from ...errors import CamparError, StoreDamaged, StoreError, io_error
from ..job import Job, job_digest
from ..plan import Tile, plan_tiles
from ._integrity import describe_exception, tile_checksum
from ._lock import StoreLock
from ._metadata import CHECKSUMS_ATTR, GLOBAL, variable_problems
from ._root import MARK_ATTR, Root, RootDamaged, root_problems
from ._schema import (
    CHECKSUMS_FROM,
    FORMAT,
    cell_arrays,
    check_tile_arrays,
    coordinates,
    layout_problems,
    remember_stored_table,
    store_arrays,
)


class StoreReader(ABC):
    """Read-only view of a store: no lock, safe while a run writes it.

    Opening checks that the metadata agrees with itself (StoreDamaged if not);
    the tiles are checked by ``_integrity.verify_store``, which reads them.
    """

    def __init__(
        self, path: Path, attrs: dict, real: Path | None = None, *, adopting: bool = False
    ):
        self.path = path  # as given, for messages
        self.real = real or path  # symbolic links resolved
        self.attrs = attrs
        self.adopting = adopting  # a store without a root record is read, to adopt it
        remember_stored_table(path, attrs)  # its job then reads without the table's file
        self.root: Root | None = None  # the root record, once ``_take_root`` found it sound
        self.root_problem: str | None = None  # why the record cannot vouch for the store
        self.stray_flags: list[int] = []  # done flags set where the record holds tiles pending
        self._cached: dict = {}  # the per-tile arrays, read once: the reader's snapshot
        try:
            self.job = Job.from_dict(attrs["job"], source=f"job stored in {path}")
        except (CamparError, KeyError, TypeError) as exc:
            stored = attrs.get("job")
            if isinstance(stored, dict) and job_digest(stored) == attrs.get("job_hash"):
                raise StoreError(  # intact, but not this campar's: another version wrote it
                    f"{path} holds a job this campar cannot read ({exc}): it was written by "
                    "another campar version; read it with that version, or upgrade"
                ) from None
            raise StoreDamaged(
                f"{path} is damaged: its stored job cannot be read ({exc})"
            ) from None
        self.format = attrs.get("campar_store")
        self.names = [a.name for a in cell_arrays(self.job)]
        self.coords = coordinates(self.job)
        self.array_dtypes = {a.name: a.dtype for a in cell_arrays(self.job)}

    # Whether ``repair`` rewrites a damaged variable where it is, keeping the tiles (Zarr), so
    # a check leaves the tiles until then; HDF5 rebuilds the file from the tiles that verify.
    rewrites_variables_in_place = False

    def _take_root(self, load) -> None:
        """Take the root record ``load()`` returns (None: there is none; RootDamaged): sound,
        or why not. A store of the current format without a record and without the mark of
        one was written before root records: StoreError unless it is being adopted."""
        if self.format != FORMAT:
            return  # formats 1 and 2: read-only, checked for readability (``_integrity``)
        try:
            root = load()
        except RootDamaged as exc:
            self.root_problem = f"the root record is damaged ({exc})"
            return
        if root is None:
            if self.attrs.get(MARK_ATTR):
                self.root_problem = "the root record is missing (deleted?)"
            elif not self.adopting:
                raise StoreError(
                    f"{self.path} has no root record (written by an earlier campar): nothing "
                    "vouches for its commit flags; `campar verify --adopt "
                    f"{self.path}` checks it against its job and adopts it (docs/restart.md)"
                )
            return
        problems = root_problems(root, self.attrs, len(plan_tiles(self.job)))
        if problems:
            self.root_problem = "the root record disagrees with the store: " + "; ".join(problems)
            return
        self.root = root

    def _outside_root(self) -> dict[int, int]:
        """{tile: checksum} of tiles committed where the root record does not reach yet
        (HDF5: the journal's entries between checkpoints)."""
        return {}

    def committed_tiles(self) -> np.ndarray:
        """Per tile: committed in this reader's snapshot (the root record, and the journal)."""
        committed = self.root.committed.copy()
        committed[list(self._outside_root())] = True
        return committed

    def commit_mark(self) -> tuple:
        """What changes whenever a tile is committed or made pending again (a repair) and
        whenever a run is logged: the root record as read (its digest, commit lines and
        chain), the tiles committed outside it (a journal), the number of runs logged. Equal
        marks of two readers: no tile changed between them (a repair and a recomputation in
        between end in another run logged). Cheap: read from the record and the attributes,
        no tile flag. Without a sound record: the runs logged alone."""
        runs = self.attrs.get("runs")
        logged = len(runs) if isinstance(runs, list) else repr(runs)
        if self.root is None:
            return (None, logged)
        outside = tuple(sorted(self._outside_root().items()))
        return (self.root.digest, self.root.lines, self.root.chain, outside, logged)

    def _check_layout(self) -> None:
        """StoreDamaged unless the arrays are as the stored job says (backends call this
        once their file is open); ``array_shapes`` from then on."""
        self.array_shapes = self._shapes()
        problems = layout_problems(self.job, self.attrs, self.array_shapes)
        if self.rewrites_variables_in_place and all(p.startswith("array ") for p in problems):
            problems = []  # an array's shape is its metadata's: ``variable_damage``, repairable
        if problems:
            raise StoreDamaged(
                f"{self.path}: its metadata disagrees with itself: " + "; ".join(problems)
            )

    @property
    def done(self) -> np.ndarray:
        """Commit flag per tile (bool, one per tile of ``plan_tiles(job)``); a flag that
        cannot be read counts as unset. Says nothing of the tiles' bytes: ``verify_store``."""
        return self.tile_flags()[0]

    def tile_flags(self) -> tuple[np.ndarray, dict[int, str]]:
        """(done per tile, {tile: why its flag is damaged}) — a damaged flag is unset. With a
        root record: the tiles it holds committed, a flag of one of them that is not 1 is
        damage ("commit flag lost"), and a flag set on any other tile is pending
        (``stray_flags``)."""
        if "flags" not in self._cached:
            self._cached["flags"] = self._read_flags()
        done, problems = self._cached["flags"]
        return done.copy(), dict(problems)

    def _read_flags(self) -> tuple[np.ndarray, dict[int, str]]:
        flags, problems = self._tile_values("done")
        flags = flags.astype(np.int64)  # bool in format 1, int8 from format 2 on
        for index in np.flatnonzero((flags != 0) & (flags != 1)).tolist():
            problems.setdefault(index, f"done flag holds {flags[index]}, neither 0 nor 1")
        done = flags == 1
        done[list(problems)] = False
        if self.root is None:
            return done, problems
        committed = self.committed_tiles()
        lost = {i: why for i, why in problems.items() if committed[i]}
        for index in np.flatnonzero(committed & ~done).tolist():
            lost.setdefault(
                index,
                f"commit flag lost: done holds {flags[index]} where the root record holds the "
                "tile committed",
            )
        stray = (done & ~committed) | np.isin(np.arange(done.size), list(problems))
        self.stray_flags = np.flatnonzero(stray & ~committed).tolist()
        return committed & ~np.isin(np.arange(done.size), list(lost)), lost

    def tile_checksums(self) -> tuple[np.ndarray | None, dict[int, str]]:
        """(checksum per tile, 0 none; {tile: why it cannot be read}); None before format 3.
        With a root record: the record's checksums (and the journal's), and a ``checksum``
        element that differs from them is damage."""
        if (self.format or 0) < CHECKSUMS_FROM:
            return None, {}
        if "sums" not in self._cached:
            self._cached["sums"] = self._read_sums()
        sums, problems = self._cached["sums"]
        return sums.copy(), dict(problems)

    def _read_sums(self) -> tuple[np.ndarray, dict[int, str]]:
        sums, problems = self._tile_values("checksum")
        if self.root is None:
            return sums, problems
        expected = self.root.checksums.copy()
        for index, checksum in self._outside_root().items():
            expected[index] = checksum
        wrong = {}
        for index in np.flatnonzero(expected != 0).tolist():
            if index in problems:
                wrong[index] = problems[index]
            elif int(sums[index]) != int(expected[index]):
                wrong[index] = (
                    f"its checksum element holds {int(sums[index]):016x}, the root record "
                    f"{int(expected[index]):016x}"
                )
        return expected, wrong

    def root_report(self) -> list[str]:
        """What is wrong with the root record, or with what it vouches for outside the tiles:
        the ``metadata_checksums`` attribute (a copy of the record's)."""
        problems = [self.root_problem] if self.root_problem else []
        if self.root is None:
            return problems
        if self.root.problem:
            problems.append(
                f"the root record's {self.root.problem}: the tiles committed after it read as "
                "pending; `campar run` writes the record anew"
            )
        copy = self.attrs.get(CHECKSUMS_ATTR)
        if copy != self.root.variables:
            what = "differs from" if isinstance(copy, dict) else "cannot be read, unlike"
            problems.append(
                f"attribute {CHECKSUMS_ATTR} (the variables' checksums) {what} the root "
                "record's copy; the root record's were used"
            )
        return problems

    def read(self, name: str) -> np.ndarray:
        """A per-cell array over ([direction,] second, omega[, tail]); uncomputed cells hold
        the fill. The whole array in memory: views of large stores read ``read_tile``."""
        self._known(name)
        return self._read_rows(name, slice(None), None)

    def read_rows(self, name: str, rows: slice, layer: int | None = None) -> np.ndarray:
        """A per-cell array over the chains ``rows`` (of direction ``layer`` of a ``both``
        store; None: every direction); raises on damaged bytes."""
        self._known(name)
        return self._read_rows(name, rows, layer)

    def read_tile(self, name: str, tile: Tile) -> np.ndarray:
        """A per-cell array's part in ``tile``, as ``run_tile`` returned it."""
        return self.read_rows(name, tile.rows, tile.layer)

    def selection(self, rows: slice, layer: int | None) -> tuple:
        """Index of chains ``rows`` of direction ``layer`` (None: all) in a per-cell array."""
        if self.job.chains.direction != "both":
            return (rows,)
        return (slice(None) if layer is None else layer, rows)

    def _known(self, name: str) -> None:
        if name not in self.names:
            raise KeyError(f"{self.path} has no array {name!r}; it has {', '.join(self.names)}")

    @property
    def journaled(self) -> dict[int, dict[str, np.ndarray]]:
        """Committed tiles whose arrays are not in the store's own arrays yet, by tile
        index (HDF5 between checkpoints); ``read`` and ``done`` include them already."""
        return {}

    @property
    def journal_problems(self) -> dict[int, str]:
        """Tiles whose journal entry cannot be read (they count as not committed)."""
        return {}

    def metadata_problems(self) -> list[str]:
        """Parts of the store's metadata a reader does not need but other tools do, damaged."""
        return []

    @property
    def metadata_checksums(self) -> bool:
        """Whether the store's variables carry checksums (a store of the current format
        written before them does not: its next run records them)."""
        stored = self.attrs.get(CHECKSUMS_ATTR)
        if self.root is not None or self.format != FORMAT:
            return True
        return isinstance(stored, dict) and GLOBAL in stored

    def variable_damage(self) -> dict[str, str]:
        """{variable: what changed} — coordinates, array metadata and the attributes that say
        how values decode, against their checksums (``_metadata``); stores of the current
        format only (older ones are read as their job lays them out)."""
        if self.format != FORMAT:
            return {}
        arrays = store_arrays(self.job)
        if self.root is not None:
            stored = self.root.variables
        elif self.adopting and not self.attrs.get(MARK_ATTR):
            stored = None  # checksums of an earlier campar's: checked against the job instead
        else:
            stored = self.attrs.get(CHECKSUMS_ATTR)  # unreadable: checked against the job
            stored = stored if isinstance(stored, dict) else None
        return variable_problems(self._describe(arrays), stored, lambda: self._fresh(arrays))

    @abstractmethod
    def _describe(self, arrays) -> dict:
        """{name: ``_metadata.Variable``, or why it cannot be read} of ``arrays``."""

    @abstractmethod
    def _fresh(self, arrays) -> dict:
        """The same of a store of this job built afresh (what ``repair`` writes)."""

    @property
    def file_damage(self) -> str | None:
        """Why the store's file cannot be handed to other readers as it is (HDF5 damaged on
        disk: this reader reads a rescued copy), or None."""
        return None

    @abstractmethod
    def _tile_values(self, name: str) -> tuple[np.ndarray, dict[int, str]]:
        """A one-per-tile array (``done``, ``checksum``) and {tile: why its element cannot
        be read}: ``tile_values`` does it for a backend."""

    @abstractmethod
    def _read_rows(self, name: str, rows: slice, layer: int | None) -> np.ndarray: ...

    @abstractmethod
    def _shapes(self) -> dict[str, tuple]: ...

    @abstractmethod
    def close(self) -> None: ...

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def tile_values(read, n_tiles: int, dtype, name: str) -> tuple[np.ndarray, dict[int, str]]:
    """A one-per-tile array read whole by ``read(slice)``, or element by element if that
    fails, so one damaged chunk spoils one element: (values, {tile: why unreadable})."""
    try:
        return np.asarray(read(slice(None))).reshape(n_tiles), {}
    except Exception:  # zarr, numcodecs and h5py raise many kinds
        pass
    values, problems = np.zeros(n_tiles, dtype), {}
    for index in range(n_tiles):
        try:
            values[index] = np.asarray(read(slice(index, index + 1))).reshape(())
        except Exception as exc:
            problems[index] = f"{name} unreadable ({describe_exception(exc)})"
    return values, problems


class Store(ABC):
    """A store opened for one run: holds the lock; the only writer of commits.

    ``direct_writes``: other processes may write a tile's arrays themselves
    (``TileWriter``), the store then commits it (``commit_tiles``): a backend whose tiles
    are files of their own (Zarr); HDF5 from PyPI is serial and has one writer.
    """

    direct_writes = False

    def __init__(self, path: Path, job: Job, lock: StoreLock, runs: list, real: Path | None = None):
        self.path = path  # as given, for messages
        self.real = real or path  # where the files are
        self.job = job
        self.tiles = plan_tiles(job)
        self._cell_arrays = cell_arrays(job)
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
        check_tile_arrays(self.job, tile, arrays, self._cell_arrays)
        names = [a.name for a in self._cell_arrays]
        try:
            self._write_tile(tile, arrays, tile_checksum(arrays, names))
        except OSError as exc:
            raise io_error(
                f"cannot write tile {tile.index} to the store {self.path}", exc
            ) from None

    def commit_tiles(self, written: list[tuple[Tile, int]]) -> None:
        """Commit tiles whose arrays a ``TileWriter`` wrote, given as (tile, checksum): every
        checksum, then every ``done`` flag (a group commit: the order per tile is kept)."""
        if not self.direct_writes:
            raise StoreError(f"{self.path}: this backend has one writer; use write_tile")
        for tile, _ in written:
            if tile != self.tiles[tile.index]:
                raise ValueError(f"{tile} is not tile {tile.index} of job {self.job.name}")
        try:
            self._commit(written)
        except OSError as exc:
            which = ", ".join(str(tile.index) for tile, _ in written)
            what = f"cannot commit tiles {which} to the store {self.path}"
            raise io_error(what, exc) from None

    def _commit(self, written: list[tuple[Tile, int]]) -> None:
        raise NotImplementedError  # backends with direct_writes

    def log_run(self, entry: dict) -> None:
        """Append one entry to the store's run log (attribute ``runs``)."""
        self._runs.append(dict(entry))
        try:
            self._write_runs(self._runs)
        except OSError as exc:
            raise io_error(f"cannot write the run log of the store {self.path}", exc) from None

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
        except OSError as exc:
            raise io_error(f"cannot flush the store {self.path}", exc) from None
        finally:
            with contextlib.suppress(OSError):  # a lock that cannot go is reported stale later
                self._lock.release()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    @abstractmethod
    def _write_tile(self, tile: Tile, arrays: dict[str, np.ndarray], checksum: int) -> None:
        """Arrays, then ``checksum``, then the ``done`` flag: the commit."""

    @abstractmethod
    def _write_runs(self, runs: list[dict]) -> None: ...

    @abstractmethod
    def _close(self) -> None: ...
