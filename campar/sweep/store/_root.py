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
``done`` flag, the root record (Zarr: the file ``campar-root.json`` at the
store's root, written aside and renamed; HDF5: the attribute ``campar_root``,
written with every checkpoint, the journal's entries carrying their own
checksums until then). A kill before the record leaves the tile pending; a
reader during a run sees the tiles of the record it read, each whole — its
snapshot. A flag set where the record holds the tile pending is a commit a kill
interrupted (or an edit): pending, and cleared by the next run.
"""

import base64
import hashlib
import json
import os
import uuid
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT_VERSION = 1
ZARR_FILE = "campar-root.json"  # beside the group's zarr.json; Zarr readers ignore it
HDF5_ATTR = "campar_root"  # the record of an HDF5 store: an attribute of its root group
# A global attribute every store with a root record has (under the global attributes'
# checksum): a store that says so and has no record lost it; one that does not was
# written before root records and is read only once adopted (``campar verify --adopt``).
MARK_ATTR = "root_record"
DIGEST_BYTES = 16


class RootDamaged(ValueError):
    """A root record that cannot be read or fails its own digest (the message says why)."""


@dataclass(frozen=True, eq=False)
class Root:
    """A store's root record (see the module's docstring)."""

    format: int
    job_hash: str
    variables: dict[str, str]
    checksums: np.ndarray  # uint64 per tile; 0: not committed

    @property
    def committed(self) -> np.ndarray:
        return self.checksums != 0

    def with_tiles(self, written) -> "Root":
        """This record with the tiles ``written`` ((tile, checksum) pairs) committed."""
        sums = self.checksums.copy()
        for tile, checksum in written:
            sums[tile.index] = checksum
        return Root(self.format, self.job_hash, self.variables, sums)

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
        """The record from its text; RootDamaged saying why if it cannot be trusted."""
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


def write_zarr_root(path: Path, root: Root) -> None:
    """Replace the record of the Zarr store at ``path`` whole (written aside, renamed)."""
    final = path / ZARR_FILE
    tmp = path / f"{ZARR_FILE}.{uuid.uuid4().hex}.partial"  # as zarr's: clean_leftovers
    try:
        with open(tmp, "w") as fh:
            fh.write(root.encode())
        os.replace(tmp, final)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
