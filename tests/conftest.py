"""The session's environment, the tiers plugin and the fixtures every test module may use.
Helpers live in ``support`` (``from support.jobs import ...``); nothing here runs at import
beyond definitions."""

import os
from pathlib import Path

import pytest
import yaml

pytest_plugins = ("support.tiers",)

TESTS = Path(__file__).resolve().parent


def pytest_configure(config: pytest.Config) -> None:
    # Tests compile campar's integrator with fields of their own (test_integrator), and
    # numba indexes those signatures by the test module's name: a process that later reads
    # such an index must be able to import the module (else ModuleNotFoundError, measured),
    # and the package's own cache, which every campar run reads, must not hold them. So the
    # session caches into a directory of its own, and its children find the test modules.
    # Set here, before collection imports campar (numba chooses a function's cache
    # directory when its module is imported), and restored when the session ends.
    saved = {name: os.environ.get(name) for name in ("NUMBA_CACHE_DIR", "PYTHONPATH")}
    os.environ.setdefault("NUMBA_CACHE_DIR", str(TESTS.parent / ".numba-test-cache"))
    os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [str(TESTS), saved["PYTHONPATH"]]))

    def restore() -> None:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value

    config.add_cleanup(restore)


@pytest.fixture
def write_job(tmp_path):
    """write_job(name="x", store=..., **sections) -> (path of a YAML job file, Job)."""
    from support.jobs import SLOW, SMALL_JOB, merge

    from campar.sweep.job import Job

    def write(name="small", slow=False, **extra):
        data = merge(SMALL_JOB, SLOW) if slow else dict(SMALL_JOB)
        data = merge(data, {"name": name, **extra})
        data.setdefault("store", str(tmp_path / f"{name}.zarr"))
        path = tmp_path / f"{name}.yaml"
        path.write_text(yaml.safe_dump(data, sort_keys=False))
        return path, Job.from_dict(data)

    return write


@pytest.fixture(scope="session")
def warm_numba_cache() -> None:
    """The kernel compiled into the session's numba cache once, in this process, before a
    test starts campar in a child: every child then loads it (about a second) instead of
    compiling it (about 20 s), and children started together do not compile it each."""
    from campar.sweep.tile import warm_up

    warm_up()


@pytest.fixture(autouse=True)
def _warm_cache_for_children(request: pytest.FixtureRequest) -> None:
    if request.node.get_closest_marker("process"):
        request.getfixturevalue("warm_numba_cache")
