"""Stop signals while campar starts: from the program's first line on, a SIGINT or SIGTERM is
one line and exit 130 or 75, serial or under ``mpirun -n 2`` (every rank stops together),
never a traceback, never a rank dying of a signal. What remains before campar's first line is
Python's own start-up (docs/stores.md measures it)."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import (
    MPIRUN,
    campar_processes,
    start_campar,
    subprocess_env,
    wait_until_guarded,
)

# The ``campar`` program, as the console script runs it, with a stop signal sent to itself
# while campar's command module imports ``IMPORT`` (one of its first imports, or one of the
# heavy ones that follow): the moment the old program took for a Ctrl-C traceback.
PROGRAM = """
import builtins, os, signal, sys
sys.modules["__main__"].__file__ = os.path.join(os.path.dirname(sys.executable), "campar")
sys.argv = ["campar", *sys.argv[1:]]
real_import, sent = builtins.__import__, []
def hook(name, *args, **kwargs):
    if name == os.environ["IMPORT"] and not sent:
        sent.append(name)
        os.kill(os.getpid(), getattr(signal, os.environ["SIGNAL"]))
    return real_import(name, *args, **kwargs)
builtins.__import__ = hook
from campar.cli import main
sys.exit(main())
"""


def assert_one_line_stop(code: int, err: str, expected: tuple[int, ...]) -> None:
    assert code in expected, err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert "BAD TERMINATION" not in err and "signal 11" not in err.lower(), err
    said = [line for line in err.splitlines() if "run the same command again" in line]
    assert len(said) == 1 and "interrupted" in said[0], err  # once, whatever the ranks


@pytest.mark.parametrize("imported", ["argparse", "numpy"])
@pytest.mark.parametrize("signame,code", [("SIGINT", 130), ("SIGTERM", 143), ("SIGUSR1", 75)])
def test_a_signal_while_campar_imports_is_one_line(write_job, imported, signame, code):
    path, _ = write_job()
    env = {**subprocess_env(), "IMPORT": imported, "SIGNAL": signame}
    done = subprocess.run(
        [sys.executable, "-c", PROGRAM, "run", str(path)],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert_one_line_stop(done.returncode, done.stderr, (code,))
    assert not Path(write_job()[1].store).exists()  # nothing computed, nothing written


@pytest.mark.mpi
def test_a_signal_while_one_rank_imports_stops_every_rank_together(write_job):
    """Under mpirun the ranks keep the signal until the run starts (a rank leaving MPI_Init
    alone would leave the other waiting for ever); then every rank stops: exit 130 for the
    SIGINT that came before the start, said once."""
    path, job = write_job()
    env = {**subprocess_env(), "IMPORT": "argparse", "SIGNAL": "SIGINT"}
    done = subprocess.run(
        [str(MPIRUN), "-n", "2", sys.executable, "-c", PROGRAM, "run", str(path)],
        env=env,
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert_one_line_stop(done.returncode, done.stderr, (130,))


@pytest.mark.mpi
@pytest.mark.slow
@pytest.mark.parametrize("after", [0.0, 0.15, 0.4])
def test_a_group_sigint_during_start_up_under_mpirun_is_one_line_no_crash(write_job, after):
    """A terminal's Ctrl-C (to mpirun and both ranks) once both ranks run campar's first
    line, and a moment later (imports, MPI start, the kernel, the store): one line, exit 75
    or 130 (mpirun's own, for a Ctrl-C), no rank killed by a signal."""
    path, _ = write_job(slow=True)
    proc = start_campar("run", path, launcher=[MPIRUN, "-n", "2"])
    wait_until_guarded(proc, ranks=2)
    assert proc.poll() is None and len(campar_processes(proc.pid)) == 2
    time.sleep(after)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=180)
    assert_one_line_stop(proc.returncode, err, (75, 130))


def test_the_program_guard_is_not_installed_by_importing_the_cli():
    code = (
        "import signal, campar.cli\n"
        "print(signal.getsignal(signal.SIGUSR1) == signal.SIG_DFL)"
    )  # a library that imports campar.cli keeps its own signal handling
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "True"
