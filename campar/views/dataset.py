"""``campar.open``: a result store as an xarray Dataset, labelled and described.

The store is CF-1.10 on both backends (``campar.sweep.store``), so this is
xarray's own reader (``xarray.open_zarr``, or ``xarray.open_dataset`` with the
h5netcdf engine for HDF5) and both backends give the same Dataset, with:

- integer arrays (codes and counts) kept integers: their ``_FillValue`` (-1, a
  cell not computed yet) stays an attribute instead of turning them into
  floats, so ``flags & mask`` and ``kind == code`` work; floats are NaN there;
- the tiles an HDF5 run has committed to its journal but not checkpointed yet
  (then the Dataset is loaded into memory), so it shows what ``campar status`` counts;
- ``label``: every cell's n-p label as text ("2-2", "1-7~", "QP", "chaos", …;
  "" where not computed), as ``campar.core.codes.cell_label`` gives it with
  the job's ``classify.chatter_p``;
- text as numpy ``str`` arrays and flag attributes as arrays of their
  variable's type, whichever backend.

A store of format 1 (before the CF metadata) is read through ``read_store``
and given the current format's variables and attributes, built from its job:
its numbers are laid out alike. The Dataset reads lazily; close it (or use
``with``) to release the file.
"""

from pathlib import Path

import numpy as np
import xarray as xr

from ..core.codes import KIND_LABELS, cell_label
from ..errors import StoreDamaged
from ..sweep.plan import plan_tiles
from ..sweep.store import FORMAT, backend_name, read_store, store_arrays, upgraded_attrs

NOT_COMPUTED = -1  # the integer arrays' fill value
TYPED_ATTRS = ("_FillValue", "flag_values", "flag_masks")  # CF: the variable's own type


def open(path: str | Path) -> xr.Dataset:
    """The store at ``path`` (Zarr directory or HDF5 file) as a labelled xarray Dataset."""
    path = Path(path)
    with read_store(path) as reader:
        if reader.file_damage:  # xarray would hand the damaged file to HDF5 itself
            raise StoreDamaged(f"{path}: {reader.file_damage}; `campar run` repairs it")
        ds = _open_current(path, reader) if reader.format == FORMAT else _from_reader(reader)
        job = reader.job
    ds = _normalise(ds)
    c = job.classify.chatter_p
    ds["label"] = (
        (job.second, "omega"),
        cell_labels(ds["kind"].values, ds["n"].values, ds["p"].values, c),
        {
            "long_name": "n-p label",
            "comment": f"n-p where kind is periodic, n-p~ where p ≥ chatter_p = {c} "
            f"(chattering impacts); else {', '.join(KIND_LABELS.values())}; "
            "empty where not computed",
        },
    )
    return ds


def cell_labels(kind, n, p, chatter_p: int = 7) -> np.ndarray:
    """``cell_label`` of every cell, vectorised: each distinct (kind, n, p) is labelled once.

    Arrays of any one shape; -1 (or NaN) in ``kind`` is a cell not computed: "".
    """
    kind, n, p = (_integers(a) for a in np.broadcast_arrays(kind, n, p))
    triples, inverse = np.unique(
        np.stack([kind.ravel(), n.ravel(), p.ravel()]), axis=1, return_inverse=True
    )
    labels = np.array([_label(k, a, b, chatter_p) for k, a, b in triples.T.tolist()], str)
    return labels[inverse.ravel()].reshape(kind.shape)


def _integers(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a)
    if a.dtype.kind == "f":
        a = np.where(np.isfinite(a), a, NOT_COMPUTED)
    return a.astype(np.int64)


def _label(kind: int, n: int, p: int, chatter_p: int) -> str:
    if kind == NOT_COMPUTED:
        return ""
    try:
        return cell_label(kind, n, p, chatter_p)
    except ValueError:  # a kind this campar does not know
        return f"kind {kind}"


def _open_current(path: Path, reader) -> xr.Dataset:
    integers = {a.name: False for a in store_arrays(reader.job) if a.dtype.kind in "iu"}
    engine = "h5netcdf" if backend_name(path) == "hdf5" else "zarr"
    ds = xr.open_dataset(path, engine=engine, mask_and_scale=integers, chunks=None)
    if reader.journaled:
        ds.load()
        tiles, sums = plan_tiles(reader.job), reader.tile_checksums()[0]
        for index, arrays in reader.journaled.items():
            rows = {reader.job.second: tiles[index].rows}
            for name, values in arrays.items():
                ds[name][rows] = values
            ds["checksum"][index] = sums[index]
            ds["done"][index] = 1
    return ds


def _from_reader(reader) -> xr.Dataset:
    """An older store as the current format opens: variables and attributes from its job."""
    variables, coords = {}, []
    for a in store_arrays(reader.job):
        attrs = {k: v for k, v in a.attrs.items() if k != "coordinates"}
        encoding = {}
        if a.dtype.kind == "f" and "_FillValue" in attrs:  # decoded, as xarray does
            encoding["_FillValue"] = attrs.pop("_FillValue")
        if a.values is not None:
            data = a.values
            coords.append(a.name)
        elif a.name == "done":
            data = reader.done.astype(a.dtype)
        elif a.name == "checksum":  # none before format 3
            data = np.zeros(a.shape, a.dtype)
        else:
            data = reader.read(a.name)
        variables[a.name] = xr.Variable(a.dims, data, attrs, encoding)
    ds = xr.Dataset(variables).set_coords(coords)
    ds.attrs = upgraded_attrs(reader.job, reader.attrs)
    return ds


def _normalise(ds: xr.Dataset) -> xr.Dataset:
    """Text as numpy str, typed attributes in their variable's type (Zarr keeps JSON lists)."""
    for var in ds.variables.values():
        for key in TYPED_ATTRS:
            if key in var.attrs:
                var.attrs[key] = np.asarray(var.attrs[key], var.dtype)[()]
    text = [name for name, var in ds.variables.items() if var.dtype.kind in "OT"]
    return ds.assign_coords(
        {name: ds[name].copy(data=np.array(ds[name].values.tolist(), str)) for name in text}
    )
