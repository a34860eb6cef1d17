"""``campar run``, ``status`` and ``verify``: a job's map in its store."""

import argparse

RUN_EPILOG = """\
resuming:
  A run stopped by a signal (SIGTERM, SIGINT, SIGUSR1: Ctrl-C, a SLURM time limit),
  a crash or a lost node keeps every tile it committed. Run the same command again
  and it computes only the tiles not yet done (and any that fail their checksum).
  A store that holds another job is refused, unless --overwrite.

exit codes:
  0 the map is complete; 2 bad job file, --set or arguments (nothing written);
  1 a tile failed twice; 3 store refused (another job, locked); 65 store damaged;
  74 I/O error; 75 interrupted by a signal: run the same command again to resume.
"""


def seconds(text: str) -> float:
    """A duration flag: a finite number ≥ 0 (argparse says what is wrong in one line)."""
    import math

    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"must be a finite number of seconds ≥ 0, got {text}")
    return value


def add_run(sub):
    p = sub.add_parser(
        "run",
        help="compute a job's map into its store (resumes; MPI under mpirun)",
        description="Compute a job's map into its store: serially, or with every rank\n"
        "computing under mpirun (rank 0 hands out tiles and commits them).",
        epilog=RUN_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("job", help="job file (YAML), or a store: resume it with its own job")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="change one key of the job, e.g. sweep.omega.points=200 or "
        "model.tensile=allow (repeatable; validated as the file is)",
    )
    p.add_argument(
        "--dry-run",
        action="store_true",
        help="print cells, tiles, store size, "
        "memory per rank and an estimated time (a few of its chains timed); "
        "write nothing",
    )
    p.add_argument(
        "--ranks", type=int, metavar="N", help="with --dry-run: plan for N MPI ranks (1)"
    )
    p.add_argument("--store", metavar="PATH", help="result store (default: the job's store:)")
    p.add_argument("--overwrite", action="store_true", help="replace a store of another job")
    p.add_argument(
        "--grace",
        type=seconds,
        default=30.0,
        metavar="SECONDS",
        help="after a signal, wait so long for tiles in flight (30)",
    )
    from ..sweep.budget import DEFAULT_MAX_MEMORY, DEFAULT_MAX_STORE, format_size, parse_size

    store, memory = format_size(DEFAULT_MAX_STORE), format_size(DEFAULT_MAX_MEMORY)
    p.add_argument(
        "--max-store",
        type=parse_size,
        metavar="SIZE",
        help=f"refuse a job whose store exceeds SIZE unpacked ({store})",
    )
    p.add_argument(
        "--max-memory",
        type=parse_size,
        metavar="SIZE",
        help=f"refuse a job whose ranks each need over SIZE ({memory})",
    )
    p.set_defaults(handler=run_run)


def run_run(args) -> int:
    from ..api import forecast, job_of, run
    from ..errors import JobError
    from ..sweep.overrides import parse_assignment

    if args.ranks is not None and not args.dry_run:
        raise JobError(
            f"--ranks {args.ranks} plans a run with --dry-run; a run takes its ranks from "
            f"mpirun: mpirun -n {args.ranks} campar run {args.job}"
        )
    job = job_of(args.job, dict(map(parse_assignment, args.set)))  # before the disk is touched
    limits = dict(max_store=args.max_store, max_memory=args.max_memory)
    if args.dry_run:
        ranks = 1 if args.ranks is None else args.ranks
        plan = forecast(job, store=args.store, ranks=ranks, overwrite=args.overwrite, **limits)
        print(plan.describe())
        return 0
    from ..sweep.runner import setup_logging
    from ..sweep.signals import finished

    setup_logging()
    run(job, store=args.store, overwrite=args.overwrite, grace=args.grace, **limits)
    finished()  # the map is complete: a signal now changes nothing
    return 0


def add_status(sub):
    p = sub.add_parser("status", help="how far a store has got: tiles, cells, failures, runs")
    p.add_argument("store", help="result store (Zarr directory or HDF5 file)")
    p.set_defaults(handler=run_status)


def run_status(args) -> int:
    from ..sweep.progress import describe
    from ..sweep.store import read_store

    with read_store(args.store) as reader:
        print(describe(reader))
    return 0


def add_verify(sub):
    p = sub.add_parser(
        "verify",
        help="read every committed tile back and check its checksum; "
        "lists damaged tiles (exit 65 if any)",
    )
    p.add_argument("store", help="result store (Zarr directory or HDF5 file)")
    p.add_argument(
        "--adopt",
        action="store_true",
        help="adopt a store written before root records: check it against its job, rewrite "
        "its metadata from the job, leave damaged tiles pending, write its root record "
        "(docs/restart.md)",
    )
    p.set_defaults(handler=run_verify)


def run_verify(args) -> int:
    from ..errors import StoreDamaged
    from ..sweep.progress import adopt_report, verify_report

    text, intact = (adopt_report if args.adopt else verify_report)(args.store)
    print(text)
    return 0 if intact else StoreDamaged.exit_code
