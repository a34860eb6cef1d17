"""`campar point`: output formats and clear refusals of bad input; the numbers it prints
are those of the shared reference cells (SciPy DOP853, rtol 1e-10, outside campar)."""

import json
import math
import re
import subprocess
import sys

import pytest
from support.cli import call_campar
from support.jobs import case_arguments, reference_case


def test_point_json_has_the_documented_keys_and_the_reference_cells_values(capsys):
    case = reference_case(112)  # ω = 3.15, μkn = 0.91: a 2-2 with the clamp active
    expected = case["expected"]
    out = call_campar(
        capsys, "point", *case_arguments(case), "--json", "--multipliers", "--lyapunov"
    )
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    for key in (
        "label",
        "n",
        "p",
        "kind",
        "dc",
        "eps_min",
        "eps_max",
        "pn_max",
        "revolutions",
        "steps",
        "multipliers",
        "lyapunov",
    ):
        assert key in data
    assert (data["label"], data["n"], data["p"]) == (
        expected["label"],
        expected["n"],
        expected["p"],
    )
    assert data["dc"] == pytest.approx(expected["DC"], abs=0.0025)
    assert data["eps_min"] == pytest.approx(expected["eps_min"], abs=0.0025)
    assert data["eps_max"] == pytest.approx(expected["eps_max"], abs=0.0025)
    assert data["pn_max"] == pytest.approx(expected["Pn_max"], rel=0.01)
    # Liouville: |λ1 λ2| = exp(∮ div f dt) ≤ exp(−2ζ n 2π/ω), since div f ≤ −2ζ
    (re1, im1), (re2, im2) = data["multipliers"]
    bound = math.exp(-2 * case["zeta"] * data["n"] * 2 * math.pi / case["omega"])
    assert 0 < abs(complex(re1, im1) * complex(re2, im2)) <= bound


def test_point_summary_is_human_readable(capsys):
    case = reference_case(102)  # ω = 1, the paper's base values: 1-1
    out = call_campar(capsys, "point", *case_arguments(case))
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith(case["expected"]["label"] + " ")
    dc = re.search(r"duty cycle (\S+)", out.stdout)
    assert dc and float(dc.group(1)) == pytest.approx(case["expected"]["DC"], abs=0.0025)


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--omega", "0"], "omega must be > 0"),
        (["--omega", "1", "--mu-kn", "1.0"], "mu_kn must be in (0, 1)"),
        (["--omega", "1", "--mu-cn", "-0.1"], "mu_cn must be in (0, 1)"),
        (["--omega", "1", "--zeta", "-1"], "zeta must be ≥ 0"),
        (["--omega", "1", "--f0", "nan"], "f0: Input should be a finite number"),
        (["--omega", "1", "--rtol", "2"], "rtol"),
        (
            ["--omega", "1", "--revolutions", "0"],
            "transient.max_revolutions: Input should be greater than or equal to 1",
        ),
    ],
)
def test_bad_input_exits_2_naming_the_parameter(capsys, args, needle):
    out = call_campar(capsys, "point", *args)
    assert out.returncode == 2
    assert needle in out.stderr
    assert out.stdout == ""


@pytest.mark.parametrize("preset", [None, "3"])
@pytest.mark.process
def test_the_campar_process_runs_one_blas_thread_unless_told_otherwise(preset):
    """OpenBLAS's idle pools spin beside the kernel's threads (campar.cli): the command's
    process starts one BLAS thread, or what the caller's OPENBLAS_NUM_THREADS says."""
    import os

    if preset and (os.cpu_count() or 1) < 2:
        pytest.skip("OpenBLAS starts no pool on one core")
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if preset:
        env["OPENBLAS_NUM_THREADS"] = preset
    probe = (
        "import campar.cli, os, numpy; print(os.environ['OPENBLAS_NUM_THREADS'], "
        "open('/proc/self/status').read().split('Threads:')[1].split()[0])"
    )
    out = subprocess.run(
        [sys.executable, "-c", probe],
        capture_output=True,
        text=True,
        env=env,
        timeout=60,
        check=True,
    )
    setting, threads = out.stdout.split()
    assert setting == (preset or "1")
    # OpenBLAS caps its pool at the cores: with "3" the process has more than one thread
    assert (int(threads) == 1) == (preset is None)


def test_the_readme_tour_shows_what_campar_point_prints(capsys):
    """The README's first example is this kernel's output, character for character (it
    went stale once: 209 steps in the README where the DOP853 kernel takes 233)."""
    from pathlib import Path

    readme = (Path(__file__).parents[1] / "README.md").read_text().splitlines()
    start = readme.index("$ campar point --omega 3") + 1
    shown = []
    for line in readme[start:]:
        if line.startswith(("$ ", "```")):
            break
        shown.append(line)
    out = call_campar(capsys, "point", "--omega", "3")
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines() == shown


@pytest.mark.process
def test_the_program_spares_its_exit_the_collector_but_a_call_from_python_does_not():
    """`campar …` freezes the garbage collector once its work is over (its exit would
    otherwise walk everything numba built: ~0.5 s after a cold compile, ~0.1 s warm);
    main() called from Python leaves the caller's collector alone."""
    probe = (
        "import gc, sys\n"
        "from campar.cli import main\n"
        "code = main(['status', sys.argv[1]])\n"
        "print(code, gc.get_freeze_count())\n"
        "sys.argv = ['campar', 'status', sys.argv[1]]\n"
        "code = main()\n"
        "print(code, gc.get_freeze_count() > 0)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", probe, "/nonexistent/s.zarr"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    (code_a, frozen_a), (code_b, frozen_b) = (line.split() for line in out.stdout.splitlines())
    assert code_a == code_b != "0"  # a store that is not there: refused, alike both ways
    assert frozen_a == "0" and frozen_b == "True"
