"""A store computed by another version of the numerical kernel is never resumed: ``campar
run`` refuses it in one line naming both versions and the way out (exit 3, as for a store of
another job), serially and under mpirun, Zarr and HDF5, leaving every byte of it as it was;
``status``, ``verify`` and ``--dry-run`` say which kernel computed it, and the explorer's cell
panel says that a cell computed again need not come back bit for bit.

The stores are written in this process by a campar whose kernel version is patched to
another value (or whose stores record none, as before stores recorded it): their tiles are
synthetic, so only the refusal is under test, not the kernel."""

import pytest
from support.damage import synthetic_store
from support.processes import NEEDS_MPIRUN, run_campar_mpi
from test_store import snapshot

import campar.sweep.store._schema as schema
from campar.cli import main
from campar.core.version import KERNEL_VERSION
from campar.errors import StoreMismatch
from campar.sweep.store import open_store, read_store

OTHER = KERNEL_VERSION + 1  # a kernel that is not this campar's


def store_of_kernel(path, monkeypatch, kernel=OTHER, tiles=(0,)):
    """A store of ``test_store.make_job()`` with ``tiles`` committed, as a campar whose
    kernel is version ``kernel`` writes it (None: a campar that records no version)."""
    current = schema.versions
    with monkeypatch.context() as patch:
        if kernel is None:
            unrecorded = {k: v for k, v in current().items() if k != "kernel"}
            patch.setattr(schema, "versions", lambda: unrecorded)
        else:
            patch.setattr(schema, "KERNEL_VERSION", kernel)
        job = synthetic_store(path, tiles=list(tiles))
    with read_store(path) as reader:  # what the store says, read back
        recorded = reader.attrs["versions"].get("kernel")
    assert recorded == (None if kernel is None else str(kernel))
    return job


def as_it_was(path) -> dict:
    """The store's every byte and the names beside it (a lock file left would show)."""
    return {"store": snapshot(path), "beside": sorted(p.name for p in path.parent.iterdir())}


@pytest.mark.parametrize("suffix", [".zarr", ".h5"])
def test_a_resume_of_another_kernels_store_is_refused_and_changes_nothing(
    tmp_path, monkeypatch, capsys, suffix
):
    path = tmp_path / f"other-kernel{suffix}"
    job = store_of_kernel(path, monkeypatch)
    before = as_it_was(path)
    assert main(["run", str(path)]) == StoreMismatch.exit_code  # the store's own job
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    line = err[0]
    assert f"kernel version {OTHER}" in line and f"kernel version {KERNEL_VERSION}" in line
    assert "another --store path" in line and "--overwrite" in line
    assert as_it_was(path) == before
    with pytest.raises(StoreMismatch, match=f"computed by kernel version {OTHER}"):
        open_store(path, job)  # the library's entry refuses alike
    assert as_it_was(path) == before
    # the way out the line names: --overwrite computes the map again with this kernel
    with open_store(path, job, overwrite=True) as store:
        assert not store.done.any()
    with read_store(path) as reader:
        assert reader.attrs["versions"]["kernel"] == str(KERNEL_VERSION)


def test_a_store_that_records_no_kernel_is_refused_too(tmp_path, monkeypatch):
    path = tmp_path / "unrecorded.zarr"
    job = store_of_kernel(path, monkeypatch, kernel=None)
    before = as_it_was(path)
    with pytest.raises(StoreMismatch, match="an earlier kernel .it records no version."):
        open_store(path, job)
    assert as_it_was(path) == before


def test_a_store_of_this_kernel_resumes(tmp_path, monkeypatch):
    path = tmp_path / "this-kernel.zarr"
    job = store_of_kernel(path, monkeypatch, kernel=KERNEL_VERSION)
    with open_store(path, job) as store:
        assert store.done.tolist() == [True] + [False] * (len(store.done) - 1)


def test_status_verify_and_dry_run_say_which_kernel_computed_the_store(
    tmp_path, monkeypatch, capsys
):
    other, this = tmp_path / "other.zarr", tmp_path / "this.zarr"
    store_of_kernel(other, monkeypatch, tiles=range(3))
    store_of_kernel(this, monkeypatch, kernel=KERNEL_VERSION)
    before = as_it_was(other)
    said = f"kernel  version {OTHER}, not this campar's ({KERNEL_VERSION}): `campar run` does"
    for command in ("status", "verify"):
        assert main([command, str(other)]) == 0
        assert said in capsys.readouterr().out
        assert main([command, str(this)]) == 0
        assert f"kernel  version {KERNEL_VERSION} (this campar's)" in capsys.readouterr().out
    assert main(["run", str(other), "--dry-run"]) == 0
    out = capsys.readouterr().out
    assert f"computed by kernel version {OTHER}" in out
    assert "a run refuses it unless --overwrite" in out
    assert as_it_was(other) == before


def test_the_explorer_says_the_store_is_another_kernels(tmp_path, monkeypatch):
    """A real (tiny) map computed while the kernel called itself another version: the cell
    computed again in the panel, and a row's line, are said to come from another kernel
    than the store's."""
    from support.jobs import plane_job

    import campar
    from campar.explore.cells import cell_report
    from campar.explore.lines import line_report

    path = tmp_path / "map.zarr"
    data = plane_job("panel", (4.0, 3.0, 3), ("mu_cn", 0.8, 0.8, 1), outputs=["label"])
    with monkeypatch.context() as patch:
        patch.setattr(schema, "KERNEL_VERSION", OTHER)
        campar.run({**data, "store": str(path)})
    report = cell_report(path, 0, 1)
    assert report["cell"]["kernel"] == str(OTHER)
    note = report["kernel_note"]
    assert f"kernel version {KERNEL_VERSION}" in note and f"computed by {OTHER}" in note
    assert line_report(path, "row", 0, 0, None, None, None)["kernel_note"] == note
    same = tmp_path / "same.zarr"
    campar.run({**data, "store": str(same)})
    assert "kernel_note" not in cell_report(same, 0, 1)
    assert "kernel_note" not in line_report(same, "row", 0, 0, None, None, None)


@pytest.mark.process
@pytest.mark.mpi
@NEEDS_MPIRUN
def test_under_mpirun_every_rank_ends_on_the_refusal(tmp_path, monkeypatch):
    path = tmp_path / "other-kernel.zarr"
    store_of_kernel(path, monkeypatch)
    before = as_it_was(path)
    result = run_campar_mpi(2, "run", path)
    assert result.returncode == StoreMismatch.exit_code, result.stderr
    assert result.stderr.count(f"computed by kernel version {OTHER}") == 1, result.stderr
    assert "Traceback" not in result.stderr
    assert as_it_was(path) == before


def test_a_store_of_another_kernel_and_of_a_job_that_differs_is_refused_naming_both(
    tmp_path, monkeypatch
):
    """A default that changed with the kernel (transient.extrapolate) makes an earlier
    kernel's store hold another job too: the refusal names the key and the kernel."""
    from test_store import make_job

    path = tmp_path / "earlier.zarr"
    store_of_kernel(path, monkeypatch)
    before = as_it_was(path)
    with pytest.raises(StoreMismatch) as refused:
        open_store(path, make_job(transient__extrapolate=1))
    said = str(refused.value)
    assert "transient.extrapolate" in said and f"computed by kernel version {OTHER}" in said
    assert as_it_was(path) == before
