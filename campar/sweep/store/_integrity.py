"""Integrity of committed tiles: a checksum per tile, and the check that reads every
committed tile back (``campar verify``, ``campar status``, ``campar plot``, ``campar.open``
and every resume), with the store's variables against their own checksums (``_metadata``).

A tile's checksum is BLAKE2b with an 8-byte digest of every per-cell array over
the tile's rows, in the store's order, each preceded by its name, dtype and
shape. The writer stores it in ``checksum`` after the tile's arrays and before
its ``done`` flag (the HDF5 journal keeps it in the tile's entry), so a
committed tile whose bytes changed afterwards — a chunk deleted or truncated, a
bit flipped, a disk block zeroed — reads back with another checksum, or not at
all. A flag that is neither 0 nor 1, or cannot be read, is damage too.

Checking streams the store: committed tiles are read in batches of whole tiles
of about ``BATCH_BYTES``, so the memory of ``verify`` and ``status`` does not
grow with the grid; a batch that fails to read is read again tile by tile, so
one damaged chunk condemns one tile. Stores of formats 1 and 2 carry no
checksums: their committed tiles are checked for being readable and holding
computed cells only.
"""

import hashlib
from collections.abc import Callable, Collection, Iterator
from dataclasses import dataclass, field

import numpy as np

from ..plan import Tile, plan_tiles
from ._metadata import CHECKSUMS_ATTR
from ._schema import fill_value

DIGEST_BYTES = 8  # 64 bits: a damaged tile passes with probability 2**-64
BATCH_BYTES = 32 * 2**20  # tiles read at once, uncompressed: bounds a check's memory
MESSAGE_CHARS = 160  # a library's error message, cut to keep a report line readable


def tile_checksum(arrays: dict[str, np.ndarray], names: list[str]) -> int:
    """The checksum of a tile's arrays (``names``: the store's order), never 0 (0: none)."""
    h = hashlib.blake2b(digest_size=DIGEST_BYTES)
    for name in names:
        a = np.asarray(arrays[name])
        a = np.ascontiguousarray(a, a.dtype.newbyteorder("<"))  # the same bytes on any host
        h.update(f"{name}:{a.dtype.str}:{a.shape};".encode())
        h.update(a.reshape(-1).view(np.uint8))
    return int.from_bytes(h.digest(), "little") or 1


def describe_exception(exc: BaseException) -> str:
    """A library's error in one short line ("RuntimeError: Zstd decompression error …")."""
    text = " ".join(str(exc).split()) or "no message"
    if len(text) > MESSAGE_CHARS:
        text = text[: MESSAGE_CHARS - 1] + "…"
    return f"{type(exc).__name__}: {text}"


@dataclass
class TileCheck:
    """One committed tile as read back: its arrays if it verified, else why not."""

    tile: Tile
    arrays: dict[str, np.ndarray] | None
    problem: str | None = None


@dataclass
class Verification:
    """What a check of every committed tile found."""

    tiles: int  # tiles of the job
    committed: list[int] = field(default_factory=list)  # done flag set (or unreadable)
    damaged: dict[int, str] = field(default_factory=dict)  # tile → why it cannot be trusted
    problems: list[str] = field(default_factory=list)  # of the store, not of one tile
    variables: dict[str, str] = field(default_factory=dict)  # variable → what changed in it
    checksums: bool = True  # the format carries checksums (else: readability only)
    metadata_checksums: bool = True  # the variables carry checksums (``_metadata``)
    root: object = None  # the sound root record the check went by (``_root.Root``), or None
    sums: np.ndarray | None = None  # per tile, the checksum the tile was verified against
    stray: list[int] = field(default_factory=list)  # flags set on pending tiles
    notes: list[str] = field(default_factory=list)  # worth saying, not damage
    adopting: bool = False  # a check to adopt a store without a root record
    tiles_checked: bool = True  # False: a tile array's metadata is damaged (see verify_store)

    @property
    def root_digest(self) -> str | None:
        return None if self.root is None else self.root.digest

    @property
    def verified(self) -> np.ndarray:
        """Per tile: committed and read back intact (what a resume keeps)."""
        good = np.zeros(self.tiles, bool)
        good[[i for i in self.committed if i not in self.damaged]] = True
        return good

    @property
    def clean(self) -> bool:
        return not self.damaged and not self.problems and not self.variables

    def lines(self, limit: int = 50) -> list[str]:
        """The report: one line per damaged variable, per damaged tile (up to ``limit``) and
        per store problem."""
        lines = [f"variable {name}: {why}" for name, why in self.variables.items()]
        lines += [f"tile {i}: {why}" for i, why in sorted(self.damaged.items())[:limit]]
        if len(self.damaged) > limit:
            lines.append(f"… and {len(self.damaged) - limit} more damaged tiles")
        return lines + list(self.problems)


def check_tiles(
    reader, batch_bytes: int | None = None, only: Collection[int] | None = None
) -> Iterator[TileCheck]:
    """Every committed tile of ``reader``'s store (of ``only``'s tile indices, if given),
    read back and verified against the reader's snapshot, in index order, in batches of
    about ``batch_bytes`` (``BATCH_BYTES``, read at the call: a test bounds it smaller)."""
    job = reader.job
    tiles = plan_tiles(job)
    if only is not None:
        wanted = set(only)
        tiles = [t for t in tiles if t.index in wanted]
    done, flag_problems = reader.tile_flags()
    sums, sum_problems = reader.tile_checksums()
    committed = [t for t in tiles if done[t.index] or t.index in flag_problems]
    row_bytes = sum(_row_bytes(reader, name) for name in reader.names)
    rows_per_batch = max(1, (batch_bytes or BATCH_BYTES) // max(row_bytes, 1))
    for batch in _batches(committed, rows_per_batch):
        for tile, arrays, problem in _read_batch(reader, batch):
            if tile.index in flag_problems:
                problem = flag_problems[tile.index]
            elif problem is None:
                problem = _verify(reader, tile, arrays, sums, sum_problems)
            yield TileCheck(tile, None if problem else arrays, problem)


def verify_store(reader, visit: Callable[[TileCheck], None] | None = None) -> Verification:
    """Check every committed tile (and the store's own parts); ``visit`` sees each tile that
    verified, with its arrays, so a caller (``status``, ``plot``) needs no second pass."""
    report = Verification(len(plan_tiles(reader.job)))
    report.checksums = reader.tile_checksums()[0] is not None
    report.problems += reader.metadata_problems()
    report.variables = reader.variable_damage()
    report.metadata_checksums = reader.metadata_checksums
    report.root, report.adopting = reader.root, reader.adopting
    if CHECKSUMS_ATTR in reader.attrs and not report.metadata_checksums:
        report.problems.append(
            f"the variables' checksums (attribute {CHECKSUMS_ATTR}) cannot be read: every "
            "variable was checked against the stored job instead; `campar run` records them"
        )
    unsure = [n for n in report.variables if n in reader.names or n in ("done", "checksum")]
    if unsure and reader.rewrites_variables_in_place:
        # Tiles read through damaged metadata (another data type, codec or chunk shape) would
        # all fail their checksums, and a resume would recompute them all: the metadata is
        # rewritten from the job first, then every tile checked (``open_store``).
        report.tiles_checked = False
        report.problems.append(
            f"tiles not checked: the metadata of {', '.join(unsure)} is damaged; `campar run` "
            "rewrites it from the job, then checks every tile"
        )
        report.root = reader.root
        return report
    for check in check_tiles(reader):
        report.committed.append(check.tile.index)
        if check.problem:
            report.damaged[check.tile.index] = check.problem
        elif visit is not None:
            visit(check)
    for index, why in reader.journal_problems.items():
        if index not in report.committed:  # a journaled tile whose entry cannot be read
            report.committed.append(index)
            report.damaged[index] = why
    report.committed.sort()
    report.sums = reader.tile_checksums()[0]
    report.problems += reader.root_report()
    report.stray = list(reader.stray_flags)
    if report.stray:
        shown = ", ".join(map(str, report.stray[:8])) + (", …" if len(report.stray) > 8 else "")
        report.notes.append(
            f"done flag set on tiles {shown}, which the root record holds pending: a commit "
            "under way, or one a kill interrupted; pending (`campar run` clears the flags)"
        )
    return report


def _row_bytes(reader, name: str) -> int:
    shape, dtype = reader.array_shapes[name], reader.array_dtypes[name]
    lead = 2 if reader.job.chains.direction == "both" else 1  # a row of one direction
    return int(np.prod(shape[lead:], dtype=np.int64)) * dtype.itemsize


def _batches(tiles: list[Tile], rows_per_batch: int) -> Iterator[list[Tile]]:
    """Runs of adjacent tiles of at most ``rows_per_batch`` rows (or one tile)."""
    batch: list[Tile] = []
    for tile in tiles:
        adjacent = batch and batch[-1].row_stop == tile.row_start and batch[-1].layer == tile.layer
        if batch and (not adjacent or tile.row_stop - batch[0].row_start > rows_per_batch):
            yield batch
            batch = []
        batch.append(tile)
    if batch:
        yield batch


def _read_batch(reader, batch: list[Tile]):
    """(tile, arrays, problem) of each tile of a batch; tile by tile if the batch fails."""
    rows, layer = slice(batch[0].row_start, batch[-1].row_stop), batch[0].layer
    try:
        whole = {name: reader.read_rows(name, rows, layer) for name in reader.names}
    except Exception:  # some chunk of the batch is damaged: find which tile's
        whole = None
    for tile in batch:
        if whole is not None:
            local = slice(tile.row_start - rows.start, tile.row_stop - rows.start)
            yield tile, {name: a[local] for name, a in whole.items()}, None
            continue
        arrays, problem = {}, None
        for name in reader.names:
            try:
                arrays[name] = reader.read_tile(name, tile)
            except Exception as exc:  # zarr, numcodecs and h5py raise many kinds
                problem = f"{name} unreadable ({describe_exception(exc)})"
                break
        yield tile, arrays, problem


def _verify(reader, tile: Tile, arrays: dict, sums, sum_problems: dict) -> str | None:
    """Why a readable committed tile cannot be trusted, or None."""
    if sums is None:  # formats 1 and 2: no checksum; at least every cell was computed
        empty = [n for n in ("kind", "status") if (arrays[n] == fill_value(arrays[n].dtype)).any()]
        return f"cells never written in {', '.join(empty)}" if empty else None
    if tile.index in sum_problems:
        return sum_problems[tile.index]
    stored = int(sums[tile.index])
    if stored == 0:
        return "committed without a checksum"
    if tile_checksum(arrays, reader.names) == stored:
        return None
    blank = [name for name, a in arrays.items() if _all_fill(a)]
    hint = f"; only fill values in {', '.join(blank)} (chunks missing?)" if blank else ""
    return f"checksum mismatch: its arrays changed after the commit{hint}"


def _all_fill(a: np.ndarray) -> bool:
    fill = fill_value(a.dtype)
    return bool(np.isnan(a).all()) if a.dtype.kind == "f" else bool((a == fill).all())
