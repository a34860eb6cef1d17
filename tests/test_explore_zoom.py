"""A small zoom runs in the process the explorer keeps warm for zooms (the serial runner,
the map's kernel loaded): its store is the one `campar run` of the zoom's job file
writes, bit for bit; a larger zoom, or one asked while the warm process is busy, runs in
a process of its own; the server's stop ends a warm zoom at a tile's end, resumable.
The zoom run in a process of its own: test_explore."""

import json
import time

import numpy as np
import pytest
import yaml
from support.http import get
from support.jobs import EXPLORE_MAP, computed_store

import campar
from campar.cli import main
from campar.explore.server import serve, shutdown
from campar.explore.zoom import WarmRun

JOB = {**EXPLORE_MAP, "name": "warm"}


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    return computed_store(tmp_path_factory, JOB)[0]


def warm_server(store):
    server = serve([store], warm_up=False)
    server.explorer.start_zoom_runner()
    deadline = time.monotonic() + 600  # a cold numba cache compiles the kernel first
    while not server.explorer.zoom_runner.free():
        assert time.monotonic() < deadline, "the warm zoom runner did not start"
        time.sleep(0.05)
    return server


def zoom(server, points: int) -> dict:
    query = f"/api/zoom?store=0&x0=2&x1=4&y0=0.65&y1=0.85&points={points}"
    status, body = get(server, query, method="POST")
    assert status == 200, body
    return json.loads(body)


def finished(server, index: int, seconds: float = 600) -> None:
    source = server.explorer.sources[index]
    deadline = time.monotonic() + seconds
    while source.status()["verified"] < len(source.tiles):
        assert time.monotonic() < deadline
        time.sleep(0.05)


@pytest.mark.process
@pytest.mark.timeout(900)  # a cold numba cache: the warm process compiles the kernel
def test_a_small_zoom_runs_warm_and_writes_what_campar_run_writes(store, tmp_path):
    server = warm_server(store)
    try:
        answer = zoom(server, 6)
        path = server.explorer.sources[answer["store"]].path
        run = server.explorer._zooms[path]
        assert isinstance(run, WarmRun)
        finished(server, answer["store"])
        assert run.wait(60) == 0
        assert server.explorer.zoom_runner.free()  # ready for the next zoom
        # a zoom asked while it is busy runs in a process of its own
        server.explorer.zoom_runner.free = lambda: False
        server.explorer.zoom_ranks = 1  # its own process, serial (no mpirun here)
        other = zoom(server, 5)
        busy = server.explorer._zooms[server.explorer.sources[other["store"]].path]
        assert not isinstance(busy, WarmRun)
        finished(server, other["store"])
    finally:
        shutdown(server)
    job = yaml.safe_load(path.with_suffix(".yaml").read_text())
    reference = tmp_path / "reference.zarr"
    campar.run({**job, "store": str(reference)})  # the serial runner, in this process
    ours, theirs = campar.open(path), campar.open(reference)
    assert ours.sizes == theirs.sizes and ours.sizes["omega"] == 6
    for name in ("kind", "n", "p", "status", "dc", "eps_max", "state", "multipliers"):
        assert np.array_equal(ours[name].values, theirs[name].values, equal_nan=True), name
    assert "complete" in path.with_suffix(".log").read_text()


@pytest.mark.process
@pytest.mark.timeout(900)
def test_the_servers_stop_ends_a_warm_zoom_resumably(store):
    """Stopped while its 10,000 cells compute (about 1.5 CPU s), the warm zoom's store
    keeps its committed tiles, and `campar run` of its job file completes it."""
    server = warm_server(store)
    try:
        answer = zoom(server, 100)
        path = server.explorer.sources[answer["store"]].path
        assert isinstance(server.explorer._zooms[path], WarmRun)
        time.sleep(0.2)
    finally:
        shutdown(server)
    assert not campar.committed(path).all()  # stopped before its end
    job_file = path.with_suffix(".yaml")
    assert main(["run", str(job_file)]) == 0
    assert campar.committed(path).all()
