"""What keeps the plain tier quick: plain ``pytest`` on every core under pytest-xdist
(tests/support/tiers.py, ``default_workers``), and the test modules' compiled helpers
cached on disk without going stale when the core changes (tests/support/jit.py)."""

import os
import re

import pytest
from support.jit import STAMP, cached_njit
from support.tiers import default_workers

pytest_plugins = ("pytester",)

SUITE = """
import os

def test_one():
    print("worker", os.environ.get("PYTEST_XDIST_WORKER", "none"))

def test_two():
    print("worker", os.environ.get("PYTEST_XDIST_WORKER", "none"))
"""


@pytest.fixture
def project(pytester, monkeypatch):
    """A project whose ini names its testpaths, as campar's pyproject.toml does; xdist
    counts two cores."""
    monkeypatch.setenv("PYTEST_XDIST_AUTO_NUM_WORKERS", "2")
    pytester.makeini("[pytest]\ntestpaths = checks\n")
    checks = pytester.mkpydir("checks")
    (checks / "test_suite.py").write_text(SUITE)
    return pytester


@pytest.mark.parametrize(
    "args, workers",
    [
        ((), 2),  # plain pytest: the tier, on every core
        (("-m", "slow"), 2),  # a tier chosen by marker, still every test path
        (("-n", "0"), None),  # asked for this process
        (("-n", "1"), None),  # asked for a number: xdist's own
        (("-p", "no:xdist"), None),
        (("--pdb",), None),
        (("--collect-only",), None),
        (("checks/test_suite.py",), None),  # a file named: one process
        (("checks/test_suite.py::test_one",), None),
    ],
)
def test_plain_pytest_takes_every_core_unless_told_otherwise(project, args, workers):
    assert default_workers(project.parseconfig(*args)) == workers


def test_one_core_is_this_process(project, monkeypatch):
    monkeypatch.setenv("PYTEST_XDIST_AUTO_NUM_WORKERS", "1")
    assert default_workers(project.parseconfig()) is None


@pytest.mark.process
def test_plain_pytest_runs_in_workers_and_n0_in_this_process(project, monkeypatch):
    """End to end: the hook reaches xdist before it starts its workers."""
    for name in ("PYTEST_XDIST_WORKER", "PYTEST_XDIST_WORKER_COUNT", "PYTEST_XDIST_TESTRUNUID"):
        monkeypatch.delenv(name, raising=False)  # this test's own worker, if it runs in one
    plugin = ("-p", "support.tiers", "-s")
    project.syspathinsert(os.path.dirname(os.path.dirname(__file__)))
    run = project.runpytest_subprocess(*plugin)
    run.assert_outcomes(passed=2)
    assert set(re.findall(r"worker (\S+)", run.stdout.str())) <= {"gw0", "gw1"}
    assert "2 workers" in run.stdout.str()
    run = project.runpytest_subprocess(*plugin, "-n", "0")
    run.assert_outcomes(passed=2)
    assert re.findall(r"worker (\S+)", run.stdout.str()) == ["none", "none"]


def test_a_cached_helper_is_dropped_when_the_core_changes(tmp_path, monkeypatch):
    """The tests' cache directory keeps its entries while the core's digest is the one it
    was built from, and loses them, and only them, once the core changes."""
    import support.jit as jit

    digest = ["core 1"]
    monkeypatch.setattr(jit, "core_digest", lambda: digest[0])
    entries = [tmp_path / f"test_x.helper-3.py311.{end}" for end in ("nbi", "1.nbc")]
    other = tmp_path / "notes.txt"

    def new_process():
        jit._fresh.cache_clear()
        jit._fresh(tmp_path)

    new_process()  # an empty directory gets its stamp
    assert (tmp_path / STAMP).read_text() == "core 1"
    for path in [*entries, other]:
        path.write_text("compiled")
    new_process()
    assert all(path.exists() for path in entries)  # the same core: kept
    digest[0] = "core 2"
    new_process()
    assert not any(path.exists() for path in entries) and other.exists()
    assert (tmp_path / STAMP).read_text() == "core 2"


def test_cached_njit_caches_where_numba_reads_and_compiles_the_same():
    import numpy as np

    from campar.core import numba_internals

    def norm(v):
        return np.sqrt(np.sum(v * v))

    helper = cached_njit(norm)
    assert numba_internals.cache_path(helper) is not None
    assert helper(np.array([3.0, 4.0])) == 5.0
