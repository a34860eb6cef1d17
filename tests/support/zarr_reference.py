"""A new store of a job built through zarr's own API: the reference campar's own writer of
Zarr documents (campar.sweep.store._zarr_documents) is checked against, file for file.

The same variables (``store_arrays``), attributes and codecs as campar's, each array made
by ``create_array`` and a coordinate's values by ``setitem``; the checksums of the
variables as zarr reads them back; every document consolidated by
``zarr.consolidate_metadata``; the root record.
"""

import json
import warnings
from pathlib import Path

import zarr
from zarr.codecs import Crc32cCodec, ZstdCodec
from zarr.errors import ZarrUserWarning

from campar.sweep.job import Job
from campar.sweep.plan import plan_tiles
from campar.sweep.store._metadata import CHECKSUMS_ATTR, digests
from campar.sweep.store._root import new_root, write_zarr_root
from campar.sweep.store._schema import TILE_ARRAYS, initial_attrs, store_arrays
from campar.sweep.store._zarr import describe_variables
from campar.sweep.store._zarr_documents import zarr_attrs


def build_with_zarr(path: Path, job: Job, separator: str = ".") -> None:
    attrs = initial_attrs(job)
    group = zarr.create_group(store=path, zarr_format=3, attributes=attrs)
    arrays = store_arrays(job)
    for a in arrays:
        text = a.dtype.kind == "U"
        array = group.create_array(
            a.name,
            shape=a.shape,
            dtype=str if text else a.dtype,
            chunks=a.chunks,
            fill_value="" if text else a.fill,
            dimension_names=list(a.dims),
            attributes=zarr_attrs(a.attrs, a.dtype),
            compressors=[Crc32cCodec()]
            if a.name in TILE_ARRAYS
            else [ZstdCodec(level=0), Crc32cCodec()],
            chunk_key_encoding={"name": "default", "separator": separator},
        )
        if a.values is not None:
            array[...] = a.values
    group = zarr.open_group(path, mode="r+", use_consolidated=False)
    recorded = digests(describe_variables(path, arrays, group, consolidated=False))
    group.attrs[CHECKSUMS_ATTR] = json.dumps(recorded)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ZarrUserWarning)
        zarr.consolidate_metadata(path)
    write_zarr_root(path, new_root(attrs, recorded, len(plan_tiles(job))))
