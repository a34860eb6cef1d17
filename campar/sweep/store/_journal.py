"""The HDF5 store's journal: committed tiles waiting for the next checkpoint.

``<store>.journal/tile-000012.npz`` holds a tile's arrays and their checksum,
written aside and renamed (whole or absent): it is the tile's commit until a
checkpoint folds it into the file (``_hdf5.apply_journal``). An entry that
cannot be read, does not fit the job, or fails its checksum is never applied:
``set_aside`` keeps it as ``tile-000012.npz.damaged-<time>`` (a name the journal
ignores) and says so; its tile is computed again.
"""

import logging
import os
import re
import time
from pathlib import Path

import numpy as np

from ..job import Job
from ..plan import plan_tiles
from ._integrity import describe_exception, tile_checksum
from ._schema import cell_arrays, check_tile_arrays

log = logging.getLogger("campar.sweep.store")

ENTRY = re.compile(r"^tile-(\d+)\.npz$")
ENTRY_TMP = re.compile(r"^\.tile-\d+\.npz\.\d+\.tmp$")  # an entry being written


def journal_dir(path: Path) -> Path:
    return path.with_name(path.name + ".journal")


def damaged_name(path: Path) -> Path:
    """``<name>.damaged-<time>[-n]``, a name nothing has yet: what is set aside is never lost."""
    base = f"{path.name}.damaged-{time.strftime('%Y%m%dT%H%M%S')}"
    aside, n = path.with_name(base), 1
    while aside.exists() or aside.with_name(aside.name + ".journal").exists():
        aside, n = path.with_name(f"{base}-{n}"), n + 1
    return aside


def journal_entries(path: Path) -> dict[int, Path]:
    journal = journal_dir(path)
    if not journal.is_dir():
        return {}
    found = {}
    for p in journal.iterdir():
        match = ENTRY.match(p.name)
        if match:
            found[int(match.group(1))] = p
    return dict(sorted(found.items()))


def write_entry(path: Path, index: int, arrays: dict[str, np.ndarray], checksum: int) -> None:
    """A tile's commit: its arrays and their checksum, written aside and renamed."""
    journal = journal_dir(path)
    journal.mkdir(exist_ok=True)
    final = journal / f"tile-{index:06d}.npz"
    tmp = journal / f".{final.name}.{os.getpid()}.tmp"
    try:
        with open(tmp, "wb") as fh:
            np.savez(fh, **arrays, checksum=np.uint64(checksum))
        os.replace(tmp, final)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def load_entry(entry: Path) -> dict[str, np.ndarray] | None:
    """A journal entry's arrays (and ``checksum``), or None if a checkpoint removed it
    meanwhile; raises on a damaged entry."""
    try:
        with np.load(entry) as data:
            return {name: data[name] for name in data.files}
    except FileNotFoundError:
        return None


def read_entry(entry: Path, job: Job, index: int) -> tuple[dict | None, str | None]:
    """(arrays with ``checksum``, None) of a whole entry that verifies; (None, why) of a
    damaged one; (None, None) if it is gone."""
    try:
        arrays = load_entry(entry)
    except Exception as exc:  # BadZipFile, EOFError, OSError, ValueError, zlib.error …
        return None, f"journal entry {entry.name} unreadable ({describe_exception(exc)})"
    if arrays is None:
        return None, None
    return verified_entry(entry, job, index, arrays)


def set_aside(entry: Path, why: str) -> Path:
    """Keep a damaged entry under a name the journal ignores, and say so."""
    aside = damaged_name(entry)
    os.replace(entry, aside)
    log.warning("%s: set aside as %s; its tile is computed again", why, aside.name)
    return aside


def verified_entry(
    entry: Path, job: Job, index: int, loaded: dict
) -> tuple[dict | None, str | None]:
    """``read_entry``'s checks of an entry already loaded."""
    tiles, arrays = plan_tiles(job), dict(loaded)
    checksum = arrays.pop("checksum", None)
    if index >= len(tiles):
        return None, f"journal entry {entry.name} names no tile of the job"
    try:
        check_tile_arrays(job, tiles[index], arrays)
    except ValueError as exc:
        return None, f"journal entry {entry.name} does not fit ({exc})"
    if checksum is None or int(checksum) != tile_checksum(
        arrays, [a.name for a in cell_arrays(job)]
    ):
        return None, f"journal entry {entry.name} fails its checksum"
    return {**arrays, "checksum": checksum}, None
