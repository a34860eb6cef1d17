"""The store's root record: one checksummed document that vouches for everything else.

ZFS keeps a checksum of every block in the block that points to it, up to one
root (the uberblock): a block cannot change, nor a pointer be lost, without the
chain to the root breaking. A campar store is flatter, so its chain has two
links. The root record holds

- the store's format and its job's hash (the job itself is one of the variables);
- the checksum of every variable (``_metadata``): each array's metadata
  document, the coordinates' values, the store's own attributes;
- every tile's checksum (``_integrity``), 0 for a tile not committed: the
  commit flags and the tiles' checksums at once;

and its own digest (BLAKE2b, 16 bytes) over all of that. A reader takes the
record first and believes nothing it does not vouch for: a tile is committed
when the record says so, and then its ``done`` flag must be 1, its ``checksum``
element the record's, and its arrays must hash to it. So a lost or edited flag,
a lost or edited checksum, a lost or edited ``metadata_checksums`` attribute
are damage, never a pending tile or a store without checksums.

The commit of a tile is, in order: its arrays, its ``checksum`` element, its
``done`` flag, the root record. Zarr: the file ``campar-root.json`` at the
store's root, its first line the record, then one line a commit appended to it,
``<tile> <checksum> <chain>``, each line's chain the BLAKE2b of the one before
and of its own tile and checksum, the first chained to the record's digest — a
hash chain, as an append-only log keeps one: a commit costs one small write,
not a rewrite of the record. The lines are folded into a new record (written
aside and renamed) every ``FOLD_LINES`` commits and when the run closes the
store. HDF5: the attribute ``campar_root``, written with every checkpoint, the
journal's entries carrying their own checksums until then.

A kill before the record (its line) leaves the tile pending, and a line a kill
cut short is no commit; a reader during a run sees the tiles of the record as
it read it, each whole — its snapshot. A flag set where the record holds the
tile pending is a commit a kill interrupted (or an edit): pending, and cleared
by the next run. A line whose chain fails before the last is damage: the
record stops vouching there.
"""

import base64
import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ._atomic import write_file

ROOT_VERSION = 1
ZARR_FILE = "campar-root.json"  # beside the group's zarr.json; Zarr readers ignore it
HDF5_ATTR = "campar_root"  # the record of an HDF5 store: an attribute of its root group
# A global attribute every store with a root record has (under the global attributes'
# checksum): a store that says so and has no record lost it; one that does not was
# written before root records and is read only once adopted (``campar verify --adopt``).
MARK_ATTR = "root_record"
DIGEST_BYTES = 16
FOLD_LINES = 256  # commit lines appended before they are folded into a new record


class RootDamaged(ValueError):
    """A root record that cannot be read or fails its own digest (the message says why)."""


@dataclass(frozen=True, eq=False)
class Root:
    """A store's root record (see the module's docstring)."""

    format: int
    job_hash: str
    variables: dict[str, str]
    checksums: np.ndarray  # uint64 per tile; 0: not committed
    lines: int = 0  # commit lines read after the record (Zarr)
    chain: str = ""  # the last line's chain (the record's digest if none)
    problem: str | None = None  # why the lines stop before the file's end, if damaged

    @property
    def committed(self) -> np.ndarray:
        return self.checksums != 0

    def with_tiles(self, written) -> "Root":
        """This record with the tiles ``written`` ((tile, checksum) pairs) committed."""
        sums = self.checksums.copy()
        for tile, checksum in written:
            sums[tile.index] = checksum
        return Root(self.format, self.job_hash, self.variables, sums)

    def folded(self) -> "Root":
        """This record with its commit lines folded in (what a new record file holds)."""
        return Root(self.format, self.job_hash, self.variables, self.checksums.copy())

    def with_sums(self, sums: np.ndarray) -> "Root":
        """This record with every tile's checksum ``sums`` (0: pending)."""
        return Root(self.format, self.job_hash, self.variables, np.asarray(sums, np.uint64))

    def _body(self) -> dict:
        sums = np.ascontiguousarray(self.checksums, "<u8")
        return {
            "campar_root": ROOT_VERSION,
            "format": self.format,
            "job_hash": self.job_hash,
            "tiles": int(sums.size),
            "variables": dict(sorted(self.variables.items())),
            "checksums": base64.b64encode(sums.tobytes()).decode("ascii"),
        }

    @property
    def digest(self) -> str:
        """The record's own checksum (hex): what a user may keep to recognise the store."""
        return _digest(self._body())

    def encode(self) -> str:
        body = self._body()
        return json.dumps({**body, "digest": _digest(body)}, sort_keys=True)

    @classmethod
    def decode(cls, text: str | bytes) -> "Root":
        """The record from its text — its first line, and the commit lines after it (Zarr)
        up to the first that fails its chain (a last line a kill cut short is no commit);
        RootDamaged saying why if the record itself cannot be trusted."""
        if isinstance(text, str):
            text = text.encode()
        head, _, rest = text.partition(b"\n")
        root = cls._decode_head(head)
        sums, chain, lines = root.checksums.copy(), root.digest, rest.split(b"\n")
        count, problem = 0, None
        for number, line in enumerate(lines):
            parsed = _commit_line(line, chain, sums.size)
            if parsed is None:
                torn = number == len(lines) - 1  # no newline yet: a write a kill cut short
                if line and not torn:
                    problem = f"commit line {number + 1} fails its chain (edited or damaged)"
                break
            index, checksum, chain = parsed
            sums[index] = checksum
            count += 1
        return Root(root.format, root.job_hash, root.variables, sums, count, chain, problem)

    @classmethod
    def _decode_head(cls, text: bytes) -> "Root":
        try:
            data = json.loads(text)
        except (TypeError, ValueError, UnicodeDecodeError) as exc:
            raise RootDamaged(f"it is not JSON ({type(exc).__name__})") from None
        if not isinstance(data, dict):
            raise RootDamaged("it is not a JSON object")
        version = data.get("campar_root")
        if isinstance(version, int) and version > ROOT_VERSION:
            raise RootDamaged(f"its version {version} is newer than this campar's {ROOT_VERSION}")
        digest = data.pop("digest", None)
        if digest != _digest(data):
            raise RootDamaged("its own digest disagrees with its contents (edited or damaged)")
        try:
            sums = np.frombuffer(base64.b64decode(data["checksums"], validate=True), "<u8")
            root = cls(
                int(data["format"]),
                str(data["job_hash"]),
                {str(k): str(v) for k, v in data["variables"].items()},
                sums.astype(np.uint64),
            )
            if version != ROOT_VERSION or sums.size != data["tiles"]:
                raise ValueError("inconsistent")
        except (KeyError, TypeError, ValueError, AttributeError):
            raise RootDamaged("its fields are not those of a root record") from None
        return root


def commit_lines(chain: str, written) -> tuple[bytes, str]:
    """The lines appended for the tiles ``written`` ((tile, checksum) pairs) after the line
    whose chain is ``chain`` (the record's digest first): (their bytes, the last chain)."""
    out = []
    for tile, checksum in written:
        entry = f"{tile.index} {int(checksum):016x}"
        chain = _chain(chain, entry)
        out.append(f"{entry} {chain}\n")
    return "".join(out).encode(), chain


def _chain(previous: str, entry: str) -> str:
    return hashlib.blake2b(f"{previous} {entry}".encode(), digest_size=DIGEST_BYTES).hexdigest()


def _commit_line(line: bytes, chain: str, n_tiles: int):
    """(tile, checksum, chain) of a commit line that follows ``chain``; None if it does not."""
    try:
        index, checksum, link = line.decode("ascii").split(" ")
        entry = f"{int(index)} {int(checksum, 16):016x}"
    except (UnicodeDecodeError, ValueError):
        return None
    if link != _chain(chain, entry) or not 0 <= int(index) < n_tiles or int(checksum, 16) == 0:
        return None
    return int(index), int(checksum, 16), link


def _digest(body: dict) -> str:
    text = json.dumps(body, sort_keys=True, separators=(",", ":")).encode()
    return hashlib.blake2b(text, digest_size=DIGEST_BYTES).hexdigest()


def new_root(attrs: dict, variables: dict[str, str], n_tiles: int) -> Root:
    """The record of a store with no committed tile (``attrs``: its attributes, decoded)."""
    return Root(
        int(attrs["campar_store"]), str(attrs["job_hash"]), variables, np.zeros(n_tiles, "u8")
    )


def root_problems(root: Root, attrs: dict, n_tiles: int) -> list[str]:
    """What in a sound record disagrees with the store's attributes or its job's grid."""
    problems = []
    if root.format != attrs.get("campar_store"):
        problems.append(
            f"the root record says format {root.format}, the store's attributes "
            f"{attrs.get('campar_store')!r}"
        )
    if root.job_hash != attrs.get("job_hash"):
        problems.append(
            f"the root record holds job {root.job_hash}, the store's attributes "
            f"{attrs.get('job_hash')!r}"
        )
    if root.checksums.size != n_tiles:
        problems.append(
            f"the root record covers {root.checksums.size} tiles, the stored job has {n_tiles}"
        )
    return problems


def read_zarr_root(path: Path) -> Root | None:
    """The record of the Zarr store at ``path``, None if it has none; RootDamaged."""
    try:
        text = (path / ZARR_FILE).read_bytes()
    except FileNotFoundError:
        return None
    except IsADirectoryError:
        raise RootDamaged(f"{ZARR_FILE} is a directory") from None
    return Root.decode(text)


class RootLog:
    """The writer's side of a Zarr store's record: commits appended as chained lines,
    folded into a new record every ``FOLD_LINES`` and at ``close``."""

    def __init__(self, path: Path, root: Root):
        self.path, self.root = path, root
        self._file = None
        if root.problem is not None or root.lines:
            self.fold()  # a damaged or long tail: start from a clean record

    def commit(self, written) -> None:
        """Append the lines committing ``written`` ((tile, checksum) pairs), in one write."""
        if self.root.lines + len(written) > FOLD_LINES:
            self.root = self.root.with_tiles(written)
            self.fold()
            return
        data, chain = commit_lines(self.root.chain or self.root.digest, written)
        if self._file is None:
            self._file = open(self.path / ZARR_FILE, "ab", buffering=0)  # noqa: SIM115
        self._file.write(data)  # one write(2): a kill leaves whole lines and at most one cut
        root = self.root.with_tiles(written)
        self.root = Root(
            root.format,
            root.job_hash,
            root.variables,
            root.checksums,
            self.root.lines + len(written),
            chain,
        )

    def fold(self) -> None:
        """Write the record with every commit in it (aside, renamed); the lines start anew."""
        self.close()
        self.root = self.root.folded()
        write_zarr_root(self.path, self.root)

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None


def write_zarr_root(path: Path, root: Root) -> None:
    """Replace the record of the Zarr store at ``path`` whole (written aside, renamed)."""
    write_file(path / ZARR_FILE, (root.encode() + "\n").encode())
