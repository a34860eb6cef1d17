"""`campar run --set` (a job changed key by key, validated as the file is), `--dry-run`
(the plan and cost, nothing written) and `run --help` (resuming, exit codes)."""

import re

import pytest
import yaml

from campar.cli import main
from campar.sweep.store import read_store

SMOKE = {
    "name": "tiny",
    "sweep": {
        "omega": {"from": 3.0, "to": 2.0, "points": 5},
        "mu_cn": {"from": 0.9, "to": 0.6, "points": 3},
    },
    "tiles": {"rows": 2},
}


@pytest.fixture
def job_file(tmp_path):
    path = tmp_path / "tiny.yaml"
    path.write_text(yaml.safe_dump(SMOKE, sort_keys=False))
    return path


def test_set_changes_the_job_as_an_edited_file_would(tmp_path, job_file):
    store = tmp_path / "set.zarr"
    assert (
        main(
            [
                "run",
                str(job_file),
                "--store",
                str(store),
                "--set",
                "sweep.omega.points=4",
                "--set",
                "model.tensile=allow",
                "--set",
                "outputs=[label, dc]",
            ]
        )
        == 0
    )
    edited = tmp_path / "edited.yaml"
    data = {
        **SMOKE,
        "sweep": {**SMOKE["sweep"], "omega": {"from": 3.0, "to": 2.0, "points": 4}},
        "model": {"tensile": "allow"},
        "outputs": ["label", "dc"],
    }
    edited.write_text(yaml.safe_dump(data, sort_keys=False))
    assert main(["run", str(edited), "--store", str(tmp_path / "file.zarr")]) == 0
    with read_store(store) as a, read_store(tmp_path / "file.zarr") as b:
        assert a.attrs["job_hash"] == b.attrs["job_hash"]
        assert a.job.shape == (3, 4) and a.job.model.tensile == "allow"
        assert (a.read("dc") == b.read("dc")).all()


@pytest.mark.parametrize(
    "setting, message",
    [
        (
            "sweep.omega.pointz=200",
            "--set: sweep.omega.pointz: unknown key; allowed here: from, to, points",
        ),
        ("sweep.omega.points=abc", "--set: sweep.omega.points: must be a number, not text"),
        (
            "sweep.omega.points=0",
            "--set: sweep.omega.points: Input should be greater than or equal",
        ),
        ("model.tensile=pull", "--set: model.tensile: Input should be 'clamp' or 'allow'"),
        ("modle.tensile=allow", "--set: modle: unknown key; allowed here: name, sweep"),
        ("model.tensile.x=1", "--set model.tensile.x: model.tensile is 'clamp', not a mapping"),
        ("sweep.omega.points", "--set expects KEY=VALUE"),
    ],
)
def test_a_bad_setting_is_one_line_and_exit_2_with_nothing_written(
    tmp_path, job_file, capsys, setting, message
):
    store = tmp_path / "never.zarr"
    assert main(["run", str(job_file), "--store", str(store), "--set", setting]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"campar run: {message}"), err
    assert not store.exists()


def test_a_bad_job_file_is_named_as_the_file_not_as_a_setting(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump({**SMOKE, "tiles": {"rowz": 2}}, sort_keys=False))
    assert main(["run", str(bad), "--set", "sweep.omega.points=4", "--dry-run"]) == 2
    assert capsys.readouterr().err.startswith(f"campar run: job file {bad}: tiles.rowz: unknown")


def dry_run(*args, capsys) -> dict:
    assert main(["run", *args, "--dry-run"]) == 0
    out = capsys.readouterr().out
    return {line[:8].strip(): line[9:] for line in out.splitlines() if line[:8].strip()}


def test_dry_run_plans_and_writes_nothing_then_sees_what_a_store_holds(tmp_path, job_file, capsys):
    store = tmp_path / "tiny.zarr"
    plan = dry_run(
        str(job_file), "--store", str(store), "--set", "sweep.mu_cn.points=5", capsys=capsys
    )
    assert not store.exists()
    assert plan["store"] == f"{store}  (new)"
    assert plan["cells"].startswith("25 (5 mu_cn × 5 omega), 25 to compute")
    assert plan["tiles"] == "3 of 2 rows, 3 to compute"  # ⌈5 / 2⌉
    assert re.fullmatch(r"up to [\d.]+ [kMG]?i?B \(uncompressed\)", plan["size"]), plan["size"]
    assert re.fullmatch(r"about [\d.]+ MiB per rank", plan["memory"]), plan["memory"]
    seconds = re.fullmatch(r"about (\d+) (s|min|h) on 1 rank", plan["time"])
    assert seconds, plan["time"]
    two = dry_run(
        str(job_file),
        "--store",
        str(store),
        "--set",
        "sweep.mu_cn.points=5",
        "--ranks",
        "2",
        capsys=capsys,
    )
    assert two["time"].endswith("on 2 ranks")
    assert main(["run", str(job_file), "--store", str(store), "--set", "sweep.mu_cn.points=5"]) == 0
    capsys.readouterr()
    done = dry_run(
        str(job_file), "--store", str(store), "--set", "sweep.mu_cn.points=5", capsys=capsys
    )
    assert done["store"] == f"{store}  (holds this job)"
    assert done["cells"].endswith("0 to compute") and done["tiles"].endswith("0 to compute")
    other = dry_run(str(job_file), "--store", str(store), capsys=capsys)  # 3 rows: another job
    assert "a run refuses it unless --overwrite" in other["store"]


def test_forecast_time_is_the_sampled_cost_times_the_pending_cells(tmp_path, job_file):
    import campar

    one = campar.forecast(job_file, store=tmp_path / "x.zarr")
    assert one.sampled_rows >= 1 and one.cell_seconds > 0
    assert one.seconds == pytest.approx(one.pending_cells * one.cell_seconds)
    assert one.pending_cells == one.cells == 15 and one.tiles == 2


def test_run_help_says_how_to_resume_and_what_exit_75_means(capsys):
    with pytest.raises(SystemExit):
        main(["run", "--help"])
    text = capsys.readouterr().out
    assert "resuming:" in text and "Run the same command again" in text
    assert re.search(r"75 interrupted by a signal", text)
    assert "--set KEY=VALUE" in text and "--dry-run" in text
