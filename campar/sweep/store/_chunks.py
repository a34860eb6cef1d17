"""Writing a tile's chunk of a Zarr array as zarr itself would, without zarr.

A tile's write is ~13 chunk files. Through zarr (``AsyncArray.setitem``: its codec
pipeline, event loop and thread pool) a tile costs several times the CPU of the file
system's own work; on a rank that computes while it writes, that CPU is the kernel's.
``DirectChunk`` encodes the chunk with the codec chain campar's arrays have (bytes,
little-endian, or variable-length UTF-8 for text; zstd or nothing; CRC32C:
``_zarr_documents.codecs``) and writes it as zarr's ``LocalStore`` does — aside, then
renamed into place (``_atomic``) — and leaves out a chunk that holds only the fill, as
zarr does (``write_empty_chunks`` false): the files are byte for byte zarr's
(tests/test_store.py), at a fraction of the CPU (chunks are files c.<i>.<j> with no
folder to make: ``_zarr.CHUNK_KEYS``). It reads the array's codecs from its zarr.json;
an array with any other codec chain (a store made by a later campar, say) is written
through zarr.
"""

import contextlib
import os
from pathlib import Path

import google_crc32c
import numpy as np
from numcodecs.vlen import VLenUTF8
from numcodecs.zstd import Zstd

from ._atomic import write_file
from ._zarr_documents import ZARR_JSON, chunk_key, read_document


class DirectChunk:
    """Encodes and writes chunks of one array (``for_document``: None if it cannot)."""

    def __init__(self, folder: Path, document: dict, dtype: np.dtype, zstd: Zstd | None):
        self.folder, self.zstd = folder, zstd
        self.document = document
        self.shape = tuple(document["chunk_grid"]["configuration"]["chunk_shape"])
        self.text = dtype.kind == "O"
        self.fill = np.full(self.shape, parse_fill(document["fill_value"], dtype), dtype)

    @classmethod
    def for_array(cls, folder: Path) -> "DirectChunk | None":
        """The writer of the array whose zarr.json lies in ``folder``."""
        return cls.for_document(folder, read_document(folder / ZARR_JSON))

    @classmethod
    def for_document(cls, folder: Path, document: dict) -> "DirectChunk | None":
        try:
            codecs = document["codecs"]
            if document["chunk_grid"]["name"] != "regular":
                return None
            if document["chunk_key_encoding"]["name"] != "default":
                return None
            names = [codec["name"] for codec in codecs]
            dtype = _dtype(document["data_type"])
            if dtype is None or len(codecs) not in (2, 3) or names[-1] != "crc32c":
                return None
            endian = codecs[0].get("configuration", {}).get("endian")
            if names[0] != ("vlen-utf8" if dtype.kind == "O" else "bytes"):
                return None
            if endian not in (None, "little"):
                return None
            zstd = None
            if len(codecs) == 3:
                config = codecs[1].get("configuration", {})
                if names[1] != "zstd" or config.get("checksum", False):
                    return None
                zstd = Zstd(level=config.get("level", 0))
            return cls(folder, document, dtype, zstd)
        except (KeyError, TypeError, ValueError, AttributeError):
            return None  # a document campar did not write: zarr reads it, or says why not

    def key(self, coords: tuple[int, ...]) -> str:
        """The chunk's file name, as zarr's default chunk key encoding names it."""
        return chunk_key(self.document, coords)

    def write(self, coords: tuple[int, ...], lead: int, values: np.ndarray) -> bool:
        """Write the chunk at ``coords`` holding ``values`` in its first rows (after ``lead``
        leading axes of length 1); False, writing nothing, where ``values`` do not fit it."""
        inner = self.shape[lead:]
        if values.shape[1:] != inner[1:] or values.shape[0] > inner[0]:
            return False
        if values.shape[0] == inner[0] and values.dtype == self.fill.dtype:  # the usual tile
            chunk = values.reshape(self.shape)
        else:
            chunk = self.fill.copy()
            chunk[(0,) * lead][: values.shape[0]] = values
        self.put(coords, chunk)
        return True

    def put(self, coords: tuple[int, ...], chunk: np.ndarray) -> None:
        """Write the chunk at ``coords`` whole (``chunk`` has the chunk's shape); delete it
        where it holds only the fill."""
        path = os.path.join(self.folder, self.key(coords))
        if self._is_fill(chunk):
            with contextlib.suppress(FileNotFoundError):
                os.unlink(path)  # as zarr deletes a chunk that became the fill
            return
        if self.text:
            body = VLENUTF8.encode(chunk)
        else:
            body = np.ascontiguousarray(chunk, chunk.dtype.newbyteorder("<")).tobytes()
        if self.zstd is not None:
            body = self.zstd.encode(body)
        body += google_crc32c.value(body).to_bytes(4, "little")  # zarr's Crc32cCodec
        try:
            write_file(path, body)
        except FileNotFoundError:  # the chunk's first write: its folder is made then
            os.makedirs(os.path.dirname(path), exist_ok=True)
            write_file(path, body)

    def _is_fill(self, chunk: np.ndarray) -> bool:
        """zarr's test (``NDBuffer.all_equal``): NaN equals NaN; a fill of 0.0 by its bits.
        The first element decides most chunks alone (a tile of numbers: not the fill)."""
        first = (slice(0, 1),) * chunk.ndim  # a view, never a copy
        if not self._is_fill_exact(chunk[first], self.fill[first]):
            return False
        return self._is_fill_exact(chunk, self.fill)

    @staticmethod
    def _is_fill_exact(chunk: np.ndarray, fill: np.ndarray) -> bool:
        if chunk.dtype.kind != "f":  # numbers, and text (object arrays compare by value)
            return bool(np.array_equal(chunk, fill))
        if fill.flat[0] == 0.0:
            return chunk.tobytes() == fill.tobytes()
        return bool(np.array_equal(chunk, fill, equal_nan=True))


VLENUTF8 = VLenUTF8()


def _dtype(name) -> np.dtype | None:
    """numpy's dtype of a Zarr data type campar writes (text as Python strings), else None."""
    if name == "string":
        return np.dtype(object)
    try:
        dtype = np.dtype(name)
    except TypeError:
        return None
    return dtype if dtype.kind in "biuf" and dtype.name == name else None


def parse_fill(value, dtype: np.dtype):
    """The fill value of a zarr.json (``_zarr_documents.fill_json``) as a number or text."""
    if dtype.kind == "f" and isinstance(value, str):
        return {"NaN": np.nan, "Infinity": np.inf, "-Infinity": -np.inf}[value]
    if dtype.kind == "O" and not isinstance(value, str):
        raise TypeError(f"a text fill value {value!r}")
    return value
