"""campar's private numba calls (campar.core.numba_internals): they answer under the numba
the tests run with, and where a numba lacks them campar compiles normally, with the same
results."""

import tomllib
from pathlib import Path

import numba
from packaging.specifiers import SpecifierSet

from campar.core import jitcache, numba_internals, split_compile
from campar.core.kernel import chain_compiled, chain_signature
from campar.core.revolution import run_revolution
from campar.sweep.job import cell_job
from campar.sweep.tile import allocate_outputs, cell_settings, chain_starts, solver_options
from campar.views.point import POINT_OUTPUTS, simulate_point

ROOT = Path(__file__).resolve().parents[1]
ANOTHER_NUMBA = "_cache_of_another_numba"  # an attribute no numba dispatcher has


def test_the_supported_range_is_pyprojects_and_holds_the_installed_numba():
    dependencies = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    (numba_spec,) = [d for d in dependencies["dependencies"] if d.startswith("numba")]
    assert numba_spec == f"numba{numba_internals.SUPPORTED}"
    assert numba.__version__ in SpecifierSet(numba_internals.SUPPORTED)


def point_signature() -> tuple:
    """The chain's argument types for ``simulate_point(3.0)`` (other tests in this process
    may have compiled other signatures first)."""
    job = cell_job(outputs=POINT_OUTPUTS, omega=3.0)
    cs = cell_settings(job)
    out = allocate_outputs(0, cs.output_bits, job.n_sections)
    return chain_signature(job.law(0), chain_starts(job)[0], solver_options(job), cs, out)


def test_this_numbas_cache_answers():
    simulate_point(3.0)  # loads (or compiles and saves) the chain into this process
    assert numba_internals.split_available(chain_compiled)
    assert numba_internals.cache_path(chain_compiled) == jitcache.located_cache_dir()
    assert point_signature() in chain_compiled.signatures
    assert numba_internals.cache_serves(chain_compiled, point_signature()) is True
    # a signature nobody compiled is not served
    from numba import types

    never = (types.Array(types.float64, 3, "C"),) * 2
    assert numba_internals.cache_serves(run_revolution, never) is False


def test_without_the_internals_nothing_is_split_and_nothing_waits(monkeypatch):
    monkeypatch.setattr(numba_internals, "CACHE_ATTRIBUTE", ANOTHER_NUMBA)
    assert numba_internals.cache_path(chain_compiled) is None
    assert numba_internals.cache_serves(chain_compiled, ()) is None
    assert not numba_internals.split_available(run_revolution)
    assert jitcache.located_cache_dir() is None
    # stale entries are still looked for where numba documents its cache
    assert jitcache.PACKAGE / "__pycache__" in jitcache.cache_dirs()
    assert numba_internals.cache_indexes(chain_compiled, ()) is None
    assert not split_compile.cold_for(run_revolution, [()])
    job = cell_job(outputs=POINT_OUTPUTS, omega=3.0)
    assert split_compile.start_helper(solver_options(job), cell_settings(job)) is None
    monkeypatch.setattr(split_compile, "HELPER_SECONDS", 60.0)
    from numba import types

    never = (types.Array(types.float64, 3, "C"),) * 2
    split_compile.until_cached(run_revolution, never)  # returns at once, no 60 s wait
