"""Signals over a run's whole life: before it starts, while it runs, after it ends.

SIGTERM, SIGINT and SIGUSR1 (what SLURM and mpich's mpirun send) mean "stop":

- from the first line of the ``campar`` program (``campar.cli``, before it imports
  anything else: ``guard_program``) until ``campar.cli.main`` runs, a stop signal
  ends the process at once with that one line (nothing is open yet);
- before the run's own handlers are installed (imports, reading the job,
  opening the store, starting MPI), ``guard_start`` turns them into
  ``Interrupted("interrupted before start")`` — one line, exit 130 for SIGINT
  (a Ctrl-C), 143 for SIGTERM and 75 for SIGUSR1 (resumable: what SLURM's
  requeue looks for, ``slurm/campar.sbatch``), nothing computed. Under a launcher of
  several ranks a rank must not leave early on its own (the others would wait
  in MPI_Init for ever, measured with mpich): there the signal is kept, and the
  run's ``Signals`` starts with it, so all ranks stop together (exit 75);
- while the run holds its store, ``Signals`` only counts them: the runner stops
  handing out tiles, collects or abandons those in flight, logs and exits 75;
- once the run has finished its work (``finished()``), they are ignored: the
  process is only leaving, and its exit code says what the run did.

Only the main thread receives Python signal handlers, and only there are they
installed (a library caller's threads are left alone). Before Python has run
campar's first line the interpreter's own handling applies: its start-up and
its ``site`` module (with an editable install, setuptools' finder) take
a fraction of a second (docs/stores.md), and a SIGINT there ends Python with its
own KeyboardInterrupt message; nothing of campar is running then.
"""

import os
import signal
import threading
import time

from ..errors import Interrupted

SIGNALS = (signal.SIGTERM, signal.SIGINT, signal.SIGUSR1)
INSIST_SECONDS = 1.0
# Before a run starts: 128 + the signal, as a shell reports it, for SIGINT (a Ctrl-C) and
# SIGTERM (`kill`); SIGUSR1, SLURM's warning, is 75: resumable, what the requeue looks for
EXIT_CODES = {signal.SIGINT: 130, signal.SIGTERM: 143}

MPI_SIZE_ENV = ("PMI_SIZE", "OMPI_COMM_WORLD_SIZE", "PMIX_SIZE")  # set by MPI launchers

_phase = {"now": "idle"}  # idle (a library caller) | starting | running | finished
_kept: list[tuple[int, float]] = []  # (signal, when) received before the start, under MPI


def guard_start() -> dict:
    """From now until a run installs ``Signals``: a stop signal ends the process with one
    line (``Interrupted``), whatever it was doing (the CLI calls this first). Returns the
    handlers it replaced (for ``restore_signals``)."""
    if threading.current_thread() is not threading.main_thread():
        return {}
    if _phase["now"] != "starting":  # kept by ``guard_program`` since the program's start
        _kept.clear()
    _phase["now"] = "starting"
    return {sig: signal.signal(sig, _before_start) for sig in SIGNALS}


def guard_program() -> None:
    """The ``campar`` program's first line: a stop signal before ``main`` runs (while the
    command's modules import) ends the process with one line, at once; under a launcher
    of several ranks it is kept for the run, as ``guard_start`` keeps it."""
    if threading.current_thread() is threading.main_thread():
        _phase["now"] = "starting"
        for sig in SIGNALS:
            signal.signal(sig, _before_main)


def _before_main(signum, frame):
    if _ranks() > 1:
        _kept.append((signum, time.monotonic()))
        return
    text = str(early_interruption(signum))
    os.write(2, f"campar: {text}\n".encode())
    os._exit(EXIT_CODES.get(signum, Interrupted.exit_code))  # nothing is open yet


def _ranks() -> int:
    for name in MPI_SIZE_ENV:
        if os.environ.get(name, "").isdigit():
            return int(os.environ[name])
    return 1


def restore_signals(saved: dict) -> None:
    """Put back the handlers ``guard_start`` replaced (a caller of ``campar.cli.main``)."""
    _phase["now"] = "idle"
    for sig, handler in saved.items():
        signal.signal(sig, handler)


def finished() -> None:
    """The run's work is done (complete, or stopped and logged): later signals are ignored."""
    _phase["now"] = "finished"
    if threading.current_thread() is threading.main_thread():
        for sig in SIGNALS:
            signal.signal(sig, signal.SIG_IGN)


def _before_start(signum, frame):
    if _phase["now"] != "starting":
        return  # a run took over, or has finished: nothing to interrupt
    if _ranks() > 1:
        _kept.append((signum, time.monotonic()))  # for the run's Signals: all ranks stop
        return
    _phase["now"] = "interrupted"  # one exception, even if the signal comes twice
    raise early_interruption(signum)


def early_interruption(signum: int) -> Interrupted:
    """What a stop signal before the run's start raises (or, under MPI, the run once every
    rank has stopped): exit 130 for SIGINT, 143 for SIGTERM, 75 for SIGUSR1."""
    return Interrupted(
        f"interrupted before start by {signal.Signals(signum).name}: no tile was computed; "
        "run the same command again",
        EXIT_CODES.get(signum, Interrupted.exit_code),
    )


class Signals:
    """While installed, SIGTERM/SIGINT/SIGUSR1 only count (``count``, ``last``)."""

    def __init__(self):
        self.count, self.last, self.first_at, self.last_at, self._old = 0, None, 0.0, 0.0, {}
        self.early = False  # the first signal came before the start (kept under MPI)

    def _handle(self, signum, frame):
        self.count += 1
        self.last, self.last_at = signum, time.monotonic()
        if self.count == 1:
            self.first_at = self.last_at

    @property
    def insist(self) -> bool:
        """A second signal a while after the first: abandon now. (A terminal's Ctrl-C can
        reach a rank twice at once, from the terminal and from mpirun.)"""
        return self.count >= 2 and self.last_at - self.first_at > INSIST_SECONDS

    def __enter__(self):
        if _phase["now"] == "starting":
            _phase["now"] = "running"
            for signum, when in _kept:  # received before the start, under MPI
                self.count, self.early = self.count + 1, True
                self.last, self.last_at = signum, when
                self.first_at = self.first_at or when
            _kept.clear()
        for sig in SIGNALS:
            self._old[sig] = signal.signal(sig, self._handle)
        return self

    def __exit__(self, *exc):
        for sig, old in self._old.items():
            signal.signal(sig, old)
