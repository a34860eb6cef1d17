"""``campar plot``: figures of a result store."""

from ..errors import JobError


def add_plot(sub):
    from ..views.plot import STORE_VIEWS, parse_range  # cheap: matplotlib loads only to draw

    p = sub.add_parser("plot", help="draw a map of a result store (n-p labels, duty cycle, …)")
    p.add_argument("store", help="result store of `campar run` (Zarr directory or HDF5 file)")
    p.add_argument("--what", choices=STORE_VIEWS, default="labels",
                   help="default: n-p labels (of a basin store: the basin)")  # fmt: skip
    p.add_argument("-o", "--output", metavar="FILE", help="image; format from the suffix "
                   "(.png, .pdf, .svg); default STORE-WHAT.png here")  # fmt: skip
    p.add_argument("--omega", metavar="A:B", type=parse_range, help="zoom to ω in [A, B]")
    p.add_argument("--second", metavar="C:D", type=parse_range,
                   help="zoom to the second parameter in [C, D]")  # fmt: skip
    p.add_argument("--direction", choices=("down", "up"), help="of a store of a "
                   "chains.direction: both job, the direction to draw (default down); "
                   "--what hysteresis compares the two")  # fmt: skip
    p.add_argument("--bifurcations", action="store_true",
                   help="overlay every boundary between labels as a cell edge typed PD, SN, "
                   "NS, G, chaos or jump (from the stored multipliers and ε extremes)")  # fmt: skip
    p.add_argument("--trace", action="store_true", help="with --bifurcations: tell grazing "
                   "from the orbits traced from the stored states (loads the kernel)")  # fmt: skip
    p.add_argument("--json", action="store_true", help="with --bifurcations: print one "
                   "JSON object: counts per type, each typed segment and its evidence")  # fmt: skip
    p.set_defaults(handler=run_plot)


def run_plot(args) -> int:
    from ..views.plot import plot_store

    if (args.json or args.trace) and not args.bifurcations:
        raise JobError("--json and --trace go with --bifurcations")
    found = None
    if args.bifurcations:
        from ..views.boundaries import store_boundaries
        from ..views.output import figure_file

        if args.output:
            figure_file(args.output)  # before typing the boundaries
        found = store_boundaries(args.store, omega=args.omega, second=args.second,
                                 trace=args.trace, direction=args.direction)  # fmt: skip
    path = plot_store(args.store, args.what, args.output, omega=args.omega, second=args.second,
                      curves=found, direction=args.direction)  # fmt: skip
    if args.json:
        import json

        print(json.dumps({**found.to_dict(), "figure": str(path)}))
    else:
        if found is not None:
            from ..views.boundaries import describe_boundaries

            print(describe_boundaries(found, limit=0))
        print(f"wrote {path}")
    return 0
