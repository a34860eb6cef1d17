"""One suite every store backend passes (as zarr's StoreTests), plus backend specifics.

These tests write synthetic tiles (random numbers of the right dtypes), so
they test the store alone and take no kernel time.
"""

import json
import logging
import os
import shutil
import signal
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
from support.processes import tree_env

from campar.errors import StoreError, StoreLocked, StoreMismatch
from campar.sweep.arrays import array_names, array_spec
from campar.sweep.job import Job
from campar.sweep.plan import plan_tiles
from campar.sweep.store import lock_path, open_store, read_store
from campar.sweep.store._lock import process_state
from campar.sweep.store._schema import cell_arrays

ROOT = Path(__file__).resolve().parents[1]

JOB = {
    "name": "store_suite",
    "sweep": {
        "omega": {"from": 5.0, "to": 1.0, "points": 7},
        "zeta": {"from": 0.1, "to": 0.3, "points": 5},
    },
    "outputs": ["label", "dc", "sections", "multipliers"],
    "classify": {"sections": 3},
    "tiles": {"rows": 2},
}


def make_job(**changes) -> Job:
    data = json.loads(json.dumps(JOB))
    for dotted, value in changes.items():
        *parents, last = dotted.split("__")
        node = data
        for key in parents:
            node = node.setdefault(key, {})
        node[last] = value
    return Job.from_dict(data)


def fake_tile(job: Job, tile, seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    arrays = {}
    for name in array_names(job):
        dtype, tail = array_spec(job, name)
        shape = (tile.n_rows, job.shape[1], *tail)
        if dtype.kind == "f":
            arrays[name] = rng.normal(size=shape).astype(dtype)
        else:
            arrays[name] = rng.integers(0, 100, size=shape).astype(dtype)
    return arrays


def snapshot(path) -> dict:
    """Every file under ``path`` (or the file) with its bytes: to prove a store untouched."""
    if path.is_file():
        return {path.name: path.read_bytes()}
    return {
        str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*")) if p.is_file()
    }


def tiles_rows(job: Job, index: int) -> slice:
    return plan_tiles(job)[index].rows


def dead_pid() -> int:
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


class StoreSuite:
    """Behaviour every backend shares; subclasses set ``suffix``."""

    suffix = ""

    @pytest.fixture
    def path(self, tmp_path):
        return tmp_path / f"results{self.suffix}"

    @pytest.fixture
    def job(self):
        return make_job()

    def test_new_store_has_schema_fills_and_attributes(self, path, job):
        with open_store(path, job) as store:
            assert not store.done.any()
            assert store.done.shape == (len(plan_tiles(job)),)
        with read_store(path) as reader:
            assert reader.job == job
            assert reader.names == array_names(job)
            np.testing.assert_array_equal(reader.coords["omega"], job.omega)
            np.testing.assert_array_equal(reader.coords["zeta"], job.second_values)
            for schema in cell_arrays(job):
                data = reader.read(schema.name)
                assert data.shape == schema.shape and data.dtype == schema.dtype
                if schema.dtype.kind == "f":
                    assert np.isnan(data).all(), schema.name
                else:
                    assert (data == -1).all(), schema.name
            assert reader.read("sections").shape == (5, 7, 3, 2)
            assert reader.attrs["job"] == job.to_dict()
            assert reader.attrs["job_hash"] == job.digest()
            assert reader.attrs["runs"] == []
            assert {"campar", "numpy", "numba", "zarr", "h5py", "mpi4py"} <= set(
                reader.attrs["versions"]
            )
            assert str(reader.path) == str(path)

    def test_tiles_round_trip_and_others_stay_unset(self, path, job):
        tiles = plan_tiles(job)
        written = {t.index: fake_tile(job, t, t.index) for t in (tiles[0], tiles[2])}
        with open_store(path, job) as store:
            for index, arrays in written.items():
                store.write_tile(tiles[index], arrays)
            assert store.done.tolist() == [True, False, True]
        with read_store(path) as reader:
            assert reader.done.tolist() == [True, False, True]
            for name in reader.names:
                data = reader.read(name)
                for index, arrays in written.items():
                    np.testing.assert_array_equal(data[tiles[index].rows], arrays[name])
                untouched = data[tiles[1].rows]
                assert (np.isnan(untouched) if data.dtype.kind == "f" else untouched == -1).all()

    def test_reader_sees_tiles_while_the_run_holds_the_store(self, path, job):
        tile = plan_tiles(job)[1]
        arrays = fake_tile(job, tile, 7)
        with open_store(path, job) as store:
            store.write_tile(tile, arrays)
            with read_store(path) as reader:
                assert reader.done.tolist() == [False, True, False]
                np.testing.assert_array_equal(reader.read("dc")[tile.rows], arrays["dc"])

    def test_reopening_the_same_job_resumes(self, path, job):
        tiles = plan_tiles(job)
        arrays = fake_tile(job, tiles[1], 1)
        with open_store(path, job) as store:
            store.write_tile(tiles[1], arrays)
            store.log_run({"outcome": "interrupted"})
        with open_store(path, make_job()) as store:
            assert store.done.tolist() == [False, True, False]
            assert store.runs == [{"outcome": "interrupted"}]
            store.log_run({"outcome": "complete"})
        with read_store(path) as reader:
            np.testing.assert_array_equal(reader.read("n")[tiles[1].rows], arrays["n"])
            assert [r["outcome"] for r in reader.attrs["runs"]] == ["interrupted", "complete"]

    def test_a_different_job_is_refused_naming_the_field_and_nothing_changes(self, path, job):
        with open_store(path, job) as store:
            store.write_tile(plan_tiles(job)[0], fake_tile(job, plan_tiles(job)[0], 0))
        before = snapshot(path)
        with pytest.raises(StoreMismatch) as err:
            open_store(path, make_job(integrator__rtol=1e-9))
        assert "integrator.rtol: 1e-07 in the store, 1e-09 in the job" in str(err.value)
        assert "--overwrite" in str(err.value)
        assert snapshot(path) == before
        assert not lock_path(path).exists()

    def test_the_store_path_is_not_part_of_the_job_identity(self, path, job):
        with open_store(path, job):
            pass
        moved = Job.from_dict({**job.to_dict(), "store": "elsewhere.zarr"})
        with open_store(path, moved) as store:
            assert not store.done.any()

    def test_overwrite_replaces_a_store_of_another_job(self, path, job):
        with open_store(path, job) as store:
            store.write_tile(plan_tiles(job)[0], fake_tile(job, plan_tiles(job)[0], 0))
        other = make_job(integrator__rtol=1e-9)
        with open_store(path, other, overwrite=True) as store:
            assert not store.done.any()
        with read_store(path) as reader:
            assert reader.job == other

    def test_something_else_at_the_path_is_never_replaced(self, path, job):
        if self.suffix == ".h5":
            path.write_bytes(b"my thesis")
        else:
            path.mkdir()
            (path / "thesis.tex").write_text("precious")
        before = snapshot(path)
        with pytest.raises(StoreError, match="not a campar store"):
            open_store(path, job, overwrite=True)
        assert snapshot(path) == before

    def test_a_second_run_is_refused_naming_host_and_pid(self, path, job):
        with open_store(path, job), pytest.raises(StoreLocked) as err:
            open_store(path, job)
        assert f"pid {os.getpid()}" in str(err.value)
        assert socket.gethostname() in str(err.value)

    @pytest.mark.process
    def test_a_run_in_another_process_holds_the_lock(self, path, job, tmp_path):
        script = textwrap.dedent(f"""
            import sys, time
            from campar.sweep.job import Job
            from campar.sweep.store import open_store
            job = Job.from_dict({job.to_dict()!r})
            with open_store({str(path)!r}, job):
                print("holding", flush=True)
                sys.stdin.read()
        """)
        holder = subprocess.Popen(
            [sys.executable, "-c", script], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
        )
        try:
            assert holder.stdout.readline().strip() == "holding"
            with pytest.raises(StoreLocked, match=f"pid {holder.pid} on host"):
                open_store(path, job)
        finally:
            holder.communicate("", timeout=60)
        with open_store(path, job):  # released when the holder closed the store
            pass

    @pytest.mark.process
    def test_a_stale_lock_is_taken_over_with_a_warning(self, path, job, caplog):
        with open_store(path, job):
            pass
        pid = dead_pid()
        holder = {"host": socket.gethostname(), "pid": pid, "start": "2020-01-01T00:00:00"}
        lock_path(path).write_text(json.dumps(holder))
        with caplog.at_level(logging.WARNING, "campar.sweep.store"), open_store(path, job):
            pass
        assert f"pid {pid}" in caplog.text and "stale" in caplog.text
        assert not lock_path(path).exists()

    def test_a_lock_from_another_host_is_refused(self, path, job):
        lock_path(path).write_text(json.dumps({"host": "node-17", "pid": 4242}))
        with pytest.raises(StoreLocked, match="pid 4242 on host node-17"):
            open_store(path, job)
        assert not path.exists()

    def test_write_tile_rejects_arrays_that_do_not_fit(self, path, job):
        tile = plan_tiles(job)[0]
        arrays = fake_tile(job, tile, 0)
        arrays["n"] = arrays["n"].astype(np.int64)
        with open_store(path, job) as store:
            with pytest.raises(ValueError, match="n is int64"):
                store.write_tile(tile, arrays)
            del arrays["n"]
            with pytest.raises(ValueError, match="missing \\['n'\\]"):
                store.write_tile(tile, arrays)
            assert not store.done.any()

    def test_reading_an_unknown_array_names_the_ones_present(self, path, job):
        with open_store(path, job):
            pass
        with read_store(path) as reader, pytest.raises(KeyError, match="lyapunov"):
            reader.read("lyapunov")

    def test_read_store_of_nothing_is_a_store_error(self, path):
        with pytest.raises(StoreError, match="no store"):
            read_store(path)

    def open_xarray(self, path):
        """The store as xarray opens it by itself (no campar code)."""
        xr = pytest.importorskip("xarray")
        if self.suffix == ".h5":
            pytest.importorskip("h5netcdf")
            return xr.open_dataset(path, engine="h5netcdf")
        return xr.open_zarr(path)

    def test_xarray_opens_a_labelled_dataset(self, path, job):
        tile = plan_tiles(job)[1]
        arrays = fake_tile(job, tile, 3)
        with open_store(path, job) as store:
            store.write_tile(tile, arrays)
        with self.open_xarray(path) as ds:
            assert ds["n"].dims == ("zeta", "omega")
            assert ds["state"].dims == ("zeta", "omega", "component")
            assert ds["sections"].dims == ("zeta", "omega", "section_point", "component")
            assert ds["multipliers"].dims == ("zeta", "omega", "multiplier", "part")
            assert ds["done"].dims == ("tile",)
            assert set(ds.dims) <= set(ds.coords)  # every dimension labelled
            assert ds["component"].values.tolist() == ["y", "ydot"]
            assert ds["part"].values.tolist() == ["real", "imag"]
            assert ds["tile_row_start"].values.tolist() == [0, 2, 4]
            assert ds["tile_row_stop"].values.tolist() == [2, 4, 5]
            assert float(ds["f0"]) == job.fixed["f0"]  # fixed parameters: scalar coordinates
            np.testing.assert_array_equal(ds["omega"].values, job.omega)
            np.testing.assert_array_equal(ds["zeta"].values, job.second_values)
            picked = ds["dc"].sel(zeta=job.second_values[2], omega=job.omega[4]).item()
            assert picked == arrays["dc"][0, 4]
            y = ds["state"].sel(component="y", zeta=job.second_values[2]).values
            np.testing.assert_array_equal(y, arrays["state"][0, :, 0])
            assert ds["done"].values.tolist() == [0, 1, 0]
            assert np.isnan(ds["n"].values[tiles_rows(job, 0)]).all()  # _FillValue -1 masked
            assert ds.attrs["job_hash"] == job.digest()
            assert ds.attrs["Conventions"] == "CF-1.10"

    @pytest.mark.process
    def test_sigkill_after_commits_loses_no_committed_tile(self, path, job):
        """A writer killed (SIGKILL) after committing tiles 0 and 2: both survive, resume works."""
        script = textwrap.dedent(f"""
            import os, signal
            import campar.sweep.store._hdf5 as h5
            from campar.sweep.job import Job
            from campar.sweep.plan import plan_tiles
            from campar.sweep.store import open_store
            from test_store import fake_tile
            h5.CHECKPOINT_TILES = 2  # the first two tiles reach the file, the third the journal
            job = Job.from_dict({job.to_dict()!r})
            tiles = plan_tiles(job)
            store = open_store({str(path)!r}, job)
            for i in (0, 2, 1):
                store.write_tile(tiles[i], fake_tile(job, tiles[i], i))
            os.kill(os.getpid(), signal.SIGKILL)
        """)
        env = tree_env()
        killed = subprocess.run([sys.executable, "-c", script], env=env, timeout=120)
        assert killed.returncode == -signal.SIGKILL
        with read_store(path) as reader:
            assert reader.done.all()
            tiles = plan_tiles(job)
            for i, tile in enumerate(tiles):
                expected = fake_tile(job, tile, i)
                for name in reader.names:
                    np.testing.assert_array_equal(reader.read(name)[tile.rows], expected[name])
        with open_store(path, job) as store:  # the dead writer's lock is stale
            assert store.done.all()


class TestZarrStore(StoreSuite):
    suffix = ".zarr"

    def test_chunks_follow_tiles(self, path, job):
        import zarr

        with open_store(path, job):
            pass
        group = zarr.open_group(path, mode="r")
        assert group["n"].chunks == (2, 7)
        assert group["sections"].chunks == (2, 7, 3, 2)
        assert group["done"].chunks == (1,)

    @pytest.mark.parametrize("separator", [".", "/"])
    @pytest.mark.parametrize("direction", ["down", "both"])
    def test_tile_chunks_are_zarrs_own_bytes(self, path, direction, separator, monkeypatch):
        """_chunks.DirectChunk writes the files zarr's setitem writes, byte for byte: full
        chunks, the edge chunk of a last tile with fewer rows, a direction axis, and a chunk
        holding only the fill (left out, as zarr leaves it), and chunks that begin with the
        fill but hold numbers after it (written: the first element alone decides nothing);
        with campar's chunk keys (c.<i>.<j>) and with those of stores made before them
        (c/<i>/<j>: a folder per chunk row, made at its first write)."""
        from campar.sweep.store import _zarr

        monkeypatch.setattr(_zarr, "CHUNK_KEYS", {"name": "default", "separator": separator})
        job = make_job(chains__direction=direction, classify__n_max=3)
        files = {}
        for way in ("direct", "zarr"):
            store_path = path.with_name(f"{way}{self.suffix}")
            with open_store(store_path, job) as store:
                assert all(store._tile_arrays.direct.values()) and all(store._tile_direct.values())
                if way == "zarr":  # every chunk through zarr's setitem
                    store._tile_arrays.direct = dict.fromkeys(store._tile_arrays.direct)
                    store._tile_direct = dict.fromkeys(store._tile_direct)
                for tile in plan_tiles(job):
                    arrays = fake_tile(job, tile, tile.index)
                    arrays["multipliers"][:] = np.nan  # the fill: no file
                    arrays["dc"].flat[0] = np.nan  # the fill, then numbers
                    arrays["n"].flat[0] = -1
                    store.write_tile(tile, arrays)
            chunks = [f.relative_to(store_path) for f in store_path.rglob("*") if f.is_file()]
            chunks = [f for f in chunks if len(f.parts) > 2 or f.name.startswith("c.")]  # c/…, c.…
            files[way] = {f: (store_path / f).read_bytes() for f in chunks}
        assert len(plan_tiles(job)) == 3 * len(job.directions)  # rows 2, 2, 1: an edge chunk
        assert not any(f.parts[0] == "multipliers" for f in files["zarr"])
        assert sum(f.parts[0] in ("dc", "n") for f in files["zarr"]) == 2 * len(plan_tiles(job))
        assert files["direct"] == files["zarr"]
        assert all((len(f.parts) == 2) == (separator == ".") for f in files["direct"])

    @pytest.mark.parametrize(
        "job_file, separator",
        [
            ("mu_cn", "."),
            ("mu_cn", "/"),
            ("basin_bistable", "."),
            ("mu_kn_both", "."),
            ("mu_kn_multistability", "."),
            ("design_rise_cycloidal", "."),
        ],
    )
    def test_a_new_store_is_the_store_zarr_makes(self, tmp_path, job_file, separator, monkeypatch):
        """campar writes a new store itself (_zarr_documents, _chunks): every file — each
        array's zarr.json, the coordinates' chunks (text among them), the group's zarr.json
        with the variables' checksums and every document consolidated, the root record — is
        byte for byte what zarr's own API writes (support.zarr_reference), for jobs of
        jobs/: the paper's plane (both chunk key separators), a basin, two sweep
        directions, an attractor census, a cam law's design plane."""
        from support.zarr_reference import build_with_zarr

        from campar.sweep.job import load_job
        from campar.sweep.store import _schema, _zarr

        monkeypatch.setattr(_schema, "utc_now", lambda: "2026-01-01T00:00:00+00:00")
        job = load_job(ROOT / "jobs" / f"{job_file}.yaml")
        _zarr._build(tmp_path / "campar.zarr", job, separator)
        build_with_zarr(tmp_path / "zarr.zarr", job, separator)
        ours, zarrs = snapshot(tmp_path / "campar.zarr"), snapshot(tmp_path / "zarr.zarr")
        assert sorted(ours) == sorted(zarrs)
        assert [name for name in ours if ours[name] != zarrs[name]] == []
        assert any(name.startswith("component/c") for name in ours)  # a text coordinate

    def test_a_run_log_is_appended_as_zarr_appends_it(self, path, job):
        """The run log goes into the group's attributes as zarr's ``attrs.update`` puts it:
        the group's zarr.json, consolidated documents and all, byte for byte."""
        import zarr

        tiles = plan_tiles(job)
        with open_store(path, job) as store:
            copy = path.with_name("copy.zarr")
            shutil.copytree(path, copy)
            store.write_tile(tiles[0], fake_tile(job, tiles[0], 0))
            store.log_run({"start": "2026-01-01T00:00:00+00:00", "tiles": 1, "ranks": 1})
        attrs = json.loads((path / "zarr.json").read_bytes())["attributes"]
        assert json.loads(attrs["runs"])[0]["tiles"] == 1
        group = zarr.open_group(copy, mode="r+")
        group.attrs.update({key: attrs[key] for key in ("runs", "history")})
        assert (copy / "zarr.json").read_bytes() == (path / "zarr.json").read_bytes()

    def test_a_store_with_the_older_chunk_keys_resumes_and_reads(self, path, job, monkeypatch):
        """Stores made before the flat keys have c/<i>/<j> (a folder per chunk row): a run
        of today's campar resumes one, writing its missing tiles under its own keys."""
        from campar.sweep.store import _zarr

        tiles = plan_tiles(job)
        with monkeypatch.context() as older:
            older.setattr(_zarr, "CHUNK_KEYS", {"name": "default", "separator": "/"})
            with open_store(path, job) as store:
                store.write_tile(tiles[0], fake_tile(job, tiles[0], 0))
        assert (path / "n" / "c" / "0" / "0").is_file()
        with open_store(path, job) as store:
            assert list(store.done) == [True] + [False] * (len(tiles) - 1)
            for tile in tiles[1:]:
                store.write_tile(tile, fake_tile(job, tile, tile.index))
        assert (path / "n" / "c" / "1" / "0").is_file() and not any(path.glob("n/c.*"))
        with read_store(path) as reader:
            assert reader.done.all()
            for tile in tiles:
                assert np.array_equal(
                    reader.read_rows("n", tile.rows), fake_tile(job, tile, tile.index)["n"]
                )

    @pytest.mark.parametrize("failing", ["first", "middle", "group", "root record"])
    def test_a_creation_that_fails_leaves_nothing(self, path, job, monkeypatch, failing):
        """A full disk fails one of the creation's writes (the first document, one in the
        middle, the group's zarr.json written last, the root record after it): nothing is
        left of the store, nor of the write."""
        import errno

        from campar.sweep.store import _chunks, _zarr, _zarr_documents

        put, calls = _zarr_documents.write_file, []

        def counted(file, body):
            calls.append(str(file))
            return put(file, body)

        for module in (_zarr_documents, _chunks):
            monkeypatch.setattr(module, "write_file", counted)
        _zarr.create(path.with_name("counted.zarr"), job)
        assert calls[-1].endswith(f"counted.zarr.creating-{os.getpid()}/zarr.json")
        shutil.rmtree(path.with_name("counted.zarr"))
        at = {"first": 1, "middle": len(calls) // 2, "group": len(calls)}.get(failing)

        def full_disk(*_):
            raise OSError(errno.ENOSPC, "No space left on device")

        def full_disk_once(file, body):
            calls.append(str(file))
            return full_disk() if len(calls) == at else put(file, body)

        calls.clear()
        for module in (_zarr_documents, _chunks):
            monkeypatch.setattr(module, "write_file", full_disk_once)
        if at is None:
            monkeypatch.setattr(_zarr, "write_zarr_root", full_disk)
        with pytest.raises(OSError, match="No space left"):
            _zarr.create(path, job)
        assert list(path.parent.iterdir()) == []

    def test_partial_files_of_a_killed_writer_are_cleaned_on_resume(self, path, job):
        with open_store(path, job):
            pass
        leftover = path / "n" / f"c.0.0.{'ab' * 16}.partial"
        leftover.write_bytes(b"half a chunk")
        with open_store(path, job):
            assert not leftover.exists()

    def test_a_killed_creation_leaves_no_store(self, path, job):
        aside = path.with_name(path.name + ".creating-12345")
        aside.mkdir()
        (aside / "zarr.json").write_text("{")
        with open_store(path, job):
            assert not aside.exists()


class TestHdf5Store(StoreSuite):
    suffix = ".h5"

    def test_dimension_scales_label_the_axes(self, path, job):
        with open_store(path, job):
            pass
        with h5py.File(path, "r") as f:
            n = f["n"]
            assert [d[0].name for d in n.dims] == ["/zeta", "/omega"]
            np.testing.assert_array_equal(n.dims[0][0][:], job.second_values)
            np.testing.assert_array_equal(n.dims[1][0][:], job.omega)
            assert [d[0].name for d in f["sections"].dims] == [
                "/zeta",
                "/omega",
                "/section_point",
                "/component",
            ]
            assert f["n"].chunks == (2, 7)
            assert f["done"].chunks == (1,)

    def test_the_file_is_untouched_until_a_checkpoint(self, path, job):
        tile = plan_tiles(job)[0]
        with open_store(path, job) as store:
            before = path.read_bytes()
            store.write_tile(tile, fake_tile(job, tile, 0))
            assert path.read_bytes() == before  # only the journal changed
        with h5py.File(path, "r") as f:
            assert f["done"][:].tolist() == [1, 0, 0]

    def test_a_killed_checkpoint_is_discarded_and_the_journal_replayed(self, path, job):
        tile = plan_tiles(job)[2]
        arrays = fake_tile(job, tile, 2)
        with open_store(path, job):
            pass
        from campar.sweep.store import tile_checksum
        from campar.sweep.store._hdf5 import write_entry

        checksum = tile_checksum(arrays, array_names(job))
        write_entry(path, tile.index, arrays, checksum)  # what a killed run leaves
        torn = path.with_name(path.name + ".checkpoint-999")
        torn.write_bytes(path.read_bytes()[:100])
        with open_store(path, job) as store:
            assert store.done.tolist() == [False, False, True]
            assert not torn.exists()
        with h5py.File(path, "r") as f:
            np.testing.assert_array_equal(f["dc"][tile.rows], arrays["dc"])


@pytest.mark.parametrize("when", ["before the rename", "after the rename"])
@pytest.mark.process
def test_hdf5_sigkill_inside_a_checkpoint_loses_nothing(tmp_path, when):
    """Kill the writer at the two delicate points of a checkpoint; the journal makes up."""
    path = tmp_path / "results.h5"
    job = make_job()
    script = textwrap.dedent(f"""
        import os, signal
        import campar.sweep.store._hdf5 as h5
        from campar.sweep.job import Job
        from campar.sweep.plan import plan_tiles
        from campar.sweep.store import open_store
        from test_store import fake_tile
        job = Job.from_dict({job.to_dict()!r})
        tiles = plan_tiles(job)
        store = open_store({str(path)!r}, job)
        for i in (0, 1):
            store.write_tile(tiles[i], fake_tile(job, tiles[i], i))
        replace = os.replace
        def dying_replace(src, dst):
            if {when == "after the rename"}:
                replace(src, dst)
            os.kill(os.getpid(), signal.SIGKILL)
        h5.os.replace = dying_replace
        store.checkpoint()
    """)
    env = tree_env()
    killed = subprocess.run([sys.executable, "-c", script], env=env, timeout=120)
    assert killed.returncode == -signal.SIGKILL
    leftovers = list(tmp_path.glob("results.h5.checkpoint-*"))
    assert bool(leftovers) == (when == "before the rename")
    tiles = plan_tiles(job)
    for _ in range(2):  # as a reader sees it, then after open_store cleaned up
        with read_store(path) as reader:
            assert reader.done.tolist() == [True, True, False]
            for i in (0, 1):
                np.testing.assert_array_equal(
                    reader.read("sections")[tiles[i].rows], fake_tile(job, tiles[i], i)["sections"]
                )
        open_store(path, job).close()
    assert not list(tmp_path.glob("results.h5.checkpoint-*"))
    assert not (tmp_path / "results.h5.journal").exists()  # emptied and removed


@pytest.mark.process
def test_a_lock_held_by_a_killed_unreaped_process_is_stale(tmp_path):
    """A rank killed with its launcher lingers as a zombie until init reaps it."""
    path, job = tmp_path / "zombie.zarr", make_job()
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        child.kill()
        for _ in range(200):  # wait until it is a zombie (we do not reap it yet)
            if process_state(child.pid) == "Z":
                break
            time.sleep(0.01)
        holder = {"host": socket.gethostname(), "pid": child.pid, "start": "now"}
        lock_path(path).write_text(json.dumps(holder))
        with open_store(path, job):
            pass
    finally:
        child.wait()
