"""The explorer sees what a run does to its store while it serves it, without a restart: a
tile pending at the first read is shown once committed and verified (Zarr and HDF5); a tile
masked as damaged is looked at again once the store's commits change — a run that repairs
it makes it pending, computes it again and commits it, and it is shown once it verifies,
even when all that happens between two looks; its cells leave the legend's counts while
masked; and a look at the store that fails is said once and tried again.

Every map is checked against ``campar.open`` of the store as it is then (an independent
reader), and the repaired map against the store computed without damage."""

import shutil
import threading
import time
from collections import Counter

import numpy as np
import pytest
from support.jobs import computed_store, plane_job

import campar
import campar.explore.source as source_module
from campar.errors import StoreDamageWarning, StoreIOError
from campar.explore.server import Explorer
from campar.explore.source import MapSource
from campar.sweep.job import Job
from campar.sweep.plan import plan_tiles
from campar.sweep.runner import run_job
from campar.sweep.store import open_store, read_store
from campar.views.plot.labels import NOT_COMPUTED

# 4 rows × 8 cells, one row a tile: tile i is row i; labels 1-1, 1-2, 2-1, 2-2 and chaos
# (no chattering cell: the page names those by the palette's classes, campar.open by p).
JOB = plane_job(
    "refresh",
    (4.5, 1.5, 8),
    ("mu_cn", 0.9, 0.6, 4),
    classify={"window_revolutions": 16},
    outputs=["label", "dc"],
    tiles={"rows": 1},
)


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    """The map computed without damage, and its tiles' arrays as stored."""
    path, job = computed_store(tmp_path_factory, JOB)
    with read_store(path) as reader:
        tiles = [{n: reader.read_tile(n, t) for n in reader.names} for t in plan_tiles(job)]
    return path, job, tiles


def drawn(source: MapSource) -> np.ndarray:
    """The whole map's labels as the page draws them, one pixel a cell ("" not computed),
    in the store's order (ω as stored)."""
    field = source.fields["label"]
    box = (*source.x_edges[[0, -1]], *source.y_edges[[0, -1]])
    values, inside = source.view(field, box, source.cols, source.rows)
    assert inside.all()
    names = source.categories["label"]
    return np.array([[names[v] if v >= 0 else "" for v in row] for row in values])[:, ::-1]


def legend(source: MapSource) -> dict:
    return {name: count for name, count in source.legend(source.fields["label"]) if count}


def opened_labels(path) -> np.ndarray:
    """The labels ``campar.open`` reads ("" where not computed or damaged)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StoreDamageWarning)
        return campar.open(path).label.values


def counted(labels: np.ndarray) -> dict:
    counts = Counter(str(x) for x in labels.ravel() if x)
    missing = int((labels == "").sum())
    return {**counts, **({NOT_COMPUTED: missing} if missing else {})}


def with_tiles(pristine, path, indices):
    """A store at ``path`` of the job with the pristine tiles ``indices`` committed."""
    _, job, tiles = pristine
    job = Job.from_dict({**job.to_dict(), "store": str(path)})
    with open_store(path, job) as store:
        for index in indices:
            store.write_tile(plan_tiles(job)[index], tiles[index])
    return job


@pytest.mark.parametrize("suffix", [".zarr", ".h5"])
def test_a_tile_pending_at_the_first_read_is_shown_once_committed(pristine, tmp_path, suffix):
    path = tmp_path / f"running{suffix}"
    job = with_tiles(pristine, path, [0, 1])
    source = MapSource(path)
    source.scan()
    assert source.status()["verified"] == 2 and (drawn(source)[2:] == "").all()
    assert source.refresh() == 0  # nothing new
    with_tiles(pristine, path, [2])  # the run goes on
    assert source.refresh() == 1
    assert (drawn(source) == opened_labels(path)).all() and (drawn(source)[3] == "").all()
    assert legend(source) == counted(opened_labels(path))
    with_tiles(pristine, path, [3])
    assert source.refresh() == 1
    assert (drawn(source) == opened_labels(pristine[0])).all()
    assert source.status() == {
        "tiles": len(plan_tiles(job)),
        "verified": len(plan_tiles(job)),
        "damaged": {},
        "scanned": True,
        "problem": None,
    }


def test_a_masked_tile_is_shown_again_once_a_run_repairs_it(pristine, tmp_path):
    """Tile 1's ``dc`` chunk is damaged before the first read: masked. A run then repairs
    the store (tile 1 pending again) and computes the tile again — all of it between two
    looks, which see the same tiles committed before and after — and the next look shows
    it: the map is the undamaged one, the legend counts every cell."""
    path = tmp_path / "repaired.zarr"
    shutil.copytree(pristine[0], path)
    (chunk,) = (path / "dc").glob("c.1.*")
    data = bytearray(chunk.read_bytes())
    data[len(data) // 2] ^= 0xFF
    chunk.write_bytes(bytes(data))
    source = MapSource(path)
    source.scan()
    assert set(source.damage) == {1}
    assert (drawn(source) == opened_labels(path)).all() and (drawn(source)[1] == "").all()
    assert legend(source) == counted(opened_labels(path))
    assert source.refresh() == 0  # the store has not changed: the tile is not read again
    with read_store(path) as reader:
        committed = reader.committed_tiles()
    run_job(pristine[1], path)  # repairs tile 1 and computes it again
    with read_store(path) as reader:
        assert (reader.committed_tiles() == committed).all()  # only the mark tells
    assert source.refresh() == 1
    assert not source.damage and source.status()["verified"] == 4
    expected = opened_labels(pristine[0])
    assert (drawn(source) == expected).all()
    assert legend(source) == counted(expected)
    assert source.cell(1, 3)["stored"] == "verified"


def test_a_tile_a_repair_makes_pending_is_pending_not_damaged(pristine, tmp_path):
    """The look falls between the repair and the tile's new commit: the tile is pending
    (not computed), no longer damaged; the commit after it is then shown."""
    path = tmp_path / "pending.zarr"
    shutil.copytree(pristine[0], path)
    for chunk in (path / "dc").glob("c.2.*"):
        chunk.unlink()  # tile 2's dc chunk lost
    source = MapSource(path)
    source.scan()
    assert set(source.damage) == {2}
    job = Job.from_dict({**pristine[1].to_dict(), "store": str(path)})
    with open_store(path, job) as store:  # the resume's repair: tile 2 pending again
        assert not store.done[2]
    assert source.refresh() == 1
    assert not source.damage and source.state[2] == source_module.PENDING
    assert source.cell(2, 0)["stored"] == "pending"
    with_tiles(pristine, path, [2])
    assert source.refresh() == 1
    assert (drawn(source) == opened_labels(pristine[0])).all()


def test_a_tile_masked_on_a_later_read_leaves_the_legend(pristine, tmp_path, monkeypatch):
    """A tile verified by the scan whose bytes change afterwards is masked when a close
    view reads it: its cells leave the legend's counts, as campar.open drops them."""
    monkeypatch.setattr(source_module, "MOSAIC_CELLS", 8)  # stride 2: close views read tiles
    path = tmp_path / "changed.zarr"
    shutil.copytree(pristine[0], path)
    source = MapSource(path)
    source.scan()
    assert source.stride == 2 and legend(source) == counted(opened_labels(path))
    (chunk,) = (path / "kind").glob("c.3.*")  # an array the labels are drawn from
    chunk.write_bytes(chunk.read_bytes()[:-3] + b"xyz")
    drawn(source)  # a close view: reads the tiles, finds tile 3 changed
    assert set(source.damage) == {3}
    assert legend(source) == counted(opened_labels(path))


def test_a_failed_look_is_said_once_and_tried_again(pristine, tmp_path, caplog):
    path = tmp_path / "flaky.zarr"
    with_tiles(pristine, path, [0])
    explorer = Explorer([path])
    source = explorer.sources[0]
    looks, said = [], []
    refresh = source.refresh

    def flaky():
        looks.append(time.monotonic())
        if len(looks) == 2:
            said.append(source.status()["problem"])
        if len(looks) <= 2:
            raise StoreIOError(f"cannot read the store {path}: Too many open files")
        return refresh()

    source.refresh = flaky
    watcher = threading.Thread(target=explorer._watch, args=(source, 0.01), daemon=True)
    watcher.start()
    try:
        deadline = time.monotonic() + 60
        while not source.scanned and time.monotonic() < deadline:
            time.sleep(0.01)
        with_tiles(pristine, path, [1, 2, 3])
        while source.status()["verified"] < 4 and time.monotonic() < deadline:
            time.sleep(0.01)
    finally:
        explorer._stop.set()
        watcher.join(10)
    assert not watcher.is_alive()
    assert source.status()["verified"] == 4 and source.status()["problem"] is None
    assert len(looks) >= 3 and "Too many open files" in said[0]
    warned = [r for r in caplog.records if "watching" in r.getMessage()]
    assert len(warned) == 1
    assert (drawn(source) == opened_labels(pristine[0])).all()
