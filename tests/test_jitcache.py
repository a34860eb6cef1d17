"""The core's numba cache is cleared where numba keeps it when the core's sources change."""

import os
import subprocess
import sys
import textwrap

import pytest

CHECK = textwrap.dedent("""
    import os, sys
    from pathlib import Path
    from campar.core import jitcache
    from campar.core.kernel import chain_compiled

    located = Path(chain_compiled._cache.cache_path)  # numba's own choice of directory
    assert located.is_relative_to(os.environ["NUMBA_CACHE_DIR"]), located
    assert located in jitcache.cache_dirs()
    located.mkdir(parents=True, exist_ok=True)
    ours = [located / "kernel.chain_compiled-429.py311.nbi",
            located / "integrator.advance-464.py311.1.nbc"]
    theirs = located / "elsewhere.f-1.py311.nbi"  # not a module of the core
    for path in [*ours, theirs]:
        path.write_bytes(b"stale")
    (located / jitcache.STAMP).write_text("a digest of other sources")
    jitcache.ensure_fresh_cache()
    assert not any(path.exists() for path in ours)
    assert theirs.exists()
    assert (located / jitcache.STAMP).read_text() == jitcache.core_digest()
    print("ok")
""")


@pytest.mark.process
def test_stale_entries_are_cleared_under_numba_cache_dir(tmp_path):
    # numba keeps entries in NUMBA_CACHE_DIR/<source dir>_<hash>/, not at its top
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    run = subprocess.run(
        [sys.executable, "-c", CHECK], env=env, capture_output=True, text=True, timeout=120
    )
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "ok"


def test_every_module_of_the_core_that_numba_compiles_is_in_the_digest():
    # numba keys a cached function by its own file only: a module compiled into the kernel
    # (inlined, linked or an intrinsic) but missing from the digest would leave stale code
    # in the cache after an edit
    import re

    from campar.core import jitcache

    compiled = {
        path.stem
        for path in jitcache.PACKAGE.glob("*.py")
        if re.search(r"^@(njit|hot|entry|inlined|intrinsic)\b", path.read_text(), re.MULTILINE)
    }
    assert compiled, "no compiled module found: the pattern is out of date"
    assert compiled <= set(jitcache.COMPILED_MODULES), compiled - set(jitcache.COMPILED_MODULES)


def test_a_chain_and_a_shooter_check_the_cache_before_they_load_the_kernel(monkeypatch):
    # the paths of `campar point --from` (a replayed chain) and of the continuation (the
    # shooter), where nothing before them may have checked the cache in this process
    from campar.core import shooting
    from campar.model import compute

    calls = []
    monkeypatch.setattr(compute, "ensure_fresh_cache", lambda: calls.append("checked"))
    monkeypatch.setattr(compute, "run_chain", lambda *args: calls.append("chain"))
    compute.run_chain_over(
        {name: [] for name in compute.CHAIN_PARAMETERS}, 0, None, None, None, None
    )
    assert calls == ["checked", "chain"]

    class Loaded(Exception):
        pass

    def shooter(*args):
        calls.append("shooter")
        raise Loaded

    calls.clear()
    monkeypatch.setattr(shooting, "ensure_fresh_cache", lambda: calls.append("checked"))
    monkeypatch.setattr(shooting, "Shooter", shooter)
    with pytest.raises(Loaded):
        shooting.compile_shooter(0, None, None)
    assert calls == ["checked", "shooter"]
