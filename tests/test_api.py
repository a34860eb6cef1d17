"""The Python API (campar/api.py, ``dir(campar)``): its documented examples run, and it
returns what the commands write."""

import doctest
import json

import numpy as np
import pytest

import campar
import campar.api
from campar.cli import main
from campar.errors import JobError

REPOSITORY = __import__("pathlib").Path(__file__).resolve().parents[1]


def test_dir_lists_the_public_names():
    names = dir(campar)
    for name in (
        "run",
        "forecast",
        "line",
        "open",
        "committed",
        "simulate_point",
        "PointResult",
        "find_attractors",
        "BifurcationLine",
        "Job",
        "load_job",
    ):
        assert name in names
        assert callable(getattr(campar, name))


def test_the_documented_examples_run(monkeypatch):
    monkeypatch.chdir(REPOSITORY)  # the examples name jobs/…
    result = doctest.testmod(campar.api, optionflags=doctest.ELLIPSIS)
    assert result.attempted >= 3 and result.failed == 0


def test_the_public_functions_have_numpydoc_sections():
    for function in (campar.run, campar.forecast, campar.line):
        for section in ("Parameters\n", "Returns\n", "Raises\n", "Examples\n"):
            assert section in function.__doc__, (function.__name__, section)


def test_run_returns_the_store_the_cli_writes(tmp_path, capsys):
    """The same job through campar.run and `campar run --set`: the same map, cell for cell."""
    settings = {"sweep.omega.points": 6, "sweep.mu_cn.points": 4}
    store = campar.run(
        REPOSITORY / "jobs/smoke.yaml", store=tmp_path / "api.zarr", settings=settings
    )
    assert store == tmp_path / "api.zarr"
    code = main(
        [
            "run",
            str(REPOSITORY / "jobs/smoke.yaml"),
            "--store",
            str(tmp_path / "cli.zarr"),
            "--set",
            "sweep.omega.points=6",
            "--set",
            "sweep.mu_cn.points=4",
        ]
    )
    assert code == 0
    api, cli = campar.open(store), campar.open(tmp_path / "cli.zarr")
    assert api["label"].shape == (4, 6)
    np.testing.assert_array_equal(api["label"].values, cli["label"].values)
    np.testing.assert_array_equal(api["dc"].values, cli["dc"].values)


def test_line_returns_what_the_cli_writes(tmp_path, capsys):
    line = campar.line((3.0, 2.9), points=5, mu_kn=0.9)
    assert (
        main(
            [
                "line",
                "--omega",
                "2.9:3",
                "--points",
                "5",
                "--mu-kn",
                "0.9",
                "--npz",
                str(tmp_path / "l.npz"),
                "-o",
                str(tmp_path / "l.png"),
                "--json",
            ]
        )
        == 0
    )
    printed = json.loads(capsys.readouterr().out)["lines"][0]
    assert printed == json.loads(json.dumps(line.to_dict()))
    stored = np.load(tmp_path / "l.npz")
    np.testing.assert_array_equal(stored["omega"], line.omega)
    np.testing.assert_array_equal(stored["sections"], line.sections)


def test_line_refuses_bad_input_in_one_clear_error():
    with pytest.raises(JobError, match="at least 2 points"):
        campar.line((3.0, 2.9), points=1)
    with pytest.raises(JobError, match=r"^mu_kn must be in \(0, 1\), got 1.5$"):
        campar.line((3.0, 2.9), points=3, mu_kn=1.5)
