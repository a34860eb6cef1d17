"""``campar.open``: a result store as an xarray Dataset, labelled and described.

The store is CF-1.10 on both backends (``campar.sweep.store``), so this is
xarray's own reader (``xarray.open_zarr``, or ``xarray.open_dataset`` with the
h5netcdf engine for HDF5) and both backends give the same Dataset, with:

- integer arrays (codes and counts) kept integers: their ``_FillValue`` (-1, a
  cell not computed yet) stays an attribute instead of turning them into
  floats, so ``flags & mask`` and ``kind == code`` work; floats are NaN there;
- a snapshot: every per-cell array holds, tile by tile, the very bytes that were
  read and verified against the store's root record (``campar.sweep.store._root``),
  and the fill where a tile is not committed in the record the reader took, or is
  damaged; ``done`` says which. A store that a run is writing (Zarr or HDF5, its
  journal included) reads as it was at one commit, never a tile half written;
- ``label``: every cell's n-p label as text ("2-2", "1-7~", "QP", "chaos", …;
  "" where not computed), as ``campar.core.codes.cell_label`` gives it with
  the job's ``classify.chatter_p``;
- text as numpy ``str`` arrays and flag attributes as arrays of their
  variable's type, whichever backend.
- ``separation_speed``, ``contact_eps_max``, ``contact_pn_max`` (second), where the job
  asked for the ``separation`` output: each row's separation speed and the largest
  intrusion and contact force below it (campar.sweep.separation), stored in every cell
  of the row and given here once a row;
- ``attractor_label`` (second, omega, attractor), where the job asked for a census of
  attractors (``attractors``): the n-p label of each stored attractor, as ``label``.

A ``chains.direction: both`` store has a ``direction`` dimension (down, up) on
every per-cell array and ``label``, and one more variable, ``hysteresis``
(second, omega): True where the two directions end on different converged
cycles (``hysteresis_cells``). It is derived here, when the store is opened,
not stored: it is a function of stored arrays alone (the two directions'
``kind``, ``status``, ``n`` and ``sections``), so it needs no commit or checksum
of its own, is never stale after a repaired tile, and the raw ``xr.open_zarr``
or ``xr.open_dataset`` of the store holds everything it is computed from
(``hysteresis(ds)`` computes it on such a Dataset).

A basin store (a job sweeping ``y0``, ``ydot0``) has ``basin`` (ydot0, y0), the
attractor each start reached, and per attractor (dimension ``attractor``) its n, p,
kind, label, starts, fraction, σn points and multipliers (``campar.views.basins``),
derived here as ``hysteresis`` is.

A store of format 1 (before the CF metadata) is read through ``read_store``
and given the current format's variables and attributes, built from its job:
its numbers are laid out alike. The Dataset is in memory (the store's size
uncompressed) and holds no file open. To follow a run, ``committed(path)`` says
cheaply which tiles are committed now (the root record alone, no tile read): open
the store again when it differs from the Dataset's ``done``.
"""

import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from ..core.codes import KIND_LABELS, cell_label
from ..errors import StoreDamaged, StoreDamageWarning
from ..sweep.census import cycle_tolerance
from ..sweep.store import (
    CHECKSUMS_ATTR,
    FORMAT,
    ROOT_ATTRS,
    backend_name,
    cell_arrays,
    committed_tiles,
    read_store,
    store_arrays,
    upgraded_attrs,
    verify_store,
)
from .basins import basin_variables
from .cycles import hysteresis_cells

NOT_COMPUTED = -1  # the integer arrays' fill value
# Per-row variables (the second axis alone) of the ``separation`` output's arrays.
SEPARATION_ROWS = {
    "separation_omega": "separation_speed",
    "separation_eps_max": "contact_eps_max",
    "separation_pn_max": "contact_pn_max",
}
TYPED_ATTRS = ("_FillValue", "flag_values", "flag_masks")  # CF: the variable's own type


def open(path: str | Path) -> xr.Dataset:
    """The store at ``path`` (Zarr directory or HDF5 file) as a labelled xarray Dataset.

    The integer codes stay integers, −1 where a cell is not computed yet; ``label`` adds
    the n-p text of every cell, a ``both`` store ``hysteresis``, a census
    ``attractor_label``, a basin store ``basin`` and the attractors' variables.

    Nothing is read unverified: every committed tile is checked against its checksum and
    every variable (coordinates, metadata, decoding attributes) against its own first, both
    as the store's root record holds them (docs/stores.md). During a run the Dataset is a
    snapshot: each tile whole as committed and verified, or not computed (``done`` 0). A
    damaged tile reads as not computed (its cells the fill, its
    ``done`` 0), with a StoreDamageWarning naming it; ``campar run`` repairs it.

    Parameters
    ----------
    path : str or pathlib.Path
        A Zarr store (a directory) or an HDF5 store (``.h5``, ``.hdf5``).

    Returns
    -------
    xarray.Dataset
        Every per-cell array over (second parameter, ω), with CF metadata.

    Raises
    ------
    campar.errors.StoreError
        No readable campar store at ``path``.
    campar.errors.StoreDamaged
        A damaged variable (a wrong coordinate or decoding attribute would make every value
        wrong), or an HDF5 file damaged; ``campar run`` repairs both.

    Examples
    --------
    >>> import campar
    >>> ds = campar.open("results/smoke.zarr")
    >>> ds.sizes["mu_cn"], ds.sizes["omega"]
    (24, 40)
    >>> ds.label.sel(omega=3, mu_cn=0.8, method="nearest").item()
    '1-1'
    """
    path = Path(path)
    with read_store(path) as reader:
        if reader.file_damage:  # xarray would hand the damaged file to HDF5 itself
            raise StoreDamaged(f"{path}: {reader.file_damage}; `campar run` repairs it")
        cells = {a.name: np.full(a.shape, a.fill, a.dtype) for a in cell_arrays(reader.job)}

        def take(check) -> None:  # a tile that verified: these very bytes, no second read
            for name, values in check.arrays.items():
                cells[name][check.tile.region] = values

        report = verify_store(reader, take)
        if report.variables or reader.root_problem:
            said = [f"variable {name}: {why}" for name, why in report.variables.items()]
            said += [reader.root_problem] if reader.root_problem else []
            raise StoreDamaged(
                f"{path} is damaged: {'; '.join(said)}; `campar run` rewrites it from the job "
                "(`campar verify` lists every problem)"
            )
        if reader.format == FORMAT:
            ds = _open_current(path, reader, cells, report)
        else:
            ds = _from_reader(reader, cells, report)
        if report.damaged:
            warnings.warn(damage_warning(path, report.damaged), StoreDamageWarning, stacklevel=2)
        job = reader.job
    ds = _normalise(ds)
    for key in (CHECKSUMS_ATTR, *ROOT_ATTRS):  # the store's own bookkeeping, checked
        ds.attrs.pop(key, None)
    if job.kind == "curves":  # its per-point arrays as stored (views.map_curves.read_curves)
        return ds
    c = job.classify.chatter_p
    ds["label"] = (
        ds["kind"].dims,
        cell_labels(ds["kind"].values, ds["n"].values, ds["p"].values, c),
        {
            "long_name": "n-p label",
            "comment": f"n-p where kind is periodic, n-p~ where p ≥ chatter_p = {c} "
            f"(chattering impacts); else {', '.join(KIND_LABELS.values())}; "
            "empty where not computed",
        },
    )
    if "attractor_kind" in ds:  # a census of attractors (job key attractors)
        ds["attractor_label"] = (
            ds["attractor_kind"].dims,
            cell_labels(
                ds["attractor_kind"].values, ds["attractor_n"].values, ds["attractor_p"].values, c
            ),
            {
                "long_name": "n-p label of the attractor",
                "comment": "as label, of each attractor of the cell's census, most frequent "
                "first; empty where the cell has fewer attractors or is not computed",
            },
        )
    if "direction" in ds.dims:
        ds["hysteresis"] = hysteresis(ds, job)
    for name in SEPARATION_ROWS:  # the row's value, the same in each of its cells
        if name in ds:
            row = ds[name].isel(omega=0, drop=True)
            ds[SEPARATION_ROWS[name]] = row.assign_attrs(ds[name].attrs)
    if job.kind == "basin":  # which attractor each start reached
        ds = ds.assign(basin_variables(ds, job))
    return ds


def committed(path: str | Path) -> np.ndarray:
    """Per tile (``ds.tile``), whether the store at ``path`` holds it committed now.

    Reads the store's root record alone (and an HDF5 store's journal listing), no tile: a
    view following a run asks this every second or so and calls ``open`` again when it
    differs from its Dataset's ``done``. A tile committed here may still prove damaged
    when ``open`` verifies it (then it reads as not computed, with a warning).

    Parameters
    ----------
    path : str or pathlib.Path
        A Zarr store (a directory) or an HDF5 store (``.h5``, ``.hdf5``).

    Returns
    -------
    numpy.ndarray
        bool, one per tile.

    Raises
    ------
    campar.errors.StoreError
        No campar store with a root record at ``path``.
    campar.errors.StoreDamaged
        Its root record is damaged.

    Examples
    --------
    >>> import campar
    >>> ds = campar.open("results/smoke.zarr")
    >>> fresh = (campar.committed("results/smoke.zarr") != ds.done.values.astype(bool)).any()
    """
    return committed_tiles(path)


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


def _open_current(path: Path, reader, cells: dict, report) -> xr.Dataset:
    """The store as xarray reads it (attributes, coordinates, encodings), its per-cell arrays
    and per-tile flags and checksums replaced by the snapshot's, all in memory."""
    integers = {a.name: False for a in store_arrays(reader.job) if a.dtype.kind in "iu"}
    engine = "h5netcdf" if backend_name(path) == "hdf5" else "zarr"
    with xr.open_dataset(path, engine=engine, mask_and_scale=integers, chunks=None) as lazy:
        variables = {}
        for name, values in {**cells, **_tile_variables(report)}.items():
            old = lazy[name].variable
            data = values.astype(old.dtype)
            variables[name] = xr.Variable(old.dims, data, old.attrs, old.encoding)
        return lazy.assign(variables).load()


def _tile_variables(report) -> dict[str, np.ndarray]:
    """``done`` and ``checksum`` as the snapshot has them: set on the tiles that verified."""
    out = {"done": report.verified.astype(np.int8)}
    if report.sums is not None:
        out["checksum"] = np.where(report.verified, report.sums, 0).astype(np.uint64)
    return out


SHOWN_TILES = 5  # damaged tiles a warning names (with why); `campar verify` lists all


def damage_warning(path: Path, damaged: dict[int, str]) -> str:
    shown = "; ".join(f"tile {i}: {why}" for i, why in sorted(damaged.items())[:SHOWN_TILES])
    more = f"; … {len(damaged) - SHOWN_TILES} more" if len(damaged) > SHOWN_TILES else ""
    return (
        f"{path}: {len(damaged)} damaged tiles read as not computed ({shown}{more}); "
        "`campar run` computes them again"
    )


def _from_reader(reader, cells: dict, report) -> xr.Dataset:
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
            data = report.verified.astype(a.dtype)
        elif a.name == "checksum":  # none before format 3
            data = np.zeros(a.shape, a.dtype)
        else:
            data = cells[a.name]
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


# -- hysteresis: the two sweep directions on different attractors ----------------------

BLOCK_ROWS = 64  # chains compared at once: ~26 MB of σn points for 400 ω values


def hysteresis(ds: xr.Dataset, job=None) -> xr.DataArray:
    """The ``hysteresis`` variable of a ``both`` store's Dataset (``campar.open``'s, or
    the raw ``xr.open_zarr``/``xr.open_dataset`` one: then ``job`` is read from its
    attributes). Computed BLOCK_ROWS chains at a time: memory does not grow with the map."""
    if job is None:
        import json

        from ..sweep.job import Job

        job = Job.from_dict(json.loads(ds.attrs["job"]), source="job of the Dataset")
    if "direction" not in ds.dims:
        raise ValueError("hysteresis needs a store of a chains.direction: both job")
    tol = cycle_tolerance(job)
    second = job.second
    out = np.zeros((ds.sizes[second], ds.sizes["omega"]), bool)
    block = job.tiles.rows * max(1, BLOCK_ROWS // job.tiles.rows)  # whole chunks at a time
    for start in range(0, out.shape[0], block):
        rows = slice(start, start + block)
        sides = [
            {
                name: _integers(ds[name].isel({"direction": layer, second: rows}).values)
                if name != "sections"
                else ds[name].isel({"direction": layer, second: rows}).values
                for name in ("kind", "status", "n", "sections")
            }
            for layer in (0, 1)
        ]
        out[rows] = hysteresis_cells(*sides, tol)
    return xr.DataArray(
        out,
        dims=(second, "omega"),
        coords={second: ds[second], "omega": ds["omega"]},
        attrs={
            "long_name": "hysteresis: the two sweep directions end on different cycles",
            "comment": "True where both directions (down, up) converged to periodic motions "
            "(kind periodic, status ok) whose stroboscopic section points differ: not "
            f"equal within {tol:.3g} (infinity norm) after any cyclic shift, cycles of "
            "different n compared over their common multiple of revolutions; False "
            "elsewhere, also where either direction is not periodic, not converged, "
            "failed or not computed (never NaN)",
            "tolerance": tol,
        },
    )
