"""`campar warm-up` (the install line's step) compiles what a first point (plotted, so its
orbit traced) and a first map use: after it, neither compiles anything more into an
empty numba cache."""

import os
import subprocess

import pytest
from support.processes import CAMPAR


def cached_functions(cache) -> set[str]:
    """Every compiled function's index and every signature's machine code in the cache."""
    return {p.name for p in cache.rglob("*.nb[ic]")}


@pytest.mark.slow  # compiles the kernel into an empty cache: ~20 s
@pytest.mark.process
@pytest.mark.timeout(900)  # a cold compile, then a point and a map: minutes on a loaded machine
def test_warm_up_leaves_nothing_for_a_point_or_a_map_to_compile(tmp_path):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}

    def campar(*args):
        done = subprocess.run(
            [*CAMPAR, *args], env=env, capture_output=True, text=True, timeout=600, cwd=tmp_path
        )
        assert done.returncode == 0, done.stderr
        return done.stdout

    assert "compiled and cached" in campar("warm-up")
    warm = cached_functions(tmp_path / "cache")
    assert any(name.startswith("kernel.") for name in warm), sorted(warm)
    campar("point", "--omega", "3", "--plot", str(tmp_path / "point.png"))
    job = tmp_path / "job.yaml"
    job.write_text(
        "name: w\nsweep:\n  omega: {from: 4.0, to: 2.0, points: 3}\n"
        "  mu_cn: {from: 0.9, to: 0.8, points: 2}\n"
        f"store: {tmp_path / 'w.zarr'}\n"
    )
    campar("run", str(job))
    assert cached_functions(tmp_path / "cache") == warm
