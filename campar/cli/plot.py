"""``campar plot``: figures of a result store."""

from ..errors import JobError


def add_plot(sub):
    from ..views.plot import STORE_VIEWS, parse_range  # cheap: matplotlib loads only to draw

    p = sub.add_parser(
        "plot", help="draw a map of a result store (n-p labels, duty cycle, …), or compare two"
    )
    p.add_argument(
        "stores",
        nargs="+",
        metavar="STORE",
        help="result store of `campar run` "
        "(Zarr directory or HDF5 file); two stores of one grid: their maps side "
        "by side, or with --diff the cells whose labels differ",
    )
    p.add_argument(
        "--what",
        choices=STORE_VIEWS,
        default="labels",
        help="default: n-p labels (of a basin store: the basin); n, p: period and "
        "detachments of the periodic cells; multistability: how many attractors "
        "coexist, attractor_sets: which (census stores)",
    )
    p.add_argument(
        "--diff",
        action="store_true",
        help="with two stores: one map of the cells whose n-p labels differ",
    )
    p.add_argument(
        "-o",
        "--output",
        metavar="FILE",
        help="image; format from the suffix "
        "(.png, .pdf, .svg); default STORE-WHAT.png here (with --bifurcations "
        "--json: no image unless given)",
    )
    p.add_argument("--omega", metavar="A:B", type=parse_range, help="zoom to ω in [A, B]")
    p.add_argument(
        "--second", metavar="C:D", type=parse_range, help="zoom to the second parameter in [C, D]"
    )
    p.add_argument(
        "--direction",
        choices=("down", "up"),
        help="of a store of a "
        "chains.direction: both job, the direction to draw (default down); "
        "--what hysteresis compares the two",
    )
    p.add_argument(
        "--bifurcations",
        action="store_true",
        help="overlay every boundary between labels as a cell edge typed PD, SN, "
        "NS, G, chaos or jump (from the stored multipliers and ε extremes)",
    )
    p.add_argument(
        "--curves",
        action="store_true",
        help="overlay the continued bifurcation "
        "curves campar curves stored beside the map (STORE-curves.zarr)",
    )
    p.add_argument(
        "--trace",
        action="store_true",
        help="with --bifurcations: tell grazing "
        "from the orbits traced from the stored states (loads the kernel)",
    )
    p.add_argument(
        "--shoot",
        action="store_true",
        help="with --bifurcations: type the edges "
        "still unknown between periodic cells by shooting (both cycles by Newton on Pⁿ, "
        "continued across the edge)",
    )
    p.add_argument(
        "--json",
        action="store_true",
        help="with --bifurcations: print one "
        "JSON object: counts per type, each typed segment and its evidence",
    )
    p.set_defaults(handler=run_plot)


def run_plot(args) -> int:
    from ..views.plot import plot_store

    if len(args.stores) > 2:
        raise JobError(f"plot draws one store or compares two, got {len(args.stores)}")
    if (args.json or args.trace or args.shoot) and not args.bifurcations:
        raise JobError("--json, --trace and --shoot go with --bifurcations")
    if len(args.stores) == 2:
        return run_compare(args)
    if args.diff:
        raise JobError("--diff compares two stores: campar plot A B --diff")
    (store,) = args.stores
    found = None
    if args.bifurcations:
        from ..views.boundaries import store_boundaries
        from ..views.output import figure_file

        if args.output:
            figure_file(args.output)  # before typing the boundaries
        found = store_boundaries(
            store,
            omega=args.omega,
            second=args.second,
            trace=args.trace,
            direction=args.direction,
            shoot=args.shoot,
        )
    continued = None
    if args.curves:
        from ..views.map_curves import read_curves

        continued = read_curves(store)
    path = None
    if not args.json or args.output:  # --json prints the curves; an image only if asked
        path = plot_store(
            store,
            args.what,
            args.output,
            omega=args.omega,
            second=args.second,
            curves=found,
            direction=args.direction,
            continued=continued,
        )
    if args.json:
        import json

        print(json.dumps({**found.to_dict(), "figure": None if path is None else str(path)}))
    else:
        if found is not None:
            from ..views.boundaries import describe_boundaries

            print(describe_boundaries(found, limit=0))
        print(f"wrote {path}")
    return 0


def run_compare(args) -> int:
    from ..views.plot import plot_compare

    if args.bifurcations:
        raise JobError("--bifurcations draws one store's curves: plot the stores one by one")
    a, b = args.stores
    zoom = {"omega": args.omega, "second": args.second, "direction": args.direction}
    result = plot_compare(a, b, args.what, args.output, difference=args.diff, **zoom)
    if args.diff:
        share = result.differ / max(result.compared, 1)
        print(
            f"{result.differ} of {result.compared} cells computed in both differ in their "
            f"labels ({100 * share:.2g} %)"
        )
    print(f"wrote {result.figure}")
    return 0


def add_separation(sub):
    p = sub.add_parser(
        "separation",
        help="separation speed of each row of stores made with the "
        "separation output, several laws on one plot (docs/design.md)",
    )
    p.add_argument("stores", nargs="+", metavar="STORE", help="result stores (one curve each)")
    p.add_argument("--plot", metavar="FILE.png", help="draw the curves into this figure")
    p.set_defaults(handler=run_separation)


def run_separation(args) -> int:
    from ..views.separation import describe_curves, separation_curve

    if args.plot:
        from ..views.output import figure_file

        figure_file(args.plot)  # before reading the stores
    curves = [separation_curve(store) for store in args.stores]
    print(describe_curves(curves))
    if args.plot:
        from ..views.plot.design import plot_separation
        from ..views.plot.style import save_figure

        print(f"wrote {save_figure(plot_separation(curves), args.plot)}")
    return 0
