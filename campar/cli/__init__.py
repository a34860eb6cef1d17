"""The ``campar`` command: argument parsing and dispatch only.

One module per command family (``point``, ``line``, ``maps``: run, status and verify;
``plot``; ``paper``: gallery and report; ``tools``: warm-up and bench), each with an
``add_<name>(subparsers)`` function per command that registers its parser and sets
``handler`` to a function that calls the module owning the logic, so every behaviour is
reachable from Python without the CLI. ``options`` holds the flags several commands
share (the model's parameters and options), defined once.

May import every layer of campar (it is the top one).
"""

import os
import sys

from ..sweep.signals import guard_program

# The program (the ``campar`` script, or ``python -m campar.cli``), not a library importing
# this package: from this first line on a stop signal is one line, never a traceback.
MAIN_FILE = os.path.basename(getattr(sys.modules.get("__main__"), "__file__", None) or "")
if MAIN_FILE == "campar" or sys.orig_argv[1:3] == ["-m", "campar.cli"]:
    guard_program()

import argparse  # noqa: E402
import contextlib  # noqa: E402
import difflib  # noqa: E402
import gc  # noqa: E402
import re  # noqa: E402

# Before numpy is imported: one OpenBLAS thread. campar's work runs on its own threads and
# ranks, and BLAS only ever sees tiny matrices; numpy's and SciPy's OpenBLAS pools (SciPy
# comes with numba's BLAS check) spin idle after their start, CPU of every process taken
# from the kernel's cores (benchmarks/RESULTS.md). The caller's setting wins.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from .. import __version__  # noqa: E402
from ..errors import CamparError, Interrupted, JobError  # noqa: E402
from . import continuation, explore, line, maps, paper, plot, point, tools  # noqa: E402
from .options import launched_rank  # noqa: E402

# The subcommands, in the order ``campar --help`` lists them.
SUBCOMMANDS = [
    point.add_point,
    plot.add_plot,
    plot.add_separation,
    maps.add_run,
    maps.add_status,
    maps.add_verify,
    tools.add_warm_up,
    tools.add_bench,
    line.add_line,
    continuation.add_continue,
    continuation.add_curves,
    paper.add_gallery,
    paper.add_report,
    explore.add_explore,
]


class CommandParser(argparse.ArgumentParser):
    """argparse's parser without abbreviated flags (``--mu`` is not ``--mu-kn``: a flag added
    later would change what an abbreviation means), naming the closest command or flag
    when one is misspelled."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)

    def error(self, message):
        choice = re.match(r"argument \S+: invalid choice: '([^']*)' \(choose from (.*)\)", message)
        if choice:
            choices = [c.strip("'") for c in choice.group(2).split(", ")]
            message += did_you_mean(choice.group(1), choices)
        super().error(message)


def did_you_mean(word: str, candidates) -> str:
    """ " (did you mean --mu-kn?)": the candidates that begin with ``word`` (an abbreviation),
    else the closest to it; "" if none is close."""
    candidates = list(candidates)
    close = [c for c in candidates if c.startswith(word)][:3]
    close = close or difflib.get_close_matches(word, candidates, n=2, cutoff=0.75)
    return f" (did you mean {' or '.join(close)}?)" if close else ""


def build_parser() -> argparse.ArgumentParser:
    parser = CommandParser(
        prog="campar",
        description="Two-parameter bifurcation maps of the cam–follower impact oscillator.",
    )
    parser.add_argument("--version", action="version", version=f"campar {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for add in SUBCOMMANDS:
        add(sub)
    return parser


def parse_arguments(parser: argparse.ArgumentParser, argv) -> argparse.Namespace:
    """``parser.parse_args``, but an unknown flag is reported by its command's parser (its
    usage, and the flag it may have meant) instead of the top-level usage."""
    args, unknown = parser.parse_known_args(argv)
    if unknown:
        command = command_parser(parser, args.command)
        flags = [f for p in nested_parsers(command) for a in p._actions for f in a.option_strings]
        hints = "".join(did_you_mean(u, flags) for u in unknown if u.startswith("-"))
        command.error(f"unrecognized arguments: {' '.join(unknown)}{hints}")
    return args


def command_parser(parser: argparse.ArgumentParser, name: str) -> argparse.ArgumentParser:
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return sub.choices[name]


def nested_parsers(parser: argparse.ArgumentParser):
    """The parser and those of its subcommands (``campar bench NAME``), depth first."""
    yield parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in action.choices.values():
                yield from nested_parsers(child)


def main(argv=None) -> int:
    """The program (``argv`` None: a stop signal after the work is done is ignored), or a
    command from Python (``argv`` a list: the caller's signal handlers are restored)."""
    from ..sweep.signals import finished, guard_start, restore_signals

    saved = guard_start()  # a stop signal from here on: one line, never a traceback
    command = "campar"
    try:
        args = parse_arguments(build_parser(), argv)
        command = f"campar {args.command}"
        code = int(args.handler(args) or 0)
    except CamparError as exc:
        if not repeated_by_other_rank(exc):
            print(f"{command}: {exc}", file=sys.stderr)
        return exc.exit_code
    except BrokenPipeError:  # `campar status S | head`: the reader left
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    finally:
        if argv is not None:
            restore_signals(saved)
        else:  # the program: its work is over, its exit code decided
            finished()
            # Nothing left to collect that matters: spare the exit the collector's passes
            # over all the program built (after a cold compile, numba's IR).
            gc.freeze()
    if argv is None and code == 0 and args.command in LEAVE_AT_ONCE and alone():
        leave(code)
    return code


# Commands whose program ends without the interpreter's teardown once they succeed: all
# their work is done and every file closed by then (``leave``).
LEAVE_AT_ONCE = ("run",)


def observed() -> bool:
    """Whether a tracer or profiler watches the program (coverage, cProfile): it writes what
    it gathered at the interpreter's exit, which ``leave`` would skip."""
    return sys.gettrace() is not None or sys.getprofile() is not None


def alone() -> bool:
    """Whether the program may leave at once: no tracer or profiler watches it and it is no
    rank of a parallel run — under mpirun the ranks end through the interpreter's exit,
    which finalizes MPI after every rank's last message (a rank gone at once can take the
    other ranks' run down with it)."""
    mpi = sys.modules.get("mpi4py.MPI")
    parallel = mpi is not None and mpi.Is_initialized() and mpi.COMM_WORLD.Get_size() > 1
    return not observed() and not parallel


def leave(code: int) -> None:
    """End the program now with ``code``, its work done and its store closed: what the
    interpreter's exit would do that matters — log handlers flushed and closed, MPI
    finalized where a one-rank run initialized it, the standard streams flushed — then
    ``os._exit``, without tearing down every module and object the program built
    (numba's compiled code, and zarr's event loop and threads where the run read its store
    through zarr), the larger part
    of a run's exit (benchmarks/RESULTS.md, "Start-up")."""
    import logging

    logging.shutdown()
    mpi = sys.modules.get("mpi4py.MPI")
    if mpi is not None and mpi.Is_initialized() and not mpi.Is_finalized():
        mpi.Finalize()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError):  # a reader that left, a closed stream
            stream.flush()
    os._exit(code)


def repeated_by_other_rank(exc: CamparError) -> bool:
    """Under mpirun, an error every rank meets alike (the job, a signal before the start) or
    one the master reports: printed by rank 0 only."""
    alike = isinstance(exc, (JobError, Interrupted)) or getattr(exc, "rank", 0)
    return launched_rank() > 0 and bool(alike)
