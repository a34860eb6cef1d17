"""The explorer reads a store through the store's snapshot read (``check_tiles`` on a
``read_store`` reader, as ``campar.open`` reads): during a run every tile it draws or
hovers is whole as the finished store holds it, or pending; a tile whose bytes change
after its first check is masked as damaged, never drawn or hovered from the changed
bytes; a tile whose commit flag is lost is damaged, as ``campar.open`` has it."""

import os
import shutil
import subprocess
import sys
import time
import warnings

import numpy as np
import pytest
import yaml
from support.jobs import EXPLORE_MAP, computed_store, plane_job

import campar
import campar.explore.source as source_module
from campar.explore.source import MapSource, stored_cell

JOB = {**EXPLORE_MAP, "name": "snapshot", "outputs": ["label", "dc"]}


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    return computed_store(tmp_path_factory, JOB)[0]


def drawn_labels(source: MapSource, width: int, height: int) -> np.ndarray:
    """The whole map's labels as drawn at width × height pixels ("" not computed), ω
    increasing left to right as the page draws it."""
    field = source.fields["label"]
    box = (*source.x_edges[[0, -1]], *source.y_edges[[0, -1]])
    values, inside = source.view(field, box, width, height)
    assert inside.all()
    names = source.categories["label"]
    return np.array([[names[v] if v >= 0 else "" for v in row] for row in values])


def flip_a_byte(chunk) -> None:
    data = bytearray(chunk.read_bytes())
    data[len(data) // 2] ^= 0xFF
    chunk.write_bytes(bytes(data))


def test_a_tile_changed_after_its_check_is_masked_not_read(store, tmp_path, monkeypatch):
    """The scan verified tile 1; its ``dc`` chunk changes on disk after: a view at full
    resolution and a hovered cell read it through the snapshot read, find it damaged and
    mask it (its cells drawn as not computed) — they never show the changed bytes."""
    monkeypatch.setattr(source_module, "MOSAIC_CELLS", 18)  # stride 2: close views read tiles
    path = tmp_path / "changed.zarr"
    shutil.copytree(store, path)
    source = MapSource(path)
    source.scan()
    assert source.stride == 2 and not source.damage
    (chunk,) = (path / "dc").glob("c.1.*")  # tile 1: rows 2 and 3
    flip_a_byte(chunk)
    assert source.cell(2, 5)["stored"] == "damaged"
    assert 1 in source.damage
    with pytest.warns(campar.errors.StoreDamageWarning):
        opened = campar.open(path)
    assert (opened.label.values[2:4] == "").all()  # campar.open: not computed either
    fine = drawn_labels(source, 24, 12)  # 2 pixels a cell: read from the tiles
    expected = opened.label.values[:, ::-1]
    assert (fine[::2, ::2] == expected).all() and (fine[1::2, 1::2] == expected).all()
    # the mosaic keeps rows 0, 2, 4 (pixel centres on rows 1, 3, 5): tile 1's row 2 masked too
    coarse = drawn_labels(source, 6, 3)
    assert (coarse == opened.label.values[0::2, 10::-2]).all() and (coarse[1] == "").all()


def test_a_hovered_cell_is_read_through_the_check(store, tmp_path):
    """A tile changed after the scan, not yet read at full resolution: the hovered cell
    is damaged, and the cell the page would compute from it is refused as damaged."""
    path = tmp_path / "hovered.zarr"
    shutil.copytree(store, path)
    source = MapSource(path)
    source.scan()
    (chunk,) = (path / "dc").glob("c.2.*")  # tile 2: rows 4 and 5
    flip_a_byte(chunk)
    cell = source.cell(4, 0)
    assert cell["stored"] == "damaged" and "dc" in cell["why"]
    with pytest.raises(campar.errors.StoreDamaged, match="tile 2"):
        stored_cell(path, 4, 0)
    assert source.cell(0, 0)["stored"] == "verified"  # the other tiles read on


def test_a_lost_commit_flag_is_damage_as_campar_open_has_it(store, tmp_path):
    """The root record holds tile 2 committed, its ``done`` flag reads 0: campar.open
    reports it damaged; the explorer's refresh, taking it in, does too (not pending)."""
    import zarr

    path = tmp_path / "lost.zarr"
    shutil.copytree(store, path)
    source = MapSource(path)
    source.scan()
    source.state[2] = source_module.PENDING  # as if the scan ran before tile 2's commit
    done = zarr.open_array(str(path / "done"), mode="r+")
    done[2] = 0
    with pytest.warns(campar.errors.StoreDamageWarning, match="tile 2"):
        campar.open(path)
    assert source.refresh() == 1
    assert 2 in source.damage and "commit flag lost" in source.damage[2]
    assert source.status()["verified"] == 2 and source.cell(4, 0)["stored"] == "damaged"


RUN_JOB = plane_job(
    "during",
    (6.0, 1.0, 16),
    ("mu_cn", 0.9, 0.6, 24),
    classify={"window_revolutions": 16},
    transient={"mode": "fixed", "max_revolutions": 300},  # commits come fast
    outputs=["label", "dc"],
    tiles={"rows": 1},
)


@pytest.mark.process
@pytest.mark.slow
@pytest.mark.parametrize("suffix", [".zarr", ".h5"])
def test_reads_during_a_run_are_whole_tiles_of_the_finished_store(tmp_path, monkeypatch, suffix):
    """A `campar run` child writes the store while the explorer refreshes, draws the map
    at full resolution and hovers cells: every tile it drew as committed is the finished
    store's, every hovered cell the finished store's or pending, and nothing is damaged."""
    monkeypatch.setattr(source_module, "MOSAIC_CELLS", 100)  # stride 2: views read tiles
    store = tmp_path / f"during{suffix}"
    job_file = tmp_path / "during.yaml"
    job_file.write_text(yaml.safe_dump({**RUN_JOB, "store": str(store)}, sort_keys=False))
    run = subprocess.Popen(
        [sys.executable, "-m", "campar.cli", "run", str(job_file)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    rng = np.random.default_rng(7)
    source, seen, hovered = None, [], []
    deadline = time.monotonic() + 600
    try:
        while run.poll() is None and time.monotonic() < deadline:
            if source is None:
                try:
                    source = MapSource(store)
                    source.scan()
                except (campar.errors.StoreError, FileNotFoundError):
                    source = None  # not created yet
                    time.sleep(0.05)
                    continue
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                source.refresh()
            verified = source.state == source_module.VERIFIED
            seen.append((verified.copy(), drawn_labels(source, 32, 48)[::2, ::2]))
            row, col = int(rng.integers(24)), int(rng.integers(16))
            hovered.append(source.cell(row, col))
    finally:
        if run.poll() is None:
            run.kill()
        _, err = run.communicate()
    assert run.returncode == 0, err
    assert source is not None and len(seen) > 2
    final = campar.open(store)
    assert final.done.values.all()
    labels = final.label.values[:, ::-1]  # as drawn: ω increasing
    kind = final.kind.values
    assert not source.damage
    partial = 0
    for verified, drawn in seen:
        rows = verified.nonzero()[0]  # one row a tile
        assert (drawn[rows] == labels[rows]).all()  # drawn whole as finished
        assert (drawn[~verified] == "").all()  # the rest drawn as not computed
        partial += 0 < verified.sum() < verified.size
    assert partial > 0  # some reads fell while the run was under way
    stored = [c for c in hovered if c["stored"] == "verified"]
    assert stored and all(c["stored"] in ("verified", "pending") for c in hovered)
    for cell in stored:
        at = cell["row"], cell["col"]
        assert cell["arrays"]["kind"] == kind[at]
        assert np.array_equal(cell["arrays"]["dc"], final.dc.values[at], equal_nan=True)
    source.refresh()  # the run's last tiles
    assert (drawn_labels(source, 32, 48)[::2, ::2] == labels).all()
