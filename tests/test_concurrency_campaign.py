"""The concurrency campaign: two ``campar run`` of the same job on one store at once (serial,
or both under ``mpirun -n 2``; Zarr and HDF5), with readers in a loop while they run.

The second run is refused in one line (exit 3, the store's lock named) or both finish; the
finished store equals, bit for bit, the map computed tile by tile in this process (no runner,
no store). While the runs write, every read holds: ``campar.open`` shows each tile whole as
in the finished store or not computed, and ``campar verify`` and ``campar status`` exit 0
(never damage, never a traceback). Snapshot reads of a single run are test_snapshot's; here
the readers face two writers. Counts on a line starting ``CONCURRENCY`` (``-s``).

    pytest tests/test_concurrency_campaign.py -m slow -s | grep CONCURRENCY
"""

import os
import time
import warnings

import numpy as np
import pytest
import yaml
from support.cli import call_campar
from support.jobs import SLOW, SMALL_JOB, assert_same_map, merge, reference_arrays
from support.processes import BACKENDS_AND_RANKS
from test_snapshot import COMPARED, start_run

import campar
from campar.errors import StoreError, StoreLocked
from campar.sweep.job import Job
from campar.sweep.plan import plan_tiles
from campar.sweep.store import read_store

# 10 chains of 12 cells, a tile each, 1500 revolutions a cell: a run of several seconds, so
# the second run starts while the first writes.
JOB = merge(merge(SMALL_JOB, SLOW), {"name": "two", "sweep": {"mu_cn": {"points": 10}}})


def read_once(store, final_tiles: dict, counts) -> None:
    """One round of the readers; every tile that ``campar.open`` calls done is kept to be
    compared with the finished store."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # a damage warning during the runs fails the test
            ds = campar.open(store)
    except (StoreError, FileNotFoundError):
        return  # not created yet
    try:
        done = ds["done"].values.astype(bool)
        for index, (start, stop) in enumerate(
            zip(ds.tile_row_start.values, ds.tile_row_stop.values, strict=True)
        ):
            part = {name: ds[name].values[int(start) : int(stop)] for name in COMPARED}
            if done[index]:
                final_tiles.setdefault(index, []).append(part)
            else:
                assert (part["kind"] == -1).all() and (part["label"] == "").all()
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
    counts = {"open": 0, "verify": 0, "status": 0}
    seen: dict[int, list] = {}
    first = start_run(job_file, ranks)
    second = None
    try:
        deadline = time.monotonic() + 600
        while first.poll() is None and time.monotonic() < deadline:
            if second is None and (store.exists() or first.poll() is not None):
                second = start_run(job_file, ranks)  # the first holds the store by now
            read_once(store, seen, counts)
        while second is not None and second.poll() is None and time.monotonic() < deadline:
            read_once(store, seen, counts)
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
    assert counts["open"] > 0, "no read while the runs wrote: the test exercised nothing"
    with capsys.disabled():
        outcome = "second refused in one line" if refused else "both finished"
        print(
            f"\nCONCURRENCY {suffix} on {ranks} rank(s): {outcome}; store equal to the serial "
            f"reference; reads during the runs: {counts['open']} campar.open "
            f"({compared} committed tiles compared), {counts['verify']} verify, "
            f"{counts['status']} status, 0 torn"
        )
