"""CPU seconds of the computation alone of the first 20 rows (8,000 cells) of the
(ω, μcn) plane, jobs/mu_cn.yaml at 400 × 400, in this process's campar (PYTHONPATH):
every tile computed once to compile or load the kernel, then again timed.

    PYTHONPATH=TREE python benchmarks/extrema_cost.py [ROWS]

Pair trees by alternating calls with each tree on PYTHONPATH (benchmarks/RESULTS.md).
"""

import sys
import time

import yaml

from campar.sweep.job import Job
from campar.sweep.plan import plan_tiles
from campar.sweep.tile import run_tile

rows = int(sys.argv[1]) if len(sys.argv) > 1 else 20
with open("jobs/mu_cn.yaml") as fh:
    spec = yaml.safe_load(fh)
step = (0.95 - 0.70) / 399
spec["sweep"]["mu_cn"] = {"from": 0.95, "to": 0.95 - (rows - 1) * step, "points": rows}
spec.pop("store", None)
job = Job.from_dict(spec)
tiles = plan_tiles(job)
run_tile(job, tiles[0])  # compiled or loaded from the cache
start = time.process_time()
for tile in tiles:
    run_tile(job, tile)
print(f"{time.process_time() - start:.3f}")
