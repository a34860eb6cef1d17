"""``campar continue``: a branch of periodic orbits, its bifurcations, switching, curves."""

import argparse
import sys

from ..errors import JobError
from ..model.laws import LAW_PARAMETERS
from .options import (
    FIELD_DEST,
    PARAMETER_HELP,
    add_model_fields,
    flag_of,
    given_fields,
    launched_rank,
    model_of,
)

CONTINUATION_PARAMETERS = ("omega", "f0", "mu_kn", "mu_cn", "zeta")
HELP = {"omega": "cam speed / natural frequency", **PARAMETER_HELP}


def value_or_range(text: str):
    """A parameter flag's value: "0.91" → 0.91, "6:2" → (6.0, 2.0)."""
    try:
        parts = [float(part) for part in text.split(":")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number or A:B, got {text!r}") from None
    if len(parts) == 1:
        return parts[0]
    if len(parts) == 2:
        return tuple(parts)
    raise argparse.ArgumentTypeError(f"expected a number or A:B, got {text!r}")


def named_range(text: str):
    """--second's value: "mu_kn:0.7:0.95" → ("mu_kn", (0.7, 0.95))."""
    parts = text.split(":")
    try:
        if len(parts) != 3:
            raise ValueError
        return parts[0].replace("-", "_"), (float(parts[1]), float(parts[2]))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected NAME:A:B, got {text!r}") from None


def add_continue(sub):
    from ..sweep.job import PAPER_VALUES

    p = sub.add_parser(
        "continue",
        help="continue a periodic orbit along a parameter: stable and unstable cycles, "
        "PD/SN/NS/G points, branch switching, two-parameter curves",
        description="Simulate the cell at the start of the range (as campar point does), "
        "solve for its periodic orbit by Newton's method on the section map, and follow "
        "the orbit's branch by pseudo-arclength continuation through folds; PD, SN, BP, "
        "NS and G points are located to 1e-10 in the parameter. Exactly one parameter "
        "takes a range A:B (the branch starts at A): omega, f0, mu_kn, mu_cn, zeta, or a "
        "law parameter of the model (--phi1 … --phi4, --n, --restitution).",
    )
    p.add_argument(
        "--omega", type=value_or_range, required=True, metavar="W or A:B", help=HELP["omega"]
    )
    for name, value in PAPER_VALUES.items():
        p.add_argument(
            flag_of(name),
            type=value_or_range,
            metavar="X or A:B",
            help=f"{HELP[name]} ({value:g})",
        )
    add_model_fields(p)
    p.add_argument(
        "--cycle",
        type=int,
        metavar="N",
        help="the start cycle's period: Newton's method solves for an N-cycle from the "
        "simulated cell's state, stable or not (default: the period of the cycle the "
        "simulation reaches; the start cycle's label is the output's first line)",
    )
    p.add_argument(
        "--switch",
        type=int,
        default=0,
        metavar="DEPTH",
        help="follow period doublings DEPTH deep from every PD point (0)",
    )
    p.add_argument("--max-step", type=float, default=0.02, help="longest arclength step (0.02)")
    p.add_argument("--max-points", type=int, default=5000, help="points per branch (5000)")
    p.add_argument(
        "--curves",
        metavar="TYPES",
        help="continue the curves of these special points in a plane, e.g. PD,SN,G (with --second)",
    )
    p.add_argument(
        "--second",
        type=named_range,
        metavar="NAME:A:B",
        help="the curves' second parameter and its window LOW:HIGH inside the model's "
        "range, e.g. mu_kn:0.7:0.95 or phi1:1.0:1.1 (a law parameter, when the range is "
        "not one's) (with --curves)",
    )
    p.add_argument(
        "--line",
        type=int,
        metavar="POINTS",
        help="with -o and a range of omega: draw the brute-force bifurcation "
        "diagram (campar line, POINTS cells) beneath the branches",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument(
        "-o",
        "--output",
        metavar="FILE.png",
        help="the branches (stable solid, unstable dashed, special points "
        "marked); with --curves a second figure FILE-curves.png",
    )
    p.set_defaults(handler=run_continue)


def split_parameters(args) -> tuple[str, tuple[float, float], dict]:
    """(the parameter with a range, its range, the other parameters' values)."""
    values = {name: getattr(args, name) for name in CONTINUATION_PARAMETERS}
    values = {name: value for name, value in values.items() if value is not None}
    for key, text in given_fields(args).items():  # a law parameter's range: --phi1 0.9:1.3
        name = key.rsplit(".", 1)[-1]
        if name in LAW_PARAMETERS and ":" in text:
            values[name] = value_or_range(text)
            delattr(args, FIELD_DEST + key)
    ranged = [name for name, value in values.items() if isinstance(value, tuple)]
    if len(ranged) != 1:
        raise JobError(
            f"give exactly one parameter a range A:B (e.g. --omega 6:2), got {len(ranged)}"
        )
    name = ranged[0]
    fixed = {k: v for k, v in values.items() if k != name}
    return name, values[name], fixed


def run_continue(args) -> int:
    import json

    from ..continuation.branch import BranchSettings
    from ..model.settings import MAX_PERIOD, MAX_POINTS
    from ..views.continuation import continue_from_cell, describe_continuation

    parameter, span, fixed = split_parameters(args)
    model = model_of(args, **{**fixed, parameter: span[0]})
    fixed = {k: v for k, v in model.parameters.items() if k != parameter}
    if args.switch < 0:
        raise JobError(f"--switch must be ≥ 0, got {args.switch}")
    if args.cycle is not None and not 1 <= args.cycle <= MAX_PERIOD:
        raise JobError(f"--cycle must be from 1 to {MAX_PERIOD}, got {args.cycle}")
    if not 0.0 < args.max_step <= 1.0:
        raise JobError(f"--max-step must be in (0, 1], got {args.max_step}")
    if not 2 <= args.max_points <= MAX_POINTS:
        raise JobError(f"--max-points must be from 2 to {MAX_POINTS}, got {args.max_points}")
    if args.line is not None and (parameter != "omega" or not args.output):
        raise JobError(
            "--line draws campar line's diagram along omega: it needs a range of --omega and -o"
        )
    types = tuple(t.strip().upper() for t in args.curves.split(",")) if args.curves else ()
    second, window = args.second if args.second else (None, None)
    if args.output:
        from ..views.output import figure_file

        figure_file(args.output)  # before computing
    settings = BranchSettings(
        max_step=args.max_step, max_points=args.max_points, step=min(0.01, args.max_step)
    )
    result = continue_from_cell(
        parameter,
        span,
        fixed,
        y0=model.initial.y,
        v0=model.initial.v,
        cycle=args.cycle,
        switch=args.switch,
        model=model,
        settings=settings,
        curve_types=types,
        second=second,
        second_window=window,
    )
    print(json.dumps(result.to_dict()) if args.json else describe_continuation(result))
    for line in result.missing:  # asked for, not found: said on stderr, and in the JSON
        print(f"campar continue: {line}", file=sys.stderr)
    if args.output:
        draw(args, result, parameter, span, model)
    return 0


def draw(args, result, parameter, span, model) -> None:
    from pathlib import Path

    from ..views.plot.branches import plot_bifurcation_curves, plot_branches

    line = None
    if args.line:
        from ..views.line import compute_line, line_spec

        line = compute_line(line_spec(span, args.line, model), transitions=False)
    plot_branches(result.root, line=line).savefig(args.output, dpi=200)
    if args.curves:
        path = Path(args.output)
        curves = path.with_name(f"{path.stem}-curves{path.suffix}")
        if not result.curves:
            print(f"campar continue: {curves} not written: no curve found", file=sys.stderr)
            return
        window = (span, args.second[1])
        plot_bifurcation_curves(result.curves, window=window).savefig(curves, dpi=200)


def add_curves(sub):
    from ..sweep.curves_job import SEED_TYPES  # not the continuation: numba loads only to run
    from .maps import RUN_EPILOG, seconds

    p = sub.add_parser(
        "curves",
        help="continue a map's PD, SN and G curves, seeded from its typed edges (resumes; "
        "MPI under mpirun)",
        description="Seed bifurcation curves from a map store's typed edges (campar plot "
        "--bifurcations), group the seeds by curve and continue each group's curves across "
        "the map's window as a task of a curves job: run, checksummed, committed and "
        "resumed as a map's tiles are, serially or under mpirun. The curves go into a store "
        "beside the map (MAP-curves.zarr); campar plot MAP --curves draws them.",
        epilog=RUN_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("map", help="a map store of campar run (with the multipliers output)")
    p.add_argument(
        "--types",
        default=",".join(SEED_TYPES),
        help=f"curve types to seed ({','.join(SEED_TYPES)})",
    )
    p.add_argument("--points", type=int, default=400, help="points of a curve at most (400)")
    p.add_argument("--store", metavar="PATH", help="the curves' store (MAP-curves.zarr)")
    p.add_argument(
        "--no-shoot",
        dest="shoot",
        action="store_false",
        help="seed only from the edges the map types itself, without typing its unknown "
        "edges between periodic cells by shooting first (faster; misses curves whose only "
        "edges are unknown)",
    )
    p.add_argument("--overwrite", action="store_true", help="replace a store of another job")
    p.add_argument(
        "--grace",
        type=seconds,
        default=30.0,
        metavar="SECONDS",
        help="after a signal, wait so long for tasks in flight (30)",
    )
    p.add_argument("--json", action="store_true", help="print the curves as one JSON object")
    p.set_defaults(handler=run_curves)


def run_curves(args) -> int:
    import json

    from ..api import run
    from ..continuation.mapscale import SEED_TYPES
    from ..sweep.runner import setup_logging
    from ..sweep.signals import finished
    from ..views.map_curves import curves_job, describe_curves, read_curves

    types = tuple(t.strip().upper() for t in args.types.split(",") if t.strip())
    unknown = [t for t in types if t not in SEED_TYPES]
    if unknown or not types:
        raise JobError(
            f"--types: {', '.join(unknown) or 'none given'}; one or more of {', '.join(SEED_TYPES)}"
        )
    if not 2 <= args.points <= 100_000:
        raise JobError(f"--points must be from 2 to 100000, got {args.points}")
    if args.store is not None:  # refused as `campar run` refuses it, before the map is read
        from ..sweep.job_file import check_store_path

        try:
            check_store_path(args.store)
        except ValueError as exc:
            raise JobError(f"store {args.store!r}: {exc}") from None
    job = curves_job(args.map, types, points=args.points, store=args.store, shoot=args.shoot)
    setup_logging()
    path = run(job, overwrite=args.overwrite, grace=args.grace)
    finished()
    if launched_rank() > 0:  # every rank ran the job; rank 0 reports it
        return 0
    curves = read_curves(path)
    if args.json:
        print(json.dumps({"store": str(path), "curves": [c.to_dict() for c in curves]}))
    else:
        print(
            f"{path}: {len(job.curves.tasks)} tasks, {len(curves)} curves "
            f"({describe_curves(curves)})"
        )
    return 0
