"""Start-up cost: what a process loads before its first cell, checked in fresh processes."""

import json
import subprocess
import sys
import textwrap

import pytest

# A process that loads the cached kernel, as `campar run` does, then compiles a function
# that uses numba's BLAS: what it imported, and what numba decided.
LOAD_KERNEL = textwrap.dedent(
    """
    import json, sys
    import numpy as np
    from numba import njit
    from campar.sweep.job import Job
    from campar.sweep.tile import compile_kernel
    job = Job.from_dict({
        "name": "one",
        "sweep": {"omega": {"from": 3.0, "to": 3.0, "points": 1},
                  "mu_cn": {"from": 0.8, "to": 0.8, "points": 1}},
    })
    compile_kernel(job)
    loaded_scipy = "scipy.linalg" in sys.modules
    from numba.np import arraymath
    a, b = np.arange(1.0, 5.0), np.arange(2.0, 6.0)
    dot = njit(lambda x, y: np.dot(x, y))(a, b)
    print(json.dumps({"scipy": loaded_scipy, "blas": arraymath._HAVE_BLAS, "dot": dot}))
    """
)
# numba's own decision, in a process where campar has no say.
NUMBA_ALONE = "from numba.np import arraymath; print(arraymath._HAVE_BLAS)"


@pytest.mark.process
def test_kernel_loads_without_scipy_and_numba_blas_is_unchanged():
    done = subprocess.run([sys.executable, "-c", LOAD_KERNEL], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    found = json.loads(done.stdout.splitlines()[-1])
    alone = subprocess.run([sys.executable, "-c", NUMBA_ALONE], capture_output=True, text=True)
    assert found["scipy"] is False  # loading the kernel imported no scipy.linalg
    assert found["blas"] is (alone.stdout.strip() == "True")  # as numba itself decides
    assert found["dot"] == 1 * 2 + 2 * 3 + 3 * 4 + 4 * 5  # numba's BLAS still works


@pytest.mark.process
@pytest.mark.mpi
def test_bench_startup_prints_fixed_cost_and_rank_ratios(capsys, monkeypatch):
    from pathlib import Path

    from campar.cli import main

    monkeypatch.chdir(Path(__file__).resolve().parents[1])  # the plane is read from jobs/
    assert main(["bench", "startup", "--quick"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("machine: ") and "load average" in out
    reference = out.split("reference job")[1].split("\n\n")[0].splitlines()
    rows = [line.split() for line in reference if line.strip().startswith("this:")]
    assert [row[1] for row in rows] == ["1", "mpirun"]
    for row in rows:  # fixed seconds ≥ the run part; CPU of a process is positive
        fixed, cpu, part = map(float, row[-3:])
        assert fixed > part >= 0 and cpu > 0
    assert "whole-command 1/2 by round" in out
