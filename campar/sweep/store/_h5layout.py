"""An HDF5 store file as campar lays it out: built in memory from a job (a netCDF-4 file,
with the Zarr store's names), described variable by variable for the checksums
(``_metadata``), its root record (``_root``) an attribute.

Both the backend (``_hdf5``) and the rescue child (``_h5guard``) build files; this
module imports neither.
"""

import json
from pathlib import Path

import h5py
import numpy as np

from ..job import Job
from ..plan import plan_tiles
from ._integrity import describe_exception
from ._metadata import CHECKSUMS_ATTR, GLOBAL, Variable, digests, global_document
from ._root import HDF5_ATTR, Root, new_root
from ._schema import TILE_ARRAYS, ArraySchema, decode_attrs, initial_attrs, store_arrays

USERBLOCK = 512  # bytes at the start of the file that HDF5 leaves to the application (the seal)


def write_attrs(node, attrs: dict, dtype: np.dtype | None = None) -> None:
    """HDF5 attributes: text as UTF-8 strings, numbers typed as netCDF wants them."""
    for key, value in attrs.items():
        if key == "_FillValue" or isinstance(value, np.ndarray):
            value = np.asarray(value, dtype)  # CF: the variable's own type
        elif isinstance(value, bool | int):
            value = np.int32(value)
        node.attrs[key] = value


def build(tmp: Path, job: Job) -> None:
    """A new empty store file of ``job`` at ``tmp``, with room for its seal (not sealed).
    Built in memory and written by Python: HDF5 never meets a full disk."""
    memory = dict(driver="core", backing_store=False, userblock_size=USERBLOCK)
    with h5py.File(tmp.name, "w", track_order=True, **memory) as f:
        _layout(f, job)
        f.flush()
        image = f.id.get_file_image()  # the HDF5 part: the user block is the caller's
    with open(tmp, "wb") as fh:
        fh.write(bytes(USERBLOCK))
        fh.write(image)


def _layout(f: h5py.File, job: Job) -> None:
    arrays = store_arrays(job)
    write_attrs(f, initial_attrs(job))
    dims = [a.name for a in arrays if a.is_dimension]
    for a in arrays:
        data = _create_dataset(f, a)
        if a.is_dimension:
            data.make_scale(a.name)
            data.attrs["_Netcdf4Dimid"] = np.int32(dims.index(a.name))
        else:
            for axis, dim in enumerate(a.dims):
                data.dims[axis].attach_scale(f[dim])
        write_attrs(data, a.attrs, a.dtype)
    variables = digests(describe_file(f, arrays))
    f.attrs[CHECKSUMS_ATTR] = json.dumps(variables)
    root = new_root(decode_attrs(f.attrs), variables, len(plan_tiles(job)))
    f.attrs[HDF5_ATTR] = root.encode()


def file_root(attrs) -> Root | None:
    """The root record among a file's attributes, None if it has none; RootDamaged."""
    if HDF5_ATTR not in attrs:
        return None
    text = attrs[HDF5_ATTR]
    return Root.decode(text.decode(errors="replace") if isinstance(text, bytes) else text)


# Attributes HDF5 keeps for dimension scales: references to other datasets, which change
# with the file's layout, not with what the values mean.
SCALE_LINKS = ("DIMENSION_LIST", "REFERENCE_LIST")


def describe_file(f: h5py.File, arrays) -> dict:
    """{name: ``_metadata.Variable``, or why it cannot be read} of the variables ``arrays``
    of an open store file: each dataset's type, shape, chunks, fill value, filters and
    attributes, and a coordinate's values."""
    attrs = {key: _plain(value) for key, value in f.attrs.items()}
    found: dict = {GLOBAL: Variable({"attributes": global_document(attrs)})}
    for a in arrays:
        try:
            data = f[a.name]
            document = {
                "dtype": data.dtype.str,
                "shape": list(data.shape),
                "chunks": list(data.chunks) if data.chunks else None,
                "fillvalue": _plain(data.fillvalue),
                "compression": data.compression,
                "compression_opts": _plain(data.compression_opts),
                "shuffle": data.shuffle,
                "scaleoffset": data.scaleoffset,
                "fletcher32": data.fletcher32,
                "attrs": {
                    key: _plain(value)
                    for key, value in data.attrs.items()
                    if key not in SCALE_LINKS
                },
            }
            values = np.asarray(data[()]) if a.values is not None else None
        except KeyError:
            found[a.name] = f"dataset {a.name} is missing"
            continue
        except Exception as exc:  # h5py raises many kinds
            found[a.name] = f"dataset {a.name} unreadable ({describe_exception(exc)})"
            continue
        found[a.name] = Variable({a.name: document}, values)
    return found


def _plain(value):
    """An attribute or property as a JSON value (text from bytes, lists from arrays)."""
    if isinstance(value, bytes):
        return value.decode(errors="replace")
    if isinstance(value, np.ndarray):
        return [_plain(v) for v in value.tolist()]
    if isinstance(value, np.generic):
        return _plain(value.item())
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value if isinstance(value, str | int | float | bool | type(None)) else repr(value)


def fresh_variables(job: Job, arrays) -> dict:
    """The variables of a store file of ``job`` built afresh (in memory)."""
    memory = dict(driver="core", backing_store=False, userblock_size=USERBLOCK)
    with h5py.File("expected.h5", "w", track_order=True, **memory) as f:
        _layout(f, job)
        return describe_file(f, arrays)


def _create_dataset(f: h5py.File, a: ArraySchema) -> h5py.Dataset:
    if a.dtype.kind == "U":
        return f.create_dataset(
            a.name, data=a.values.astype(object), dtype=h5py.string_dtype(), track_order=True
        )
    if a.values is not None:
        return f.create_dataset(a.name, data=a.values, dtype=a.dtype, track_order=True)
    return f.create_dataset(
        a.name,
        shape=a.shape,
        dtype=a.dtype,
        chunks=a.chunks,
        fillvalue=a.fill,
        compression=None if a.name in TILE_ARRAYS else "gzip",
        track_order=True,
    )
