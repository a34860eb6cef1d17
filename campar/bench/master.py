"""``campar bench master``: how many tiles a second the master (rank 0) can take.

The real runner (``campar.sweep.runner``: master, workers, wire protocol, store
writes) runs under ``mpirun -n R`` with the kernel replaced by a stand-in that
sleeps for a realistic tile time and returns arrays of the job's layout, filled
with random numbers (incompressible: the worst case for the store's codecs).
Sleeping ranks cost no core, so R may far exceed the cores (oversubscribed: a
capacity test of the master, not of the kernel). Reported per R:

- tiles/s the run sustained, against the ideal R / tile time;
- idle: the share of the lanes' time not spent in the stand-in tile;
- latency from a tile's end on its rank to its arrays on disk (median, p95),
  and the store write itself (median): the stand-in stamps its end time
  (``CLOCK_MONOTONIC``, shared by the processes of one host) into the tile;
- the master's CPU time per tile (rank 0's process: its own compute lane only
  sleeps), and its inverse, the tiles/s one core can write — the capacity that
  oversubscription on a small machine hides behind the ranks' own polling;
- the CPU of every rank per tile (the stand-in's random arrays, the workers' writes
  and polls, the master): what a tile costs the machine beside its kernel — on an
  oversubscribed machine, what bounds the tiles/s;
- each for both writers (``--writer``): the workers writing their own tiles' chunks
  and the master committing them in groups, or the master writing every tile
  (``CAMPAR_WRITER=master``, and always for HDF5); "write ms" is the master's share
  per tile (the write, or the commit);
- peak RSS of rank 0 and of the largest worker (without numba: the stand-in
  replaces the kernel's module, so add the compiled kernel's memory for a real run).

Memory of a 4000 × 4000 map: ``--rows 4000 --omegas 4000`` (the store size is
printed; random data makes it an upper bound).

    campar bench master                               # R = 16, 64, 128; 400 × 400
    campar bench master --ranks 256 --tile-seconds 1.5 --rows 4000 --omegas 4000
"""

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
import types
from pathlib import Path

import numpy as np
import yaml

from .common import format_table, machine_line

MPIRUN = Path(sys.executable).parent / "mpirun"
QUICK = {"ranks": [4], "rows": 40, "omegas": 40, "tile_seconds": 0.05}


def stand_in_tile(seconds: float):
    """A replacement for ``run_tile``: sleeps ``seconds``, returns random arrays of the
    job's layout, with its end time (ns, CLOCK_MONOTONIC) in ``steps[0, 0]``."""
    from campar.sweep.store import cell_arrays

    def run_tile(job, tile):
        rng = np.random.default_rng(tile.index)
        time.sleep(seconds)
        arrays = {}
        for schema in cell_arrays(job):
            shape = (tile.n_rows, *schema.shape[1:])
            if schema.dtype.kind == "f":
                arrays[schema.name] = rng.random(shape).astype(schema.dtype)
            else:
                arrays[schema.name] = rng.integers(0, 8, shape).astype(schema.dtype)
        arrays["steps"][0, 0] = time.monotonic_ns()
        return arrays

    return run_tile


def serve(job_path: str, store: str, seconds: float, report: str) -> None:
    """One rank of the capacity run (called under mpirun): the real runner, stand-in kernel."""
    # The stand-in takes the kernel's module's place before the runner imports it, so a
    # rank loads neither numba nor LLVM: hundreds of ranks fit in a small machine's memory.
    kernel_free = types.ModuleType("campar.sweep.tile")
    kernel_free.run_tile = stand_in_tile(seconds)
    kernel_free.load_kernel = lambda job, share: None  # a worker's lane preloads the kernel
    kernel_free.compile_kernel = lambda job, share: None  # rank 0 compiles before its store opens
    kernel_free.located_cache_dir = lambda: "no cache"  # where the ranks of a node compile
    sys.modules["campar.sweep.tile"] = kernel_free
    from campar.sweep import runner
    from campar.sweep.job import load_job

    committed, writes = {}, []
    save = runner.Master.save

    def timed_save(self, outcomes):  # the writes (of tiles their workers wrote: the commit)
        if not outcomes:
            return save(self, outcomes)
        start = time.monotonic_ns()
        save(self, outcomes)
        end = time.monotonic_ns()
        committed.update((out.index, end) for out in outcomes)
        writes.extend([(end - start) / 1e9 / len(outcomes)] * len(outcomes))

    runner.Master.save = timed_save
    job = load_job(job_path)
    summary = runner.run_job(job, store, overwrite=True)
    if summary.outcome != "worker":
        # each tile's end on its rank, stamped by the stand-in into the store (whoever wrote)
        from campar.sweep.plan import plan_tiles
        from campar.sweep.store import read_store

        with read_store(store) as reader:
            steps = reader.read("steps")
        tiles = plan_tiles(job)
        latency = [(end - int(steps[tiles[i].row_start, 0])) / 1e9 for i, end in committed.items()]
        Path(report).write_text(
            json.dumps({"entry": summary.entry, "latency": latency, "write": writes})
        )


def write_job(directory: Path, rows: int, omegas: int, tile_rows: int) -> Path:
    data = {
        "name": f"master_{rows}x{omegas}",
        "sweep": {
            "omega": {"from": 6.0, "to": 0.02, "points": omegas},
            "mu_cn": {"from": 0.95, "to": 0.70, "points": rows},
        },
        "tiles": {"rows": tile_rows},
    }
    path = directory / "job.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def launch(job: Path, store: Path, ranks: int, seconds: float, writer: str) -> dict:
    report = store.with_suffix(".json")
    code = (
        "import sys; from campar.bench.master import serve; serve(*sys.argv[1:3], "
        "float(sys.argv[3]), sys.argv[4])"
    )
    command = [
        str(MPIRUN),
        "-n",
        str(ranks),
        sys.executable,
        "-c",
        code,
        str(job),
        str(store),
        str(seconds),
        str(report),
    ]
    env = {**os.environ, "CAMPAR_WRITER": writer}  # workers: each its own tiles (Zarr only)
    done = subprocess.run(command, capture_output=True, text=True, env=env)
    if done.returncode != 0:
        raise RuntimeError(f"mpirun -n {ranks} failed ({done.returncode}):\n{done.stderr[-2000:]}")
    return json.loads(report.read_text())


def store_bytes(path: Path) -> int:
    if path.is_file():
        return path.stat().st_size
    return sum(f.stat().st_size for f in path.rglob("*") if f.is_file())


def run(args) -> int:
    if args.quick:
        for key, value in QUICK.items():
            setattr(args, key, value)
    print(machine_line())
    rows = []
    with tempfile.TemporaryDirectory(prefix="campar-bench-master-", dir=args.tmp) as tmp:
        tmp = Path(tmp)
        job = write_job(tmp, args.rows, args.omegas, args.tile_rows)
        n_tiles = -(-args.rows // args.tile_rows)
        for ranks, writer in ((r, w) for r in args.ranks for w in args.writer):
            store = tmp / f"r{ranks}{writer}{args.suffix}"
            result = launch(job, store, ranks, args.tile_seconds, writer)
            entry, latency = result["entry"], sorted(result["latency"])
            ideal = min(ranks / args.tile_seconds, n_tiles / args.tile_seconds)
            sustained = entry["tiles"] / entry["seconds"]
            idle = 1 - entry["compute_seconds"] / (entry["seconds"] * ranks)
            rss = [mb for mb in entry["peak_rss_mb"] if mb is not None]
            master_cpu = entry["cpu_seconds"][0] / entry["tiles"]  # its compute lane sleeps
            all_cpu = sum(c for c in entry["cpu_seconds"] if c is not None) / entry["tiles"]
            rows.append(
                [
                    f"{ranks}",
                    entry.get("writer", writer),
                    f"{sustained:.1f}",
                    f"{ideal:.1f}",
                    f"{100 * idle:.1f} %",
                    f"{1e3 * statistics.median(latency):.1f}",
                    f"{1e3 * latency[int(0.95 * (len(latency) - 1))]:.1f}",
                    f"{1e3 * statistics.median(result['write']):.2f}",
                    f"{1e3 * master_cpu:.1f}",
                    f"{1 / master_cpu:.0f}",
                    f"{1e3 * all_cpu:.1f}",
                    f"{rss[0]:.0f} / {max(rss[1:], default=0):.0f}",
                    f"{store_bytes(store) / 2**20:.1f}",
                ]
            )
            if not args.keep_stores:
                subprocess.run(["rm", "-rf", str(store)], check=False)
    print(
        f"\n{args.rows} × {args.omegas} cells, {args.tile_rows} chains a tile ({n_tiles} tiles), "
        f"stand-in tile {args.tile_seconds:g} s, {args.suffix} store, {os.cpu_count()} cores "
        "(ranks beyond them oversubscribed: they sleep)\n"
    )
    print(
        format_table(
            [
                "ranks",
                "writer",
                "tiles/s",
                "ideal",
                "idle",
                "result→disk ms (median)",
                "p95 ms",
                "write ms",
                "master CPU ms/tile",
                "capacity tiles/s",
                "all ranks CPU ms/tile",
                "RSS MB rank 0 / worker max",
                "store MiB",
            ],
            rows,
        )
    )
    return 0
