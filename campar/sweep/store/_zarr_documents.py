"""A Zarr v3 store's metadata documents as zarr writes them, written without zarr.

A run creates its store, writes its tiles and appends to its run log; none of that needs
zarr's machinery (its import, event loop and thread pool are a good part of a
``campar run``'s start-up, benchmarks/RESULTS.md). The documents here are zarr 3's own,
key for key and byte for byte (``json.dumps`` with zarr's ``json_indent`` of 2,
tests/test_store.py builds a store both ways): an array's ``zarr.json`` from its
``ArraySchema``, the group's, and the group's copy of every array's (consolidated
metadata, sorted as zarr sorts it). Reading, verifying and repairing a store still go
through zarr (``_zarr``), as every other reader does.

Every document is written aside and renamed into place (``_atomic``).
"""

import base64
import json
import math
import struct
import unicodedata
from pathlib import Path

import numpy as np

from ._atomic import write_file
from ._schema import TILE_ARRAYS, ArraySchema

ZARR_JSON = "zarr.json"
JSON_INDENT = 2  # zarr's default ``json_indent``


def array_document(a: ArraySchema, separator: str) -> dict:
    """The zarr.json zarr writes for the array ``a`` (zarr_attrs: its attributes as JSON)
    with chunk keys c<sep><i><sep><j>."""
    document = {
        "shape": list(a.shape),
        "data_type": data_type(a.dtype),
        "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": list(a.chunks)}},
        "chunk_key_encoding": {"name": "default", "configuration": {"separator": separator}},
        "fill_value": fill_json(a.fill, a.dtype),
        "codecs": codecs(a.name, a.dtype),
        "attributes": zarr_attrs(a.attrs, a.dtype),
    }
    if a.dims:
        document["dimension_names"] = list(a.dims)
    return {**document, "zarr_format": 3, "node_type": "array", "storage_transformers": []}


def zarr_attrs(attrs: dict, dtype: np.dtype) -> dict:
    """Attributes as JSON values; ``_FillValue`` encoded as xarray reads it from Zarr v3."""
    out = {}
    for key, value in attrs.items():
        if key == "_FillValue" and dtype.kind == "f":
            value = base64.standard_b64encode(struct.pack("<d", value)).decode()
        elif isinstance(value, np.ndarray):
            value = value.tolist()
        out[key] = value
    return out


def data_type(dtype: np.dtype) -> str:
    dtype = np.dtype(dtype)
    if dtype.kind == "U":
        return "string"
    if dtype.kind not in "biuf":
        raise TypeError(f"no Zarr data type written for {dtype}")
    return dtype.name


def fill_json(fill, dtype: np.dtype):
    """The fill value as zarr's metadata holds it (None: zarr's default, zero or empty)."""
    dtype = np.dtype(dtype)
    if dtype.kind == "U":
        return "" if fill is None else str(fill)
    if dtype.kind == "b":
        return False if fill is None else bool(fill)
    if dtype.kind in "iu":
        return 0 if fill is None else int(fill)
    value = 0.0 if fill is None else float(fill)
    if math.isnan(value):
        return "NaN"
    if math.isinf(value):
        return "Infinity" if value > 0 else "-Infinity"
    return value


def codecs(name: str, dtype: np.dtype) -> list[dict]:
    """Zstd for the arrays (not the one-byte flags), then a CRC32C of every chunk's bytes:
    a chunk changed on disk fails to read, even where zstd would decode it alike."""
    dtype = np.dtype(dtype)
    if dtype.kind == "U":
        first = {"name": "vlen-utf8", "configuration": {}}
    elif dtype.itemsize > 1:
        first = {"name": "bytes", "configuration": {"endian": "little"}}
    else:
        first = {"name": "bytes"}
    zstd = [] if name in TILE_ARRAYS else [ZSTD]
    return [first, *zstd, {"name": "crc32c"}]


ZSTD = {"name": "zstd", "configuration": {"level": 0, "checksum": False}}


def chunk_key(document: dict, coords: tuple[int, ...]) -> str:
    """A chunk's file name in its array's folder, by zarr's default chunk key encoding."""
    separator = document["chunk_key_encoding"]["configuration"]["separator"]
    return separator.join(["c", *map(str, coords)])


def group_document(attributes: dict, arrays: dict[str, dict] | None = None) -> dict:
    """The group's zarr.json; with ``arrays`` ({name: its document}) consolidated into it,
    ordered as zarr orders them."""
    document: dict = {"attributes": attributes, "zarr_format": 3}
    if arrays is not None:
        document["consolidated_metadata"] = {
            "kind": "inline",
            "must_understand": False,
            "metadata": {name: arrays[name] for name in sorted(arrays, key=_consolidated_order)},
        }
    document["node_type"] = "group"
    return document


def _consolidated_order(name: str):
    return name.count("/"), unicodedata.normalize("NFKC", name).casefold()


def encode(document: dict) -> bytes:
    return json.dumps(document, indent=JSON_INDENT, allow_nan=True).encode()


def read_document(path: Path) -> dict:
    return json.loads(path.read_bytes())


def write_document(path: Path, document: dict) -> None:
    """Replace ``path`` by ``document``: written aside, renamed into place."""
    write_file(path, encode(document))
