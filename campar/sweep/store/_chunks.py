"""Writing a tile's chunk of a Zarr array as zarr itself would, without its event loop.

A tile's write is ~13 chunk files. Through zarr (``AsyncArray.setitem``: its codec
pipeline, event loop and thread pool) a tile costs several times the CPU of the file
system's own work; on a rank that computes while it writes, that CPU is the kernel's.
``DirectChunk`` encodes the chunk with the codec chain campar's arrays have (bytes,
little-endian; zstd or nothing; CRC32C: ``_zarr._codecs``) and writes it as zarr's
``LocalStore`` does — aside as ``<key>.<32 hex>.partial``, then renamed into place — and
leaves out a chunk that holds only the fill, as zarr does (``write_empty_chunks``
false): the files are byte for byte zarr's (tests/test_store.py), at a fraction of the
CPU (chunks are files c.<i>.<j> with no folder to make: ``_zarr.CHUNK_KEYS``). An array
with any other codec chain (a store made by a later campar, say) is written through
zarr.
"""

import contextlib
import os
import uuid
from pathlib import Path

import google_crc32c
import numpy as np
from numcodecs.zstd import Zstd
from zarr.codecs import BytesCodec, Crc32cCodec, ZstdCodec


class DirectChunk:
    """Encodes and writes chunks of one array (``for_array``: None if it cannot)."""

    def __init__(self, folder: Path, array, zstd: Zstd | None):
        self.folder, self.array, self.zstd = folder, array, zstd
        self.shape = tuple(array.metadata.chunk_grid.chunk_shape)
        self.fill = np.full(self.shape, array.fill_value, array.dtype)
        self.write_empty = bool(array.config.write_empty_chunks)

    @classmethod
    def for_array(cls, folder: Path, array) -> "DirectChunk | None":
        codecs = tuple(array.metadata.codecs)
        if array.dtype.kind not in "biuf" or len(codecs) not in (2, 3):
            return None
        first, *middle, last = codecs
        if not (isinstance(first, BytesCodec) and isinstance(last, Crc32cCodec)):
            return None
        if first.endian is not None and first.endian.value != "little":
            return None
        zstd = None
        if middle:
            (codec,) = middle
            if not isinstance(codec, ZstdCodec) or codec.checksum:
                return None
            zstd = Zstd(level=codec.level)
        return cls(folder, array, zstd)

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
        path = os.path.join(self.folder, self.array.metadata.encode_chunk_key(coords))
        if not self.write_empty and self._is_fill(chunk):
            with contextlib.suppress(FileNotFoundError):
                os.unlink(path)  # as zarr deletes a chunk that became the fill
            return True
        data = np.ascontiguousarray(chunk, chunk.dtype.newbyteorder("<"))
        body = self.zstd.encode(data) if self.zstd is not None else data.tobytes()
        aside = f"{path}.{uuid.uuid4().hex}.partial"
        try:
            _put(aside, body)
        except FileNotFoundError:  # the chunk's first write: its folder is made then
            os.makedirs(os.path.dirname(path), exist_ok=True)
            _put(aside, body)
        os.replace(aside, path)
        return True

    def _is_fill(self, chunk: np.ndarray) -> bool:
        """zarr's test (``NDBuffer.all_equal``): NaN equals NaN; a fill of 0.0 by its bits.
        The first element decides most chunks alone (a tile of numbers: not the fill)."""
        first = (slice(0, 1),) * chunk.ndim  # a view, never a copy
        if not self._is_fill_exact(chunk[first], self.fill[first]):
            return False
        return self._is_fill_exact(chunk, self.fill)

    @staticmethod
    def _is_fill_exact(chunk: np.ndarray, fill: np.ndarray) -> bool:
        if chunk.dtype.kind != "f":
            return bool(np.array_equal(chunk, fill))
        if fill.flat[0] == 0.0:
            return chunk.tobytes() == fill.tobytes()
        return bool(np.array_equal(chunk, fill, equal_nan=True))


def _put(path: str, body: bytes) -> None:
    """A chunk file: its encoded bytes, then their CRC32C (zarr's ``Crc32cCodec``)."""
    with open(path, "wb") as file:
        file.write(body)
        file.write(google_crc32c.value(body).to_bytes(4, "little"))
