"""Snapshot reads: ``campar.open`` on a store a run is writing gives each tile whole as it is
committed in the finished store, or not computed; ``campar.committed`` follows the run.

Each test starts one run (serial, or ``mpirun -n 2``; Zarr or HDF5) of a job of 40 short
tiles, reads the store in a loop until the run ends, keeps every tile each read held as
committed, and compares them with the finished store."""

import os
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml
from support.processes import BACKENDS_AND_RANKS, MPIRUN

import campar
from campar.errors import StoreError
from campar.sweep.plan import plan_tiles

JOB = {
    "name": "snapshot",
    "sweep": {
        "omega": {"from": 6.0, "to": 1.0, "points": 24},
        "mu_cn": {"from": 0.9, "to": 0.6, "points": 40},
    },
    "classify": {"window_revolutions": 16},
    "transient": {"mode": "fixed", "max_revolutions": 300},  # commits come fast
    "tiles": {"rows": 1},
}
COMPARED = ("kind", "status", "n", "p", "dc", "label")  # codes, a float, and the derived text


def start_run(job_file: Path, ranks: int) -> subprocess.Popen:
    launcher = [str(MPIRUN), "-n", str(ranks)] if ranks > 1 else []
    return subprocess.Popen(
        [*launcher, sys.executable, "-m", "campar.cli", "run", str(job_file)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
        start_new_session=True,
    )


def read_during(proc: subprocess.Popen, store: Path, n_tiles: int, timeout: float = 600.0):
    """campar.open in a loop while ``proc`` runs: [(done per tile, {tile: {name: values}})]."""
    reads, rows = [], None
    deadline = time.monotonic() + timeout
    while proc.poll() is None and time.monotonic() < deadline:
        try:
            now = campar.committed(store)
            with warnings.catch_warnings():
                warnings.simplefilter("error")  # a damage warning during a run fails the test
                ds = campar.open(store)
        except (StoreError, FileNotFoundError):
            time.sleep(0.05)  # not created yet
            continue
        done = ds["done"].values.astype(bool)
        assert done.shape == now.shape == (n_tiles,)
        starts, stops = ds.tile_row_start.values, ds.tile_row_stop.values
        rows = rows or [(int(a), int(b)) for a, b in zip(starts, stops, strict=True)]
        tiles = {}
        for index, (start, stop) in enumerate(rows):
            part = {name: ds[name].values[start:stop] for name in COMPARED}
            if done[index]:
                tiles[index] = part
            else:  # pending in the snapshot: nothing of it shows
                assert (part["kind"] == -1).all() and (part["label"] == "").all()
                assert np.isnan(part["dc"]).all()
        reads.append((done, tiles))
        ds.close()
    return reads


@pytest.mark.process
@pytest.mark.slow
@pytest.mark.parametrize("suffix, ranks", BACKENDS_AND_RANKS)
def test_reads_during_a_run_are_snapshots_of_the_finished_store(tmp_path, suffix, ranks):
    store = tmp_path / f"snapshot{suffix}"
    job_file = tmp_path / "snapshot.yaml"
    job_file.write_text(yaml.safe_dump({**JOB, "store": str(store)}, sort_keys=False))
    n_tiles = len(plan_tiles(campar.load_job(job_file)))
    proc = start_run(job_file, ranks)
    try:
        reads = read_during(proc, store, n_tiles)
        assert proc.wait(timeout=600) == 0, proc.stderr.read()
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, 9)
    final = campar.open(store)
    assert final["done"].values.all()
    partial = [done for done, _ in reads if 0 < done.sum() < n_tiles]
    compared = 0
    for _, tiles in reads:
        for index, part in tiles.items():
            start, stop = int(final.tile_row_start[index]), int(final.tile_row_stop[index])
            for name, values in part.items():
                expected = final[name].values[start:stop]
                assert np.array_equal(values, expected, equal_nan=values.dtype.kind == "f"), (
                    f"tile {index}, {name}"
                )
            compared += 1
    print(
        f"{suffix} on {ranks} rank(s): {len(reads)} reads during the run, {len(partial)} of a "
        f"partial map, {compared} committed tiles compared with the finished store"
    )
    assert partial, "no read saw the run half way: the test exercised nothing"
    assert (campar.committed(store) == final["done"].values.astype(bool)).all()
