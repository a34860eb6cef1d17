"""``campar explore``: one or two stores in the browser, served on this machine."""

from ..errors import JobError

LOOPBACK = "127.0.0.1"
MAX_CELL_SECONDS = 86400.0  # a day: a longer computation belongs in a job, not a page


def add_explore(sub):
    p = sub.add_parser(
        "explore",
        help="explore one or two map stores in the browser: the map, a cell's orbit, a line",
    )
    p.add_argument("stores", nargs="+", metavar="STORE", help="a map's store (two: compare them)")
    p.add_argument("--port", type=int, default=0, help="the port (default: a free one)")
    p.add_argument(
        "--host",
        default=LOOPBACK,
        help=f"the interface to listen on ({LOOPBACK}: this machine only; another one lets "
        "other machines reach the stores and the computations)",
    )
    p.add_argument("--no-browser", action="store_true", help="print the URL, open no browser")
    p.add_argument(
        "--cell-seconds",
        type=float,
        default=60.0,
        help="time limit of one computation of the page (a cell, a line, a census) (60)",
    )
    p.add_argument(
        "--zoom-ranks",
        type=int,
        default=2,
        help="MPI ranks of a zoom too large for the warm runner (mpirun -n; 1: serial) (2)",
    )
    p.set_defaults(handler=run_explore)


def run_explore(args) -> int:
    import signal
    import threading
    import webbrowser

    from ..explore.server import serve, shutdown

    if len(args.stores) > 2:
        raise JobError(f"campar explore shows one or two stores, got {len(args.stores)}")
    if not 0 <= args.port <= 65535:
        raise JobError(f"--port must be in [0, 65535], got {args.port}")
    if not 0 < args.cell_seconds <= MAX_CELL_SECONDS:
        raise JobError(
            f"--cell-seconds must be in (0, {MAX_CELL_SECONDS}], got {args.cell_seconds}"
        )
    if not 1 <= args.zoom_ranks <= 1024:
        raise JobError(f"--zoom-ranks must be in [1, 1024], got {args.zoom_ranks}")
    try:
        server = serve(args.stores, args.host, args.port, args.cell_seconds)
        server.explorer.zoom_ranks = args.zoom_ranks
    except OSError as exc:
        raise JobError(f"cannot listen on {args.host}:{args.port}: {exc.strerror}") from None
    stop = threading.Event()
    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, lambda *_: stop.set())
    print(f"campar explore: serving {', '.join(args.stores)} at {server.url}", flush=True)
    if args.host != LOOPBACK:
        print(f"campar explore: listening on {args.host}: reachable from other machines")
    if not args.no_browser:
        webbrowser.open(server.url)
    try:
        stop.wait()
    finally:
        shutdown(server)
    return 0
