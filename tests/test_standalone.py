"""Stores that stand alone (a tabulated cam's table kept in the store), and input files and
small command-line cases refused in one line before anything is read or computed. Each
command runs in this process (``campar.cli.main``)."""

import math
import os
import shutil

import numpy as np
import pytest
import yaml

import campar
from campar.cli import main
from campar.errors import JobError, StoreMismatch
from campar.model.cam_table import _KNOWN

GRID = {
    "omega": {"from": 4.0, "to": 3.0, "points": 3},
    "mu_cn": {"from": 0.9, "to": 0.8, "points": 2},
}


def table_text(n: int = 64, stroke: float = 1.0) -> str:
    """A smooth cam of one revolution: S = stroke (1 − cos θ) / 2, ``n`` points."""
    rows = ["theta,S"]
    for i in range(n):
        theta = 2 * math.pi * i / n
        rows.append(f"{theta!r},{stroke * 0.5 * (1 - math.cos(theta))!r}")
    return "\n".join(rows) + "\n"


@pytest.fixture
def tabulated(tmp_path, monkeypatch):
    """(job file, store, table) of a computed 2 × 3 map of a tabulated cam, run in
    ``tmp_path/work`` with the table given by a relative path."""
    work = tmp_path / "work"
    work.mkdir()
    (work / "cam.csv").write_text(table_text())
    job = {
        "name": "tabulated",
        "sweep": GRID,
        "classify": {"window_revolutions": 16},
        "model": {"cam": {"table": "cam.csv"}},
        "store": "tabulated.zarr",
        "tiles": {"rows": 1},
    }
    (work / "job.yaml").write_text(yaml.safe_dump(job, sort_keys=False))
    monkeypatch.chdir(work)
    _KNOWN.clear()  # as a new process: no table known but the file
    assert main(["run", "job.yaml"]) == 0
    return work / "job.yaml", work / "tabulated.zarr", work / "cam.csv"


def test_a_tabulated_cam_store_is_read_verified_plotted_and_resumed_without_its_table(
    tabulated, tmp_path, monkeypatch, capsys
):
    job_file, store, table = tabulated
    expected = campar.open(store)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    moved = shutil.move(store, elsewhere / "moved.zarr")
    table.unlink()
    monkeypatch.chdir(elsewhere)
    _KNOWN.clear()
    for command in (["verify", "moved.zarr"], ["status", "moved.zarr"]):
        assert main(command) == 0, capsys.readouterr()
    assert main(["plot", "moved.zarr", "-o", "map.png"]) == 0
    assert (elsewhere / "map.png").stat().st_size > 0
    ds = campar.open(moved)
    for name in ("kind", "n", "p", "dc", "label"):
        np.testing.assert_array_equal(ds[name].values, expected[name].values)
    assert "cam_table" not in ds.attrs or ds.attrs["cam_table"] == table_text()
    # resumed from the store alone: a tile made pending is computed again, bit for bit
    from campar.sweep.store._root import ZARR_FILE, Root, write_zarr_root

    root = Root.decode((moved / ZARR_FILE).read_text())
    write_zarr_root(moved, root.with_sums(np.where(np.arange(2) == 1, 0, root.checksums)))
    assert campar.committed(moved).tolist() == [True, False]
    _KNOWN.clear()
    assert main(["run", "moved.zarr"]) == 0
    again = campar.open(moved)
    assert again["done"].values.all()
    for name in ("kind", "n", "p", "dc"):
        np.testing.assert_array_equal(again[name].values, expected[name].values)


def test_a_changed_table_refuses_a_resume_and_says_so(tabulated, capsys):
    job_file, store, table = tabulated
    table.write_text(table_text(stroke=1.01))
    _KNOWN.clear()
    assert main(["run", str(job_file)]) == StoreMismatch.exit_code
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "the cam table cam.csv has changed" in err[0], err
    assert main(["verify", str(store)]) == 0  # the store itself reads with the table it keeps


# -- input files: type and size before a byte is read -----------------------------------


def special_files(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    big = tmp_path / "big.yaml"
    big.write_bytes(b"#" * (2 << 20))
    return {
        "/dev/zero": "a character device",
        str(fifo): "a FIFO",
        str(tmp_path): "a directory",
        str(big): "is at most 1048576",
        str(tmp_path / "absent.yaml"): "No such file",
    }


def bad_job_files(tmp_path) -> dict[str, str]:
    """{path: what the refusal says} of job files that are no job: special files, and text
    that is not UTF-8, not YAML, bounded YAML or a mapping."""
    found = special_files(tmp_path)
    for name, data, said in [
        ("latin1.yaml", b"name: caf\xe9\n", "not UTF-8 text"),
        ("unclosed.yaml", b"name: [x\n", "not valid YAML"),
        ("binary.yaml", b"name: !!binary aGk=\n", "not allowed in a job"),
        ("twice.yaml", b"name: a\nname: b\n", "given twice"),
        ("list.yaml", b"- 1\n- 2\n", "a mapping of keys"),
        ("empty.yaml", b"", "a mapping of keys"),
    ]:
        (tmp_path / name).write_bytes(data)
        found[str(tmp_path / name)] = said
    return found


def test_bad_job_files_are_refused_in_one_line_by_every_command_that_reads_one(tmp_path, capsys):
    """The bad-input matrix: input kind × command, every cell refused in one line, exit 2."""
    commands = (["run"], ["run", "--dry-run"], ["run", "--set", "name=x"])
    cells = 0
    for path, said in bad_job_files(tmp_path).items():
        for command in commands:
            assert main([command[0], path, *command[1:]]) == JobError.exit_code, (command, path)
            err = capsys.readouterr().err.strip().splitlines()
            assert len(err) == 1 and said in err[0], (command, path, err)
            cells += 1
    with capsys.disabled():
        print(
            f"BAD-INPUT job files: {cells} cells ({cells // len(commands)} kinds × "
            f"{len(commands)} commands), {cells} refused in one line"
        )


def test_a_cam_table_that_is_no_regular_file_is_refused_unread(tmp_path, capsys):
    for path, said in special_files(tmp_path).items():
        job = tmp_path / "job.yaml"
        job.write_text(
            yaml.safe_dump(
                {"name": "t", "sweep": GRID, "model": {"cam": {"table": path}}}, sort_keys=False
            )
        )
        assert main(["run", str(job), "--dry-run"]) == JobError.exit_code, path
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and said in err[0], (path, err)


@pytest.mark.parametrize(
    "value", ["!!binary aGVsbG8=", "!!timestamp 2024-01-01", "!!set {a, b}", "!!omap [a: 1]"]
)
def test_yaml_tags_outside_the_safe_set_are_refused(tmp_path, value, capsys):
    job = tmp_path / "job.yaml"
    job.write_text(f"name: t\nstore: {value}\n")
    assert main(["run", str(job), "--dry-run"]) == JobError.exit_code
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "is not allowed in a job" in err[0], err
    with pytest.raises(JobError, match="not allowed"):
        campar.load_job(job)


def write_small_job(tmp_path) -> str:
    job = tmp_path / "job.yaml"
    job.write_text(
        yaml.safe_dump(
            {"name": "t", "sweep": GRID, "store": str(tmp_path / "t.zarr")}, sort_keys=False
        )
    )
    return str(job)


@pytest.mark.parametrize(
    "arguments, said",
    [
        (["--set", "name=[unclosed"], "not valid YAML: line 1"),
        (["--ranks", "2"], "--dry-run"),
    ],
)
def test_small_command_line_cases_are_refused_in_one_line(tmp_path, arguments, said, capsys):
    job = write_small_job(tmp_path)
    assert main(["run", job, *arguments]) == JobError.exit_code
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and said in err[0], err
    assert not (tmp_path / "t.zarr").exists()
    assert main(["run", job, "--ranks", "2", "--dry-run"]) == 0  # with --dry-run it plans


def test_curves_refuses_an_empty_store_path_as_run_does(tmp_path, capsys):
    job = write_small_job(tmp_path)
    assert main(["run", job]) == 0
    capsys.readouterr()
    assert main(["curves", str(tmp_path / "t.zarr"), "--store", ""]) == JobError.exit_code
    curves_err = capsys.readouterr().err.strip().splitlines()
    assert main(["run", job, "--store", ""]) == JobError.exit_code
    run_err = capsys.readouterr().err.strip().splitlines()
    assert len(curves_err) == len(run_err) == 1 and "store" in curves_err[0], curves_err
    assert not (tmp_path / "t-curves.zarr").exists()


@pytest.mark.parametrize("zoom", ["nan:4", "3:inf", "-inf:2"])
def test_plot_refuses_a_zoom_that_is_not_finite(tmp_path, zoom, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["plot", str(tmp_path / "x.zarr"), f"--omega={zoom}"])
    assert exit_.value.code == 2
    assert "two finite numbers" in capsys.readouterr().err
