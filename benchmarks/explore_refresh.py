"""What the explorer's look at an unchanged store costs: paired in one process, in
alternating blocks, ``MapSource.refresh`` as it is (the store's commit mark and the root
record's committed tiles, no tile flag read) against a look that reads every tile's flag
(``StoreReader.tile_flags``, what each look read while a tile was pending or masked), on
a store of synthetic tiles with its last tile pending (so the explorer keeps looking);
prints the CPU ms per look of each side.

    PYTHONPATH=. python benchmarks/explore_refresh.py [--tiles 400] [--suffix .zarr]
"""

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from campar.explore.source import MapSource
from campar.sweep.arrays import array_names, array_spec
from campar.sweep.job import Job
from campar.sweep.plan import plan_tiles
from campar.sweep.store import open_store, read_store

BLOCKS, LOOKS = 6, 10  # alternating blocks of looks, per side


def synthetic_tile(job: Job, tile, rng) -> dict:
    """A tile of 1-1 cells (kind 0, n = p = 1), its numbers random."""
    arrays = {}
    for name in array_names(job):
        dtype, tail = array_spec(job, name)
        shape = (tile.n_rows, job.shape[1], *tail)
        if dtype.kind == "f":
            arrays[name] = rng.random(shape).astype(dtype)
        else:
            arrays[name] = np.full(shape, 1 if name in ("n", "p") else 0, dtype)
    return arrays


def flags_look(path) -> None:
    with read_store(path) as reader:
        reader.tile_flags()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tiles", type=int, default=400)
    parser.add_argument("--suffix", default=".zarr", choices=(".zarr", ".h5"))
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"looks{args.suffix}"
        job = Job.from_dict(
            {
                "name": "looks",
                "sweep": {
                    "omega": {"from": 6.0, "to": 1.0, "points": 50},
                    "mu_cn": {"from": 0.9, "to": 0.6, "points": args.tiles},
                },
                "outputs": ["label", "dc"],
                "tiles": {"rows": 1},
            }
        )
        rng = np.random.default_rng(0)
        with open_store(path, job) as store:
            for tile in plan_tiles(job)[:-1]:
                store.write_tile(tile, synthetic_tile(job, tile, rng))
        source = MapSource(path)
        source.scan()
        sides = {"refresh": source.refresh, "flags": lambda: flags_look(path)}
        spent = {name: 0.0 for name in sides}
        for _ in range(BLOCKS):
            for name, look in sides.items():
                start = time.process_time()
                for _ in range(LOOKS):
                    look()
                spent[name] += time.process_time() - start
        for name, seconds in spent.items():
            print(
                f"{args.suffix} {args.tiles} tiles, {name}: "
                f"{seconds / (BLOCKS * LOOKS) * 1e3:.1f} ms CPU a look"
            )


if __name__ == "__main__":
    main()
