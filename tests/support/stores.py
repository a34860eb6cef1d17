"""Stores read whole and compared bit for bit."""

import numpy as np


def stored(path) -> dict[str, np.ndarray]:
    """Every per-cell array of a store, its checksums and done flags."""
    from campar.sweep.store import read_store

    with read_store(path) as reader:
        out = {name: reader.read(name) for name in reader.names}
        out["checksum"], _ = reader.tile_checksums()
        out["done"] = reader.done
    return out


def assert_same_store(a: dict, b: dict) -> None:
    """Two ``stored`` stores hold the same arrays, bit for bit."""
    assert sorted(a) == sorted(b)
    for name in a:
        assert a[name].dtype == b[name].dtype, name
        assert np.array_equal(a[name], b[name], equal_nan=True), name
