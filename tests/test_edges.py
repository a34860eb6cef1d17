"""Hard edges: symbolic links, full disks, unwritable outputs, signals outside a run's
handlers, job validation and size limits, and the one-line messages of each."""

import json
import os
import signal
import socket
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest
import zarr
from support.damage import (
    assert_synthetic,
    finish,
    leftovers,
    plausible_store,
    small_disk,
    synthetic_store,
)
from support.jobs import plane_job
from support.processes import CAMPAR, MPIRUN, start_campar, tree_env, wait_until_guarded
from test_store import fake_tile, make_job

from campar.cli import main
from campar.errors import (
    Interrupted,
    JobError,
    OutputError,
    StoreIOError,
    StoreLocked,
)
from campar.sweep import signals
from campar.sweep.budget import DEFAULT_MAX_STORE, check_budget, estimate, parse_size
from campar.sweep.job import Job, load_job
from campar.sweep.plan import plan_tiles
from campar.sweep.store import lock_path, open_store, read_store
from campar.views.output import figure_file, writable_file

# -- symbolic links -----------------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".zarr", ".h5"])
def test_a_store_through_a_link_is_written_at_its_target_and_the_link_stays(tmp_path, suffix):
    (tmp_path / "data").mkdir()
    target, link = tmp_path / "data" / f"s{suffix}", tmp_path / f"link{suffix}"
    link.symlink_to(target)  # dangling until the store is created
    job = synthetic_store(link)
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert target.exists() and not target.is_symlink()
    assert lock_path(target).exists() is False and not lock_path(link).exists()
    assert_synthetic(target, job)


def test_a_second_run_through_any_alias_of_a_store_is_refused(tmp_path):
    (tmp_path / "data").mkdir()
    target = tmp_path / "data" / "s.zarr"
    (tmp_path / "alias.zarr").symlink_to(target)
    (tmp_path / "folder").symlink_to(tmp_path / "data")
    job = make_job()
    with open_store(target, job):
        for alias in (tmp_path / "alias.zarr", tmp_path / "folder" / "s.zarr"):
            with pytest.raises(StoreLocked, match=f"pid {os.getpid()} on host"):
                open_store(alias, job)


@pytest.mark.parametrize("suffix", [".zarr", ".h5"])
def test_overwrite_through_a_link_replaces_the_target_and_keeps_the_link(tmp_path, suffix):
    (tmp_path / "data").mkdir()
    target, link = tmp_path / "data" / f"s{suffix}", tmp_path / f"link{suffix}"
    synthetic_store(target)
    link.symlink_to(target)
    other = make_job(integrator__rtol=1e-9)
    with open_store(link, other, overwrite=True) as store:
        assert not store.done.any()
    assert link.is_symlink() and os.readlink(link) == str(target)
    with read_store(target) as reader:
        assert reader.job == other
    assert not list(tmp_path.glob("**/*deleting*"))


# -- full disks and other refusals of the system ------------------------------------------


@pytest.mark.parametrize("suffix", [".zarr", ".h5"])
@pytest.mark.process
def test_a_full_disk_is_one_error_74_then_a_resume_completes_the_same_store(tmp_path, suffix):
    disk = tmp_path / "disk"
    job = make_job(sweep__omega__points=200, tiles__rows=1)  # tiles of ~60 kB
    path = disk / f"s{suffix}"
    with small_disk(disk, 256) as resize:
        with pytest.raises(StoreIOError) as err:
            synthetic_store(path, job)
        assert err.value.exit_code == 74
        assert str(path) in str(err.value) and "No space left on device" in str(err.value)
        assert "\n" not in str(err.value)
        assert leftovers(disk) == []
        with pytest.raises(StoreIOError):  # still full: the same error, nothing left over
            finish(path, job)
        assert leftovers(disk) == []
        resize(8192)
        finish(path, job)
        assert_synthetic(path, job)


@pytest.mark.process
def test_hdf5_never_meets_a_full_disk_inside_the_library(tmp_path):
    """Even if the free-space check is fooled, HDF5 does not write into a full disk: the
    blocks are reserved first (measured before: thousands of HDF5 errors, then a crash)."""
    disk = tmp_path / "disk"
    script = textwrap.dedent(f"""
        import collections, sys
        import campar.sweep.store._hdf5 as h5
        Usage = collections.namedtuple("Usage", "total used free")
        h5.shutil.disk_usage = lambda path: Usage(1 << 40, 0, 1 << 40)
        from support.damage import synthetic_store
        from test_store import make_job
        synthetic_store({str(disk / "s.h5")!r}, make_job(sweep__omega__points=200))
    """)
    env = tree_env()
    with small_disk(disk, 160):
        done = subprocess.run(
            [sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=120
        )
        assert done.returncode == 1, done.stderr[-2000:]
        assert "StoreIOError" in done.stderr and "No space left on device" in done.stderr
        assert "HDF5-DIAG" not in done.stderr and len(done.stderr.splitlines()) < 40
        assert leftovers(disk) == []


@pytest.mark.process
def test_a_read_only_store_path_is_one_line_74_before_any_computation(tmp_path):
    folder = tmp_path / "ro"
    with small_disk(folder, 64):
        subprocess.run(["mount", "-o", "remount,ro", str(folder)], check=True)
        with pytest.raises(StoreIOError, match="Read-only file system"):
            open_store(folder / "s.zarr", make_job())
        with pytest.raises(OutputError, match="Read-only file system"):
            figure_file(folder / "map.png")


def test_outputs_are_checked_before_anything_is_computed(tmp_path):
    with pytest.raises(OutputError, match=r"\.xyz file has no image format.*\.png"):
        figure_file(tmp_path / "p.xyz")
    with pytest.raises(OutputError, match="without a suffix"):
        figure_file(tmp_path / "p")
    with pytest.raises(OutputError, match="is a directory"):
        writable_file(tmp_path)
    (tmp_path / "file").write_text("")
    with pytest.raises(OutputError, match="cannot write"):
        writable_file(tmp_path / "file" / "below.png")  # a file where a folder must be
    with pytest.raises(OutputError, match="the folder .*new does not exist"):
        figure_file(tmp_path / "new" / "p.pdf")  # never created: a typo makes no folders
    assert not (tmp_path / "new").exists()
    assert figure_file(tmp_path / "p.pdf") == tmp_path / "p.pdf"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]  # the probe is gone


@pytest.mark.parametrize(
    "args",
    [
        ["plot", "STORE", "-o", "no/such/map.png"],
        ["point", "--omega", "3", "--plot", "no/such/orbit.png"],
        ["line", "--omega", "2:3", "--points", "3", "-o", "no/line.png"],
        ["line", "--omega", "2:3", "--points", "3", "--npz", "no/line.npz"],
        ["plot", "STORE", "-o", "file/map.png"],
    ],
    ids=["plot -o", "point --plot", "line -o", "line --npz", "a file as the folder"],
)
def test_an_output_in_a_missing_folder_is_one_line_and_creates_no_folder(
    tmp_path, monkeypatch, capsys, args
):
    from support.damage import synthetic_store

    from campar.cli import main

    synthetic_store(tmp_path / "s.zarr")
    (tmp_path / "file").write_text("")
    monkeypatch.chdir(tmp_path)
    before = sorted(p.name for p in tmp_path.iterdir())
    args = [str(tmp_path / "s.zarr") if a == "STORE" else a for a in args]
    assert main(args) == OutputError.exit_code
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and ("does not exist" in err or "is a file, not a folder" in err)
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_a_store_below_a_file_is_named_as_such(tmp_path, capsys):
    from campar.cli import main

    (tmp_path / "plain.txt").write_text("")
    job = tmp_path / "j.yaml"
    job.write_text(
        "name: x\nsweep: {omega: {from: 6, to: 1, points: 3}, "
        "mu_cn: {from: 0.9, to: 0.5, points: 2}}\n"
    )
    assert main(["run", str(job), "--store", str(tmp_path / "plain.txt" / "s.zarr")]) == 74
    err = capsys.readouterr().err
    assert "plain.txt is a file, not a folder" in err and "File exists" not in err


def test_plot_and_point_refuse_a_bad_output_in_one_line(tmp_path, capsys):
    path = tmp_path / "s.zarr"
    synthetic_store(path)
    for args in (
        ("plot", path, "-o", tmp_path / "p.xyz"),
        ("point", "--omega", "3", "--plot", "/proc/x.png"),
    ):
        assert main([*map(str, args)]) == OutputError.exit_code
        err = capsys.readouterr().err
        assert err.startswith(f"campar {args[0]}: cannot write the figure")
        assert len(err.splitlines()) == 1


# -- the lock -----------------------------------------------------------------------------


def test_an_empty_lock_file_is_refused_naming_the_file_not_pid_none(tmp_path):
    path = tmp_path / "s.zarr"
    lock_path(path).write_text("")
    with pytest.raises(StoreLocked) as err:
        open_store(path, make_job())
    assert "names no run" in str(err.value) and str(lock_path(path)) in str(err.value)
    assert "None" not in str(err.value)


@pytest.mark.process
def test_lock_files_a_killed_run_was_writing_are_removed(tmp_path):
    path = tmp_path / "s.zarr"
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stray = path.with_name(f"{path.name}.lock.{dead.pid}.tmp")
    stray.write_text("")
    with open_store(path, make_job()):
        assert not stray.exists()


# -- signals outside the run's handlers ---------------------------------------------------


def test_a_signal_before_the_start_is_one_interrupted_and_after_the_end_nothing():
    saved = signals.guard_start()
    try:
        with pytest.raises(Interrupted, match="interrupted before start by SIGINT") as err:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1)
        assert err.value.exit_code == 130
        signals.guard_start()
        with pytest.raises(Interrupted) as err:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(1)
        assert err.value.exit_code == 143  # 128 + SIGTERM, as a shell reports it
        signals.finished()
        os.kill(os.getpid(), signal.SIGUSR1)  # ignored: would end the process by default
    finally:
        signals.restore_signals(saved)


@pytest.mark.parametrize("delay", [0.15, pytest.param(0.6, marks=pytest.mark.slow)])
@pytest.mark.process
def test_campar_run_interrupted_early_says_so_in_one_line(write_job, delay):
    # from campar's first line on (before it, Python's own start-up, which takes longer
    # than a fixed delay on a loaded machine, handles a SIGINT with its own traceback)
    path, job = write_job()
    proc = start_campar("run", path)
    wait_until_guarded(proc, ranks=1)
    time.sleep(delay)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode in (130, 75, 0), err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err
    if proc.returncode == 130:
        assert "interrupted before start by SIGINT" in err


# -- validation ---------------------------------------------------------------------------

SWEEP = (
    "sweep:\n  omega: {from: 3.0, to: 1.0, points: 8}\n  mu_cn: {from: 0.9, to: 0.6, points: 3}\n"
)


@pytest.mark.parametrize(
    "text,expected",
    [
        (SWEEP.replace("to: 1.0", "to: 3.0"), "from = to = 3 with 8 points"),
        (SWEEP.replace("points: 8", "points: true"), "points: must be a number, not true"),
        (SWEEP + "fixed: {zeta: false}\n", "fixed: must be a number"),
        (SWEEP + "integrator: {rtol: true}\n", "rtol: must be a number"),
        (SWEEP + "name: y\n", "the key 'name' is given twice (lines 1 and 5)"),
        (SWEEP.replace("{from: 0.9,", "{from: 0.9, from: 0.8,"), "'from' is given twice"),
    ],
    ids=["from=to", "bool points", "bool fixed", "bool rtol", "duplicate top", "duplicate inner"],
)
def test_job_files_that_mean_something_else_are_refused(tmp_path, text, expected):
    path = tmp_path / "job.yaml"
    path.write_text("name: x\n" + text)
    with pytest.raises(JobError, match=expected.replace("(", r"\(").replace(")", r"\)")):
        load_job(path)
    path.write_text("name: x\n" + SWEEP)
    load_job(path)  # the same without the mistake is fine


def test_a_single_point_axis_may_have_from_equal_to():
    one = {"omega": {"from": 3, "to": 3, "points": 1}, "f0": {"from": 0.5, "to": 0.5, "points": 1}}
    job = Job.from_dict({"name": "p", "sweep": one})
    assert job.shape == (1, 1)


def test_a_job_too_large_is_refused_with_the_estimate_and_the_option_raises_the_limit():
    huge = Job.from_dict(plane_job("huge", (6, 0.02, 100_000), ("mu_cn", 0.99, 0.5, 100_000)))
    with pytest.raises(JobError, match=r"store would hold up to 670\.6 GiB.*--max-store 671G"):
        check_budget(huge)
    assert check_budget(huge, max_store=parse_size("671G")).cells == 10**10
    wide = plane_job("wide", (6, 0.02, 100_000), ("mu_cn", 0.99, 0.5, 4000), tiles={"rows": 4000})
    wide = Job.from_dict(wide)
    with pytest.raises(JobError, match="each rank would need about .*--max-memory"):
        check_budget(wide, max_store=DEFAULT_MAX_STORE * 100)
    assert estimate(make_job()).store_bytes < 10_000
    assert parse_size("1.5k") == 1536 and parse_size("2GiB") == 2 * 2**30


def test_campar_run_refuses_a_huge_job_before_touching_the_disk(tmp_path, capsys):
    job = tmp_path / "huge.yaml"
    job.write_text(
        "name: huge\nsweep:\n  omega: {from: 6, to: 0.02, points: 100000}\n"
        "  mu_cn: {from: 0.99, to: 0.5, points: 100000}\n"
    )
    assert main(["run", str(job), "--store", str(tmp_path / "huge.zarr")]) == 2
    err = capsys.readouterr().err
    assert "670.6 GiB" in err and "--max-store" in err and len(err.splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["huge.yaml"]


def test_point_names_the_models_key_as_every_entry_does(capsys):
    """One message for a bad value whatever the entry (flag, --set, job, Python): the
    model's key, which the flag's help names."""
    assert main(["point", "--omega", "3", "--rtol", "0"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("campar point: integrator.rtol: ") and err.count("\n") == 1
    with pytest.raises(SystemExit):
        main(["point", "--help"])
    assert "(integrator.rtol; default 1e-07)" in capsys.readouterr().out


def test_status_of_a_store_written_by_another_host_run_is_safe(tmp_path):
    """A lock of another host does not stop readers (status, verify, plot)."""
    path = tmp_path / "s.zarr"
    synthetic_store(path)
    lock_path(path).write_text(json.dumps({"host": "node-9", "pid": 1}))
    with read_store(path) as reader:
        assert reader.done.all()
    assert socket.gethostname() != "node-9"


def test_a_store_of_synthetic_tiles_resumes_after_a_kill_inside_a_write(tmp_path):
    """A tile half written (arrays without flag) is pending and written again."""
    path, job = tmp_path / "s.zarr", make_job()
    synthetic_store(path, job, tiles={0})
    with open_store(path, job):  # tile 1's dc written, by a writer killed before its commit
        zarr.open_group(path, mode="r+")["dc"][plan_tiles(job)[1].rows] = np.zeros((2, 7))
    assert (path / "dc" / "c.1.0").is_file()
    assert finish(path, job) == [1, 2]
    assert_synthetic(path, job)
    assert fake_tile  # the numbers assert_synthetic compared


@pytest.mark.slow  # mpirun: ~3 s
@pytest.mark.skipif(not MPIRUN.exists(), reason=f"no mpirun at {MPIRUN}")
@pytest.mark.process
@pytest.mark.mpi
def test_under_mpirun_a_bad_job_or_store_is_reported_once(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(
        "name: x\nsweep:\n  omega: {from: 3, to: 3, points: 4}\n"
        "  mu_cn: {from: 0.9, to: 0.6, points: 3}\n"
    )
    good = tmp_path / "good.yaml"
    good.write_text(bad.read_text().replace("to: 3,", "to: 1,"))
    with small_disk(tmp_path / "ro", 64):
        subprocess.run(["mount", "-o", "remount,ro", str(tmp_path / "ro")], check=True)
        for args, code in (((bad,), 2), ((good, "--store", tmp_path / "ro" / "s.zarr"), 74)):
            out = subprocess.run(
                [str(MPIRUN), "-n", "2", *CAMPAR, "run", *map(str, args)],
                capture_output=True,
                text=True,
                timeout=300,
            )
            assert out.returncode == code, out.stdout + out.stderr
            assert out.stderr.count("campar run:") == 1, out.stderr
            assert "Traceback" not in out.stderr and "BAD TERMINATION" not in out.stdout


@pytest.mark.slow  # builds stores of 90 000 and 640 000 cells and reads each twice, ~12 s
def test_status_and_verify_memory_does_not_grow_with_the_grid(tmp_path, monkeypatch, capsys):
    """Both read the store in batches of whole tiles of about ``BATCH_BYTES``: 7× the cells,
    the same peak of memory. ``BATCH_BYTES`` is made 1 MiB, so that stores of a few MB are
    many batches; the peak is that of every allocation of Python and numpy in the command
    (tracemalloc), which reading the store whole would raise by its size. The bound, 3 MB
    for 550 000 more cells, is under 6 bytes a cell: one whole array of 8-byte numbers kept
    fails it, while the interpreter's own tables (its interned strings' grows by some 2 MB
    now and then) stay under it."""
    import gc
    import tracemalloc

    import campar.sweep.store._integrity as integrity

    monkeypatch.setattr(integrity, "BATCH_BYTES", 2**20)
    small, large = tmp_path / "small.zarr", tmp_path / "large.zarr"
    plausible_store(small, 300)
    plausible_store(large, 800)

    def peak_mb(command: str, path) -> float:
        gc.collect()
        tracemalloc.start()
        try:
            assert main([command, str(path)]) == 0
        finally:
            _, peak = tracemalloc.get_traced_memory()
            tracemalloc.stop()
        capsys.readouterr()
        return peak / 1e6

    for command in ("status", "verify"):
        grown = peak_mb(command, large) - peak_mb(command, small)
        assert grown < 3, f"campar {command}: {grown:.1f} MB more for 7× the cells"


def test_an_hdf5_store_with_a_second_name_is_refused_untouched(tmp_path):
    """A hard link is another name the lock does not know: a second run through it would
    write the same file. Refused, the store left as it was."""
    from support.damage import synthetic_store
    from test_store import snapshot

    from campar.errors import StoreError

    path = tmp_path / "s.h5"
    job = synthetic_store(path)
    os.link(path, tmp_path / "other.h5")
    before = snapshot(path)
    with pytest.raises(StoreError, match="2 names \\(hard links\\)"):
        open_store(tmp_path / "other.h5", job)
    with pytest.raises(StoreError, match="hard links"):
        open_store(path, job)
    assert snapshot(path) == before
