"""The concurrency campaign: two ``campar run`` of the same job on one store at once (serial,
or both under ``mpirun -n 2``; Zarr and HDF5), with readers in a loop while they run.

The second run is refused in one line (exit 3, the store's lock named) or both finish; the
finished store equals, bit for bit, the map computed tile by tile in this process (no runner,
no store). While the runs write, every read is a snapshot: ``campar.open`` shows each tile
whole as it is committed in the finished store, or not computed (never part of it, never a
damage warning), ``campar.committed`` follows the run, and ``campar verify`` and ``campar
status`` exit 0 (never damage, never a traceback). The job has 40 short tiles, so that
commits come fast and reads meet them. Counts on a line starting ``CONCURRENCY`` (``-s``).

    pytest tests/test_concurrency_campaign.py -m slow -s | grep CONCURRENCY
"""

import os
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml
from support.cli import call_campar
from support.jobs import SMALL_JOB, assert_same_map, merge, reference_arrays
from support.processes import BACKENDS_AND_RANKS, MPIRUN

import campar
from campar.errors import StoreError, StoreLocked
from campar.sweep.job import Job
from campar.sweep.plan import plan_tiles
from campar.sweep.store import read_store

# 40 tiles of 12 cells, 300 revolutions a cell: commits come fast, and the run lasts the
# seconds the second run takes to start.
JOB = merge(
    SMALL_JOB,
    {
        "name": "two",
        "sweep": {"mu_cn": {"points": 40}},
        "transient": {"mode": "fixed", "max_revolutions": 300},
    },
)
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


def read_once(store: Path, n_tiles: int, seen: dict, counts: dict) -> None:
    """One round of the readers; every tile that ``campar.open`` calls done is kept in
    ``seen`` to be compared with the finished store."""
    try:
        now = campar.committed(store)
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # a damage warning during the runs fails the test
            ds = campar.open(store)
    except (StoreError, FileNotFoundError):
        time.sleep(0.05)
        return  # not created yet
    try:
        done = ds["done"].values.astype(bool)
        assert done.shape == now.shape == (n_tiles,)
        counts["partial"] += 0 < done.sum() < n_tiles
        for index, (start, stop) in enumerate(
            zip(ds.tile_row_start.values, ds.tile_row_stop.values, strict=True)
        ):
            part = {name: ds[name].values[int(start) : int(stop)] for name in COMPARED}
            if done[index]:
                seen.setdefault(index, []).append(part)
            else:  # pending in the snapshot: nothing of it shows
                assert (part["kind"] == -1).all() and (part["label"] == "").all()
                assert np.isnan(part["dc"]).all()
        counts["open"] += 1
    finally:
        ds.close()
    for command in ("verify", "status"):
        said = call_campar(None, command, store)
        lines = [line for line in said.stderr.splitlines() if line.strip()]
        assert said.returncode == 0 and not lines, (command, said.returncode, said.stderr)
        counts[command] += 1


@pytest.mark.process
@pytest.mark.slow
@pytest.mark.timeout(900)  # two runs of the same job on a loaded machine
@pytest.mark.parametrize("suffix, ranks", BACKENDS_AND_RANKS)
def test_two_writers_of_one_store_never_corrupt_it(tmp_path, suffix, ranks, capsys):
    store = tmp_path / f"two{suffix}"
    job_file = tmp_path / "two.yaml"
    job_file.write_text(yaml.safe_dump({**JOB, "store": str(store)}, sort_keys=False))
    job = Job.from_dict({**JOB, "store": str(store)})
    n_tiles = len(plan_tiles(job))
    reference_arrays(job)  # before the runs: the machine is theirs while they write
    counts = {"open": 0, "partial": 0, "verify": 0, "status": 0}
    seen: dict[int, list] = {}
    first = start_run(job_file, ranks)
    second = None
    try:
        deadline = time.monotonic() + 600
        while first.poll() is None and time.monotonic() < deadline:
            if second is None and (store.exists() or first.poll() is not None):
                second = start_run(job_file, ranks)  # the first holds the store by now
            read_once(store, n_tiles, seen, counts)
        while second is not None and second.poll() is None and time.monotonic() < deadline:
            read_once(store, n_tiles, seen, counts)
        codes = [first.wait(timeout=60), second.wait(timeout=60) if second else None]
        errors = [first.stderr.read(), second.stderr.read() if second else ""]
    finally:
        for proc in (first, second):
            if proc is not None and proc.poll() is None:
                os.killpg(proc.pid, 9)
    assert codes[0] == 0, errors[0]
    refused = codes[1] == StoreLocked.exit_code
    if refused:
        lines = [line for line in errors[1].splitlines() if line.strip()]
        # one line a rank that reports it: rank 0 only, under mpirun too
        assert len(lines) == 1 and ("in use by" in lines[0] or "lock" in lines[0]), lines
    else:
        assert codes[1] == 0, errors[1]
    with read_store(store) as reader:
        assert_same_map(reader, job)
    final = campar.open(store)
    assert final["done"].values.all()
    compared = 0
    for index, parts in seen.items():
        start, stop = int(final.tile_row_start[index]), int(final.tile_row_stop[index])
        for part in parts:
            for name, values in part.items():
                expected = final[name].values[start:stop]
                assert np.array_equal(values, expected, equal_nan=values.dtype.kind == "f"), (
                    f"tile {index}, {name}"
                )
            compared += 1
    assert (campar.committed(store) == np.ones(n_tiles, bool)).all()
    assert counts["partial"] > 0, "no read saw the runs half way: the test exercised nothing"
    with capsys.disabled():
        outcome = "second refused in one line" if refused else "both finished"
        print(
            f"\nCONCURRENCY {suffix} on {ranks} rank(s): {outcome}; store equal to the serial "
            f"reference; reads during the runs: {counts['open']} campar.open "
            f"({counts['partial']} of a partial map, {compared} committed tiles compared), "
            f"{counts['verify']} verify, {counts['status']} status, 0 torn"
        )
