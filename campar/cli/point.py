"""``campar point``: one cell, its classification, its cycle, its attractors; or a stored
cell of a map reproduced (``--from``)."""

from ..errors import JobError
from .options import add_model_fields, add_parameter_arguments, model_of, parameter_values
from .point_output import format_cycle, format_point, run_attractors, save_orbit


def add_point(sub):
    p = sub.add_parser(
        "point",
        help="simulate one cell and classify its steady motion",
        description="One cell of the model: every key of a job's model is a flag (or "
        "--set KEY=VALUE, or --job FILE for a job's model). With --from STORE the cell "
        "of a map's store nearest the coordinates given (its axes by name, e.g. --omega "
        "--mu-cn) is computed again from its store's model and checked against every "
        "value the store holds for it.",
    )
    p.add_argument("--omega", type=float, help="cam speed / natural frequency")
    add_parameter_arguments(p)
    add_model_fields(p)
    p.add_argument("--multipliers", action="store_true", help="Floquet multipliers")
    p.add_argument("--lyapunov", action="store_true", help="largest Lyapunov exponent")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="FILE.png", help="phase portrait, ε(t), Pn(t) and yc(t)")
    p.add_argument(
        "--attractors",
        type=int,
        metavar="K",
        help="run K starts (rest, --y0/--v0, a spread over a box of (y, y')) "
        "and list the distinct attractors with basin fractions",
    )
    p.add_argument(
        "--cycle",
        type=int,
        metavar="N",
        help="solve for the N-cycle by Newton's method on the section map, stable "
        "or not, from --y0/--v0 (or, from rest, the simulated cell's end state); "
        "its label, multipliers and stability",
    )
    p.add_argument(
        "--from",
        dest="store",
        metavar="STORE",
        help="the cell of this map's or basin's store nearest --omega and its second "
        "axis' flag (e.g. --mu-cn, --phi1; a basin's --y0 --v0): its model from the "
        "store, its values checked bit for bit against the stored ones",
    )
    p.add_argument(
        "--direction",
        choices=("down", "up"),
        help="with --from on a store of chains.direction both: which chain (down)",
    )
    p.add_argument(
        "--run-on",
        type=int,
        metavar="N",
        help="with --from: run the cell's motion on from its stored final state for up to "
        "N revolutions with no early chaos or quasi-periodic verdict, and say whether its "
        "label holds (a chaotic label may be a long transient's)",
    )
    p.add_argument(
        "--recompute",
        action="store_true",
        help="with --from on a store another kernel version wrote: compute with this "
        "campar's kernel and say which values changed",
    )
    p.set_defaults(handler=run_point)


def check_counts(args) -> None:
    """--cycle and --attractors within their bounds, before anything is computed."""
    from ..model.settings import MAX_COUNT, MAX_PERIOD, MAX_STARTS, check_count

    try:
        if args.cycle is not None:
            check_count("--cycle", args.cycle, 1, MAX_PERIOD)
        if args.attractors is not None:
            check_count("--attractors", args.attractors, 2, MAX_STARTS)
        if args.run_on is not None:
            check_count("--run-on", args.run_on, 1, MAX_COUNT)
    except ValueError as exc:
        raise JobError(str(exc)) from None
    if args.run_on is not None and (args.cycle is not None or args.attractors is not None):
        raise JobError("--run-on runs the cell's own motion on: without --cycle and --attractors")
    if args.cycle is not None and (args.plot or args.lyapunov):
        raise JobError("--cycle reports the cycle's multipliers: without --plot and --lyapunov")
    if args.attractors is not None and args.plot:
        raise JobError(
            "--plot draws one orbit: use it without --attractors, from an "
            "attractor's state (--y0 --v0)"
        )


def run_point(args) -> int:
    import json

    check_counts(args)
    if args.store is not None:
        from .point_from import run_from

        return run_from(args)
    if args.direction or args.recompute or args.run_on is not None:
        raise JobError(
            "--direction, --recompute and --run-on go with --from STORE (without it: "
            "--revolutions N --chaos-after 0 from --y0 --v0)"
        )
    if args.omega is None and not args.job:
        raise JobError("give --omega (or --from STORE, or --job FILE with a fixed omega)")
    model = model_of(args, omega=args.omega, **parameter_values(args))
    if args.attractors is not None:
        return run_attractors(args, model, model.start)
    if args.cycle is not None:
        return run_cycle(args, model, None if model.start == (0.0, 0.0) else model.start)
    if args.plot:
        from ..views.output import figure_file

        figure_file(args.plot)  # before computing
    from ..views.point import simulate_point

    result = simulate_point(
        model, multipliers=args.multipliers, lyapunov=args.lyapunov, trace=bool(args.plot)
    )
    print(json.dumps(result.to_dict()) if args.json else format_point(result))
    if args.plot:
        save_orbit(result, args.plot)
    return 0


def run_cycle(args, model, guess) -> int:
    """The ``--cycle`` orbit of ``model`` from ``guess`` (None: the simulated cell's end)."""
    import json

    from ..continuation.orbit import find_cycle
    from ..views.point import simulate_point

    if guess is None:  # from rest: the simulated cell's end state is the guess
        guess = simulate_point(model).state
    orbit = find_cycle(args.cycle, guess, model=model, **model.parameters)
    print(json.dumps(orbit.to_dict()) if args.json else format_cycle(orbit))
    return 0
