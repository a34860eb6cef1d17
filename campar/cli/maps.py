"""``campar run``, ``status`` and ``verify``: a job's map in its store."""


def add_run(sub):
    p = sub.add_parser("run", help="compute a job's map into its store (resumes; MPI under mpirun)")
    p.add_argument("job", help="job file (YAML)")
    p.add_argument("--store", metavar="PATH", help="result store (default: the job's store:)")
    p.add_argument("--overwrite", action="store_true", help="replace a store of another job")
    p.add_argument("--grace", type=float, default=30.0, metavar="SECONDS",
                   help="after a signal, wait so long for tiles in flight (30)")  # fmt: skip
    from ..sweep.budget import DEFAULT_MAX_MEMORY, DEFAULT_MAX_STORE, format_size, parse_size

    store, memory = format_size(DEFAULT_MAX_STORE), format_size(DEFAULT_MAX_MEMORY)
    p.add_argument("--max-store", type=parse_size, metavar="SIZE",
                   help=f"refuse a job whose store exceeds SIZE unpacked ({store})")  # fmt: skip
    p.add_argument("--max-memory", type=parse_size, metavar="SIZE",
                   help=f"refuse a job whose ranks each need over SIZE ({memory})")  # fmt: skip
    p.set_defaults(handler=run_run)


def run_run(args) -> int:
    from ..sweep.job import load_job

    job = load_job(args.job)  # before anything touches the disk
    from ..sweep.runner import run_job, setup_logging
    from ..sweep.signals import finished

    setup_logging()
    limits = dict(max_store=args.max_store, max_memory=args.max_memory)
    run_job(job, args.store, overwrite=args.overwrite, grace=args.grace, **limits)
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
    p = sub.add_parser("verify", help="read every committed tile back and check its checksum; "
                       "lists damaged tiles (exit 65 if any)")  # fmt: skip
    p.add_argument("store", help="result store (Zarr directory or HDF5 file)")
    p.set_defaults(handler=run_verify)


def run_verify(args) -> int:
    from ..errors import StoreDamaged
    from ..sweep.progress import verify_report

    text, intact = verify_report(args.store)
    print(text)
    return 0 if intact else StoreDamaged.exit_code
