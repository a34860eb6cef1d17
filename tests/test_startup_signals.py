"""Stop signals while campar starts: from the program's first line on, a SIGINT or SIGTERM is
one line and exit 130 or 75, serial or under ``mpirun -n 2`` (every rank stops together),
never a traceback, never a rank dying of a signal. What remains before campar's first line is
Python's own start-up (docs/stores.md measures it)."""

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from support.processes import (
    MPIRUN,
    campar_processes,
    start_campar,
    subprocess_env,
    wait_for_tiles,
    wait_until_guarded,
)

from campar.sweep.store import read_store

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
@pytest.mark.process
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
@pytest.mark.process
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


def assert_one_line_stop_or_done(code: int, err: str, store: Path, tiles: int) -> str:
    """What a group SIGINT to a starting run may correctly give, by when it lands: before
    the run's start, one "interrupted before start" line (exit 130, or 75 once the ranks
    agree to stop); while it runs, one "stopped by SIGINT with k of N tiles pending" line
    (exit 75, or mpirun's own 130 for a Ctrl-C); after its last tile, a complete map (exit
    0). Never a traceback or a rank killed by a signal. Returns which it was."""
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert "BAD TERMINATION" not in err and "signal 11" not in err.lower(), err
    if code == 0:
        with read_store(store) as reader:
            assert reader.done.all(), err
        return "complete"
    assert code in (75, 130), err
    said = [line for line in err.splitlines() if "run the same command again" in line]
    assert len(said) == 1, err  # once, whatever the ranks
    if "interrupted before start by SIGINT" in said[0]:
        return "before start"
    stopped = re.search(r"stopped by SIGINT with (\d+) of (\d+) tiles pending", said[0])
    assert stopped, err
    assert 1 <= int(stopped[1]) <= int(stopped[2]) == tiles, err
    return "running"


@pytest.mark.mpi
@pytest.mark.slow
@pytest.mark.parametrize(
    "moment,after",
    [("guarded", 0.0), ("guarded", 0.15), ("guarded", 0.4), ("first tile", 0.0)],
    ids=["guarded", "guarded+0.15", "guarded+0.4", "first-tile"],
)
@pytest.mark.process
def test_a_group_sigint_during_start_up_under_mpirun_is_one_line_no_crash(write_job, moment, after):
    """A terminal's Ctrl-C (to mpirun and both ranks) once both ranks run campar's first
    line, a moment later (imports, MPI start, the kernel, the store: where it lands depends
    on the machine's speed, so every correct outcome is accepted), and once the first tile
    is stored (the run is running: it must say how many tiles are pending)."""
    path, job = write_job(slow=True)
    proc = start_campar("run", path, launcher=[MPIRUN, "-n", "2"])
    if moment == "first tile":
        wait_for_tiles(job.store, 1, proc)
    else:
        wait_until_guarded(proc, ranks=2)
        assert proc.poll() is None and len(campar_processes(proc.pid)) == 2
    time.sleep(after)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=180)
    outcome = assert_one_line_stop_or_done(proc.returncode, err, job.store, 6)
    if moment == "first tile":
        assert outcome in ("running", "complete"), err


@pytest.mark.process
def test_the_program_guard_is_not_installed_by_importing_the_cli():
    code = (
        "import signal, campar.cli\n"
        "print(signal.getsignal(signal.SIGUSR1) == signal.SIG_DFL)"
    )  # a library that imports campar.cli keeps its own signal handling
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "True"
