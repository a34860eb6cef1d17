"""What the root record costs a Zarr commit: paired in one process, commits (each tile's
checksum and done chunks) with and without the record's line, in alternating blocks of
10 commits over 800 tiles; prints the CPU ms per commit of each side.

    PYTHONPATH=. python benchmarks/root_commit_cost.py
"""

import json
import tempfile
import time
from pathlib import Path

import numpy as np

from campar.sweep.job import Job
from campar.sweep.plan import plan_tiles
from campar.sweep.store import TileWriter, _root, cell_arrays, open_store

job = Job.from_dict(
    {
        "name": "bench",
        "sweep": {
            "omega": {"from": 5.0, "to": 1.0, "points": 400},
            "mu_cn": {"from": 0.9, "to": 0.6, "points": 800},
        },
        "tiles": {"rows": 1},
    }
)
tiles = plan_tiles(job)
rng = np.random.default_rng(0)


def arrays(tile):
    return {
        a.name: (
            rng.normal(size=(tile.n_rows, *a.shape[1:]))
            if a.dtype.kind == "f"
            else rng.integers(0, 9, size=(tile.n_rows, *a.shape[1:]))
        ).astype(a.dtype)
        for a in cell_arrays(job)
    }


real_commit = _root.RootLog.commit
cpu = {"with": 0.0, "without": 0.0}
n = {"with": 0, "without": 0}
with tempfile.TemporaryDirectory() as tmp:
    path = Path(tmp) / "s.zarr"
    with open_store(path, job) as store:
        writer = TileWriter(store.real, job)
        sums = [(t, writer.write_tile(t, arrays(t))) for t in tiles]
        for b in range(0, len(sums), 10):
            side = "with" if (b // 10) % 2 == 0 else "without"
            _root.RootLog.commit = real_commit if side == "with" else (lambda self, w: None)
            t0 = time.process_time()
            for t, s in sums[b : b + 10]:
                store.commit_tiles([(t, s)])
            cpu[side] += time.process_time() - t0
            n[side] += 10
        _root.RootLog.commit = real_commit
print(json.dumps({k: 1e3 * cpu[k] / n[k] for k in cpu} | {"tiles": len(tiles)}))
