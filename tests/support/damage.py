"""Helpers of the integrity and fault-injection tests: stores of synthetic tiles, damage done
to them on disk, and small filesystems that fill up."""

import contextlib
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from test_store import fake_tile, make_job

from campar.sweep.job import Job
from campar.sweep.plan import plan_tiles
from campar.sweep.store import open_store, read_store, verify_store

DAMAGE = ("delete", "truncate", "flip", "zero")


def synthetic_store(path: Path, job: Job | None = None, tiles=None) -> Job:
    """A store whose tiles ``tiles`` (default: all) hold ``fake_tile(job, tile, index)``."""
    job = job or make_job()
    with open_store(path, job) as store:
        for tile in plan_tiles(job):
            if tiles is None or tile.index in tiles:
                store.write_tile(tile, fake_tile(job, tile, tile.index))
    return job


def assert_synthetic(path: Path, job: Job) -> None:
    """Every tile is committed, verifies, and holds exactly ``fake_tile``'s numbers."""
    with read_store(path) as reader:
        report = verify_store(reader)
        assert report.clean and report.verified.all(), report.lines()
        for tile in plan_tiles(job):
            expected = fake_tile(job, tile, tile.index)
            for name in reader.names:
                assert np.array_equal(reader.read_rows(name, tile.rows), expected[name]), name


def finish(path: Path, job: Job) -> list[int]:
    """Resume: write every pending tile again; returns the tiles that were pending."""
    with open_store(path, job) as store:
        pending = [t for t in plan_tiles(job) if not store.done[t.index]]
        for tile in pending:
            store.write_tile(tile, fake_tile(job, tile, tile.index))
    return [t.index for t in pending]


def zarr_chunks(path: Path, job: Job, index: int) -> list[Path]:
    """The chunk files of tile ``index`` in a Zarr store: its cell arrays', checksum, done."""
    path = Path(path)
    with read_store(path) as reader:
        names = [*reader.names, "checksum", "done"]
    found = []
    for name in names:
        folder = path / name  # chunk files c.<tile> (per-tile arrays), c.<tile>.<j>…
        found += sorted(folder.glob(f"c.{index}")) + sorted(folder.glob(f"c.{index}.*"))
    return found


def damage_file(
    target: Path, how: str, rng: np.random.Generator, at: int | None = None
) -> str | None:
    """Damage one file as a failing disk or a careless hand would, at byte ``at`` (default:
    drawn at random); returns what was done (None if the bytes happened not to change)."""
    size = target.stat().st_size
    if how == "delete":
        target.unlink()
    elif how == "truncate":
        if size == 0:
            return None
        with open(target, "r+b") as fh:
            fh.truncate(int(rng.integers(0, size)) if at is None else at)
    elif how == "flip":
        offset = int(rng.integers(0, max(size, 1))) if at is None else at
        bit = int(rng.integers(0, 8))
        with open(target, "r+b") as fh:
            fh.seek(offset)
            byte = fh.read(1) or b"\0"
            fh.seek(offset)
            fh.write(bytes([byte[0] ^ (1 << bit)]))
    elif how == "zero":
        offset = int(rng.integers(0, max(size, 1))) if at is None else at
        with open(target, "r+b") as fh:
            fh.seek(offset)
            if not fh.read(4096).strip(b"\0"):
                return None  # zeros over zeros: nothing changed
            fh.seek(offset)
            fh.write(bytes(min(4096, size - offset)))
    else:
        raise ValueError(how)
    return f"{how} {target.name}"


def running_as_root() -> bool:
    return os.geteuid() == 0


@contextlib.contextmanager
def small_disk(folder: Path, kilobytes: int):
    """A tmpfs of ``kilobytes`` at ``folder`` (root only; the test is skipped otherwise).
    Yields a function that resizes it (to free space, as a user would)."""
    if not running_as_root():
        pytest.skip("a full disk is simulated with a small tmpfs, which needs root")
    folder.mkdir(parents=True, exist_ok=True)
    mount = ["mount", "-t", "tmpfs", "-o", f"size={kilobytes}k", "tmpfs", str(folder)]
    done = subprocess.run(mount, capture_output=True, text=True)
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({done.stderr.strip()})")

    def resize(new_kilobytes: int) -> None:
        options = f"remount,size={new_kilobytes}k"
        subprocess.run(["mount", "-o", options, str(folder)], check=True)

    try:
        yield resize
    finally:
        subprocess.run(["umount", "-l", str(folder)], capture_output=True)


def leftovers(folder: Path) -> list[str]:
    """Temporary files a writer must never leave behind."""
    marks = (".tmp", ".partial", ".creating-", ".checkpoint-", ".deleting-", ".lock")
    return sorted(str(p) for p in folder.rglob("*") if any(m in p.name for m in marks))


def plausible_tile(job: Job, tile, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Random arrays of a tile with valid codes (kinds, status 0, small n and p): a store of
    these reads like a computed map, for measuring the views on large grids."""
    from campar.sweep.arrays import array_names, array_spec

    arrays = {}
    for name in array_names(job):
        dtype, tail = array_spec(job, name)
        shape = (tile.n_rows, job.shape[1], *tail)
        if name == "kind":
            arrays[name] = rng.choice(np.array([0, 0, 0, 1, 2], np.int8), size=shape)
        elif name in ("status", "flags"):
            arrays[name] = np.zeros(shape, dtype)
        elif dtype.kind == "f":
            arrays[name] = rng.normal(size=shape).astype(dtype)
        else:
            arrays[name] = rng.integers(1, 8, size=shape).astype(dtype)
    return arrays


def plausible_store(path: Path, points: int) -> Job:
    """A points × points store of ``plausible_tile``s."""
    job = Job.from_dict(
        {
            "name": "big",
            "sweep": {
                "omega": {"from": 6.0, "to": 0.02, "points": points},
                "mu_cn": {"from": 0.99, "to": 0.5, "points": points},
            },
        }
    )
    rng = np.random.default_rng(0)
    with open_store(path, job) as store:
        for tile in plan_tiles(job):
            store.write_tile(tile, plausible_tile(job, tile, rng))
    return job
