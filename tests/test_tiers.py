"""The test tiers (tests/support/tiers.py): what plain pytest selects, the hook that fails a
test starting a program without its marker, and the README's test command as .ci/run runs
it. The sessions under test run in this process (pytester), their tests start ``true``
and a program named mpirun that is ``true`` too."""

import re
import shutil
from pathlib import Path

import pytest
from support.tiers import required_markers

ROOT = Path(__file__).resolve().parents[1]

pytest_plugins = ("pytester",)

SUITE = """
import subprocess, sys
import pytest

def test_unit():
    pass

@pytest.mark.slow
def test_slow():
    pass

@pytest.mark.process
def test_marked_start():
    subprocess.run(["true"], check=True)

def test_unmarked_start():
    subprocess.run(["true"], check=True)

@pytest.mark.process
def test_mpirun_without_mpi(tmp_path):
    subprocess.run([MPIRUN, "-n", "2"], check=True)

@pytest.mark.mpi
def test_mpirun_with_mpi():
    subprocess.run([MPIRUN, "-n", "2"], check=True)

def test_fork_is_no_program():
    import os
    pid = os.fork()
    if pid == 0:
        os._exit(0)
    os.waitpid(pid, 0)
"""


@pytest.fixture
def suite(pytester, tmp_path_factory):
    mpirun = tmp_path_factory.mktemp("bin") / "mpirun"
    mpirun.symlink_to(shutil.which("true"))
    pytester.makepyfile(test_suite=f"MPIRUN = {str(mpirun)!r}\n" + SUITE)
    pytester.makeini(
        "[pytest]\nmarkers =\n    process\n    mpi\n    slurm\n    browser\n    slow\n"
    )
    return pytester


def outcomes(result) -> dict[str, str]:
    return {
        r.nodeid.split("::")[-1]: r.outcome
        for r in result.reprec.getreports("pytest_runtest_logreport")
        if r.when == "call" or r.outcome != "passed"
    }


def test_plain_pytest_runs_the_tests_without_a_tier_marker(suite):
    result = suite.runpytest_inprocess("-p", "support.tiers", "-p", "no:cacheprovider")
    assert outcomes(result) == {
        "test_unit": "passed",
        "test_unmarked_start": "failed",
        "test_fork_is_no_program": "passed",  # a copy of this interpreter, no program
    }
    result.stdout.fnmatch_lines(["*4 deselected*", "*time by tier*", "unit 3 tests *"])


def test_every_tier_runs_and_a_program_started_without_its_marker_fails(suite):
    result = suite.runpytest_inprocess(
        "-p", "support.tiers", "-p", "no:cacheprovider", "--all-tiers"
    )
    ran = outcomes(result)
    assert ran == {
        "test_unit": "passed",
        "test_slow": "passed",
        "test_marked_start": "passed",
        "test_unmarked_start": "failed",
        "test_mpirun_without_mpi": "failed",
        "test_mpirun_with_mpi": "passed",  # mpi implies process
        "test_fork_is_no_program": "passed",
    }
    text = result.stdout.str()
    assert re.search(r"test_unmarked_start starts 'true' .* without @pytest\.mark\.process", text)
    assert re.search(
        r"test_mpirun_without_mpi starts '\S*mpirun -n 2' .* without @pytest\.mark\.mpi", text
    )


def test_a_marker_expression_selects_across_tiers(suite):
    result = suite.runpytest_inprocess("-p", "support.tiers", "-p", "no:cacheprovider", "-m", "mpi")
    assert outcomes(result) == {"test_mpirun_with_mpi": "passed"}


@pytest.mark.parametrize(
    "words, needed",
    [
        (["/usr/bin/python", "-m", "campar.cli", "run"], {"process"}),
        (["/venv/bin/mpirun", "-n", "2", "python"], {"process", "mpi"}),
        (["srun", "--mpi=pmi2", "hostname"], {"process", "slurm"}),
        (["/root/.cache/ms-playwright/chromium-1/chrome-linux/chrome"], {"process", "browser"}),
    ],
)
def test_what_a_started_program_needs(words, needed):
    assert required_markers(words) == needed


def test_ci_runs_exactly_the_readmes_test_command():
    readme = (ROOT / "README.md").read_text()
    (command,) = [
        line
        for line in readme.splitlines()
        if line.startswith("python3 -m venv .venv") and "[test]" in line
    ]
    assert command in (ROOT / ".ci" / "run").read_text().splitlines()
    assert "--all-tiers" in command and "--durations=20" in command


@pytest.mark.parametrize("load, expected", [(0.5, 1.0), (2.0, 1.0), (6.0, 3.0), (100.0, 10.0)])
def test_the_timeout_stretches_with_the_load_per_core(monkeypatch, load, expected):
    from support import tiers

    monkeypatch.setattr(tiers.os, "getloadavg", lambda: (load, load, load))
    monkeypatch.setattr(tiers.os, "cpu_count", lambda: 2)
    assert tiers.stretch() == expected
