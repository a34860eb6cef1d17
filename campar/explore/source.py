"""A result store as the explorer reads it: verified tiles only, memory bounded, growing.

Opening refuses what ``campar.open`` refuses (a damaged variable or file: StoreDamaged).
A scan then reads every committed tile once, verifies it against its checksum
(``campar.sweep.store.verify_store``, streaming) and keeps each field the map can show
in memory at a stride ``s`` (every s-th row and column), the smallest power of two that
keeps a field under MOSAIC_CELLS cells: a 400 × 400 map is kept whole, a 4000 × 4000
one at s = 2. A damaged tile is masked — its cells read as not computed, as
``campar.open`` reads them — and named in ``status()``. Tiles a run commits later are
verified and taken in by ``refresh()`` as they come; a tile not yet committed is pending.
A masked tile is looked at again whenever the store's commits have changed since
(``StoreReader.commit_mark``): a run that repairs it makes it pending, then commits it
anew, and the tile is shown once it verifies — without a restart of the explorer.
Tiles are taken in through the store's snapshot read (``check_tiles`` on a
``read_store`` reader, as ``campar.open`` reads): the tiles its root record holds
committed, each verified whole against the record's checksum — so a tile is drawn whole
and verified or as pending, never torn by a run writing the store. Taking a tile in
records a digest of each array a view or a hovered cell reads of it (``DIGEST_BYTES``,
of the very bytes that verified); reading such an array again later (a close view, a
hovered cell) checks it against that digest, so it is the verified bytes or the tile is
masked as damaged — at the cost of hashing the arrays read, not of reading and hashing
every array of the tile again.

A view asks for one cell per screen pixel (the cell under the pixel's centre, as a map
image is drawn, never a mixture of cells): where a pixel spans at least s cells the
kept mosaic answers, else only the tiles the view crosses are read, at full resolution,
through a small cache.
"""

import hashlib
import threading
from collections import Counter, OrderedDict
from pathlib import Path

import numpy as np

from ..errors import StoreDamaged, StoreError
from ..sweep.job import cell_edges
from ..sweep.plan import plan_tiles
from ..sweep.store import check_tiles, read_store, verify_store
from .fields import Field, categories, fields_of, numeric

MOSAIC_CELLS = 4_000_000  # per field and direction kept in memory: 16 MB as float32
CACHE_BYTES = 128 * 2**20  # stored arrays of the tiles read for close views
DIGEST_BYTES = 16  # BLAKE2b of an array taken in: a changed array passes with p = 2**-128
PENDING, VERIFIED, DAMAGED = 0, 1, 2
NO_CELL = -1  # a pixel outside the grid
PENDING_CELL = -2  # a cell of a tile not committed (or masked as damaged): not computed
# Arrays a hovered cell shows (the σn points and census arrays are for other panels).
CELL_ARRAYS = (
    "n",
    "p",
    "kind",
    "status",
    "flags",
    "dc",
    "eps_min",
    "eps_max",
    "pn_max",
    "lyapunov",
    "multipliers",
    "state",
    "revolutions",
    "steps",
    "n_attractors",
    "attractor_n",
    "attractor_p",
    "attractor_kind",
    "attractor_fraction",
)


class MapSource:
    """One store of a map job, served by the explorer (thread-safe)."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        reader = read_store(self.path)
        try:
            if reader.file_damage:
                raise StoreDamaged(f"{path}: {reader.file_damage}; `campar run` repairs it")
            damage = reader.variable_damage()
            if damage:
                said = "; ".join(f"variable {k}: {why}" for k, why in damage.items())
                raise StoreDamaged(
                    f"{path} is damaged: {said}; `campar run` rewrites it from the job"
                )
            self.job = reader.job
            self.names = list(reader.names)
        finally:
            reader.close()
        if self.job.kind != "map":
            raise StoreError(f"{path} is a {self.job.kind} store: campar explore shows maps")
        self.tiles = plan_tiles(self.job)
        self.rows, self.cols = self.job.shape
        self.layers = len(self.job.directions)
        self.fields = {f.name: f for f in fields_of(self.names)}
        # the arrays a view or a hovered cell reads (not the σn points: cached tiles stay small)
        self._read_names = {*CELL_ARRAYS, *(n for f in self.fields.values() for n in f.needs)}
        self.stride = 1
        while -(-self.rows // self.stride) * -(-self.cols // self.stride) > MOSAIC_CELLS:
            self.stride *= 2
        s = self.stride
        shape = (-(-self.rows // s), -(-self.cols // s))
        self.state = np.zeros(len(self.tiles), np.int8)
        self.damage: dict[int, str] = {}
        self.categories: dict[str, list[str]] = {}
        self.counts: dict[tuple[str, int], Counter] = {}
        self._tile_counts: dict[tuple[str, int], Counter] = {}  # (field, tile) → its share
        self.mosaic: dict[tuple[str, int], np.ndarray] = {}
        for field in self.fields.values():
            for layer in range(self.layers):
                if field.categorical:
                    self.mosaic[field.name, layer] = np.full(shape, PENDING_CELL, np.int16)
                    self.counts[field.name, layer] = Counter()
                    self.categories[field.name] = []
                else:
                    self.mosaic[field.name, layer] = np.full(shape, np.nan, np.float32)
        self.x_edges = np.sort(cell_edges(self.job.first_values))
        self.y_edges = np.sort(cell_edges(self.job.second_values))
        self._x_desc = self.job.first_values[0] > self.job.first_values[-1]
        self._y_desc = self.job.second_values[0] > self.job.second_values[-1]
        self._lock = threading.RLock()
        self._cache: OrderedDict = OrderedDict()
        self._digests: dict[tuple[str, int], bytes] = {}  # (array, tile) → as verified
        self._cache_bytes = 0
        self._open_reader = None
        self._mark = None  # the store's commit mark as last taken in (``commit_mark``)
        self.scanned = False
        self.problem: str | None = None  # why the last look at the store failed, if it did

    # -- taking tiles in -----------------------------------------------------------------

    def scan(self) -> None:
        """Verify every committed tile and take the intact ones in (streaming)."""
        with read_store(self.path) as reader:
            mark = reader.commit_mark()
            report = verify_store(reader, lambda check: self._ingest(check.tile, check.arrays))
        with self._lock:
            for index, why in report.damaged.items():
                self._mark_damaged(index, why)
            self._mark = mark
            self.scanned = True

    def refresh(self) -> int:
        """Verify and take in the tiles committed since the last look and, if the store's
        commits changed since (``commit_mark``), look again at the masked ones: pending if
        a repair made them so, shown once they verify; how many tiles changed state."""
        with read_store(self.path) as reader:
            mark = reader.commit_mark()
            changed = mark != self._mark
            with self._lock:
                pending, masked = self.state == PENDING, self.state == DAMAGED
            if not changed and not _newly_committed(reader, pending):
                return 0  # nothing committed since: no tile flag read
            done, flag_problems = reader.tile_flags()
            done[list(flag_problems)] = True  # committed, its flag damaged: check_tiles says
            again = masked & changed
            new = np.flatnonzero(done & (pending | again)).tolist()
            gone = np.flatnonzero(again & ~done).tolist()  # pending again: a run repairs it
            for index in gone:
                self._mark_pending(index)
            if new:
                with self._lock:  # a reader opened before these tiles does not see them
                    self._close_reader()
                for check in check_tiles(reader, only=new):
                    if check.problem:
                        self._mark_damaged(check.tile.index, check.problem)
                    else:
                        self._ingest(check.tile, check.arrays)
            self._mark = mark
        return len(new) + len(gone)

    def _mark_damaged(self, index: int, why: str) -> None:
        """A tile that failed its check: named in ``status()``, its cells masked."""
        with self._lock:
            self._mask(index)
            self.state[index] = DAMAGED
            self.damage[index] = why

    def _mark_pending(self, index: int) -> None:
        """A tile the store holds pending again (a run repairs it): masked, not damaged."""
        with self._lock:
            self._mask(index)
            self.state[index] = PENDING
            self.damage.pop(index, None)

    def _mask(self, index: int) -> None:
        """Draw the tile's cells as not computed, take them out of the legend's counts and
        forget what was read of it (a tile taken in again is read and digested anew)."""
        tile = self.tiles[index]
        s = self.stride
        at = slice(-(-tile.row_start // s), -(-tile.row_stop // s))
        layer = tile.layer or 0
        for (name, which), mosaic in self.mosaic.items():
            if which != layer:
                continue
            mosaic[at] = PENDING_CELL if self.fields[name].categorical else np.nan
            counted = self._tile_counts.pop((name, index), None)
            if counted:
                self.counts[name, layer] -= counted
        for key in [k for k in self._cache if k[1] == index]:
            self._cache_bytes -= self._cache.pop(key).nbytes
        for key in [k for k in self._digests if k[1] == index]:
            del self._digests[key]

    def _ingest(self, tile, arrays: dict) -> None:
        layer = tile.layer or 0
        s = self.stride
        first = -(-tile.row_start // s) * s  # the tile's first row on the mosaic's lattice
        rows = slice(first - tile.row_start, None, s)
        at = slice(first // s, first // s + len(range(first, tile.row_stop, s)))
        chatter = self.job.classify.chatter_p
        with self._lock:
            if self.state[tile.index] != PENDING:  # taken in before (a scan looked again)
                self._mask(tile.index)
            for field in self.fields.values():
                if field.categorical:
                    codes, names = categories(field, arrays, chatter)
                    known = self.categories[field.name]
                    ids = np.array([_category_id(known, name) for name in names], np.int16)
                    values = ids[codes]
                    counts = np.bincount(codes.ravel(), minlength=len(names)).tolist()
                    counted = Counter(dict(zip(names, counts, strict=True)))
                    self.counts[field.name, layer].update(counted)
                    self._tile_counts[field.name, tile.index] = counted
                else:
                    values = numeric(field, arrays)
                self.mosaic[field.name, layer][at] = values[rows, ::s]
            for name in self._read_names & arrays.keys():
                self._digests[name, tile.index] = _digest(arrays[name])
            self.state[tile.index] = VERIFIED
            self.damage.pop(tile.index, None)

    # -- reading -------------------------------------------------------------------------

    def pixel_cells(self, box, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        """(rows (height,), columns (width,)): the cell under each pixel's centre of a view
        of ``box`` = (x0, x1, y0, y1) in parameter values, y up; NO_CELL outside the grid."""
        x0, x1, y0, y1 = box
        xs = x0 + (np.arange(width) + 0.5) * (x1 - x0) / width
        ys = y1 - (np.arange(height) + 0.5) * (y1 - y0) / height
        return (
            _cell_index(ys, self.y_edges, self._y_desc),
            _cell_index(xs, self.x_edges, self._x_desc),
        )

    def view(self, field: Field, box, width: int, height: int, layer: int = 0):
        """(values, inside): the field's value (category id, or float) of the cell under
        every pixel, shape (height, width), and whether the pixel lies on the grid; a cell
        not computed (or masked) is PENDING_CELL (categories) or NaN (numbers)."""
        rows, cols = self.pixel_cells(box, width, height)
        fill = NO_CELL if field.categorical else np.nan
        dtype = np.int16 if field.categorical else np.float32
        out = np.full((height, width), fill, dtype)
        inside_r, inside_c = rows >= 0, cols >= 0
        inside = inside_r[:, None] & inside_c[None, :]
        if not inside.any():
            return out, inside
        r, c = rows[inside_r], cols[inside_c]
        step = min(_spacing(c), _spacing(r))
        s = self.stride
        with self._lock:
            if step >= s or s == 1:
                grid = self.mosaic[field.name, layer]
                block = grid[np.ix_(r // s, c // s)]
            else:
                block = self._full_resolution(field, layer, r, c)
        out[np.ix_(inside_r, inside_c)] = block
        return out, inside

    def _full_resolution(self, field: Field, layer: int, rows, cols) -> np.ndarray:
        """The field at the cells (rows × cols) read from their tiles: the tiles' stored
        arrays are cached, the field computed on the cells drawn only."""
        fill = PENDING_CELL if field.categorical else np.nan
        block = np.full((len(rows), len(cols)), fill, self.mosaic[field.name, layer].dtype)
        per_layer = len(self.tiles) // self.layers
        starts = np.array([t.row_start for t in self.tiles[:per_layer]])
        which = np.searchsorted(starts, rows, side="right") - 1
        picked, parts = [], []
        for k in np.unique(which).tolist():
            tile = self.tiles[layer * per_layer + k]
            if self.state[tile.index] != VERIFIED:
                continue
            arrays = self._tile_arrays(field.needs, tile)
            if arrays is None:  # it failed its check just now: masked
                continue
            sel = np.flatnonzero(which == k)
            parts.append({n: a[rows[sel] - tile.row_start][:, cols] for n, a in arrays.items()})
            picked.append(sel)
        if not parts:
            return block
        arrays = {n: np.concatenate([p[n] for p in parts]) for n in field.needs}
        if field.categorical:
            codes, names = categories(field, arrays, self.job.classify.chatter_p)
            known = self.categories[field.name]
            values = np.array([_category_id(known, n) for n in names], np.int16)[codes]
        else:
            values = numeric(field, arrays)
        block[np.concatenate(picked)] = values
        return block

    def _tile_arrays(self, names, tile) -> dict | None:
        """The stored arrays ``names`` of a verified tile, through the cache, each read
        checked against its digest taken when the tile verified; None when one no longer
        matches or reads (the tile is then masked as damaged)."""
        out = {}
        for name in names:
            key = (name, tile.index)
            if key in self._cache:
                self._cache.move_to_end(key)
                out[name] = self._cache[key]
                continue
            try:
                values = self._reader().read_tile(name, tile)
            except Exception as exc:  # zarr, numcodecs and h5py raise many kinds
                self._mark_damaged(tile.index, f"{name} unreadable ({type(exc).__name__})")
                return None
            if _digest(values) != self._digests.get(key):
                self._mark_damaged(
                    tile.index, f"its {name} changed after it verified (checksum mismatch)"
                )
                return None
            self._cache[key] = out[name] = values
            self._cache_bytes += values.nbytes
        while self._cache_bytes > CACHE_BYTES and len(self._cache) > 1:
            _, old = self._cache.popitem(last=False)
            self._cache_bytes -= old.nbytes
        return out

    def _reader(self):
        """A reader kept open for the reads after the scan (reopened by ``refresh``)."""
        if self._open_reader is None:
            self._open_reader = read_store(self.path)
        return self._open_reader

    def _close_reader(self) -> None:
        if self._open_reader is not None:
            self._open_reader.close()
            self._open_reader = None

    def cell(self, row: int, col: int, layer: int = 0) -> dict:
        """Everything the store holds of one cell (no σn points), or why it has nothing."""
        if not (0 <= row < self.rows and 0 <= col < self.cols and 0 <= layer < self.layers):
            raise IndexError(f"no cell ({row}, {col}) in a {self.rows} × {self.cols} map")
        per_layer = len(self.tiles) // self.layers
        tile = next(
            t for t in self.tiles[layer * per_layer : (layer + 1) * per_layer] if row < t.row_stop
        )
        where = {
            "row": row,
            "col": col,
            "layer": layer,
            self.job.first: float(self.job.first_values[col]),
            self.job.second: float(self.job.second_values[row]),
            "tile": tile.index,
        }
        state = int(self.state[tile.index])
        if state == DAMAGED:
            return {**where, "stored": "damaged", "why": self.damage[tile.index]}
        if state == PENDING:
            return {**where, "stored": "pending"}
        with self._lock:
            arrays = self._tile_arrays([n for n in CELL_ARRAYS if n in self.names], tile)
        if arrays is None:
            return {**where, "stored": "damaged", "why": self.damage[tile.index]}
        values = {n: a[row - tile.row_start, col] for n, a in arrays.items()}
        return {**where, "stored": "verified", "arrays": values}

    def status(self) -> dict:
        with self._lock:
            return {
                "tiles": len(self.tiles),
                "verified": int((self.state == VERIFIED).sum()),
                "damaged": {str(i): why for i, why in sorted(self.damage.items())},
                "scanned": self.scanned,
                "problem": self.problem,
            }

    def legend(self, field: Field, layer: int = 0) -> list[tuple[str, int]]:
        """(category, cells) of a categorical field over the whole map (verified tiles)."""
        with self._lock:
            counts = self.counts[field.name, layer]
            pending = self.rows * self.cols - sum(counts.values())
            items = list(counts.items())
        from ..views.plot.labels import NOT_COMPUTED

        if pending > 0:
            items.append((NOT_COMPUTED, pending))
        return items


def stored_cell(path, row: int, col: int, layer: int = 0) -> tuple:
    """(job, {array: value}) of one cell of a store, its tile read through the snapshot
    read and verified (its tile alone is read); StoreError when its tile is not committed,
    StoreDamaged when it is damaged."""
    with read_store(path) as reader:
        job = reader.job
        rows, cols = job.shape
        if not (0 <= row < rows and 0 <= col < cols):
            raise StoreError(f"no cell ({row}, {col}) in a {rows} × {cols} map")
        tiles = plan_tiles(job)
        per_layer = len(tiles) // len(job.directions)
        tile = next(t for t in tiles[layer * per_layer :] if row < t.row_stop)
        check = next(check_tiles(reader, only=[tile.index]), None)
    if check is None:
        raise StoreError(f"cell ({row}, {col}) is not computed yet (tile {tile.index})")
    if check.problem:
        raise StoreDamaged(f"tile {tile.index} of {path} is damaged: {check.problem}")
    return job, {name: a[row - tile.row_start, col] for name, a in check.arrays.items()}


def _newly_committed(reader, pending: np.ndarray) -> bool:
    """Whether the reader's snapshot holds a tile committed that ``pending`` says is not
    (True without a sound root record: only the tile flags can tell then)."""
    return reader.root is None or bool((reader.committed_tiles() & pending).any())


def _digest(a: np.ndarray) -> bytes:
    """BLAKE2b of an array's bytes, dtype and shape."""
    a = np.ascontiguousarray(a)
    h = hashlib.blake2b(f"{a.dtype.str}:{a.shape};".encode(), digest_size=DIGEST_BYTES)
    h.update(a.reshape(-1).view(np.uint8))
    return h.digest()


def _category_id(known: list[str], name: str) -> int:
    if name not in known:
        known.append(name)
    return known.index(name)


def _cell_index(values: np.ndarray, edges: np.ndarray, descending: bool) -> np.ndarray:
    """Index of the cell (in the store's order) holding each value; NO_CELL outside."""
    k = np.searchsorted(edges, values, side="right") - 1
    n = len(edges) - 1
    k = np.where((k < 0) | (k >= n), NO_CELL, k)
    if descending:
        k = np.where(k >= 0, n - 1 - k, NO_CELL)
    return k


def _spacing(index: np.ndarray) -> float:
    """Cells per pixel along one axis of a view."""
    if len(index) < 2:
        return 1.0
    return abs(float(index[-1]) - float(index[0])) / (len(index) - 1)
