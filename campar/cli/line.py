"""``campar line``: bifurcation diagrams along ω."""

from ..errors import JobError
from .options import add_model_fields, add_parameter_arguments, model_of, parameter_values


def add_line(sub):
    from ..views.line import DEFAULT_POINTS  # cheap: numba loads only to compute
    from ..views.plot import parse_range  # cheap: matplotlib loads only to draw

    p = sub.add_parser(
        "line",
        help="bifurcation diagram: σn points y and detachments p against ω (continuation, "
        "ω decreasing)",
        description="A bifurcation line: one continuation chain along ω. It starts at the "
        "larger ω of --omega from rest, (y, y') = (0, 0) at θ = 0, and each next cell "
        "(ω decreasing) starts from the previous cell's final state, as a row of a map "
        "does; the same from Python: campar.line.",
    )
    p.add_argument(
        "--omega",
        metavar="A:B",
        type=parse_range,
        required=True,
        help="ω range; computed from the larger value down (the paper's direction)",
    )
    p.add_argument(
        "--points", type=int, default=DEFAULT_POINTS, help=f"ω values ({DEFAULT_POINTS})"
    )
    add_parameter_arguments(p, several=True)
    add_model_fields(p)
    p.add_argument(
        "-o",
        "--output",
        metavar="FILE",
        default="line.png",
        help="figure; format from the suffix (default line.png)",
    )
    p.add_argument("--npz", metavar="FILE", help="also save the arrays (FILE, or FILE-1.npz, …)")
    p.add_argument(
        "--json",
        action="store_true",
        help="print one JSON object: each line's "
        "runs of labels and its transitions (ω, type, multiplier evidence)",
    )
    p.set_defaults(handler=run_line)


def run_line(args) -> int:
    import time
    from pathlib import Path

    from ..views.line import compute_lines, describe_line, line_spec, varied_parameters
    from ..views.transitions import describe_transitions

    if args.points < 2:
        raise JobError(f"--points must be ≥ 2, got {args.points}")
    from ..views.output import figure_file, writable_file

    figure_file(args.output)  # before computing
    if args.npz:
        writable_file(args.npz, "arrays")
    given = {name: value for name, value in parameter_values(args).items() if value is not None}
    model = model_of(args, omega=max(args.omega))
    specs = [
        line_spec(args.omega, args.points, model, **params) for params in varied_parameters(given)
    ]
    start = time.perf_counter()
    lines = compute_lines(specs)
    seconds = time.perf_counter() - start
    if not args.json:
        for line in lines:
            print(describe_line(line))
            print(
                f"  transitions (ω decreasing):\n{describe_transitions(line.transitions)}"
                if line.transitions
                else "  no transitions"
            )
        print(f"{sum(len(line.omega) for line in lines)} cells in {seconds:.2f} s")
    if args.npz:
        for i, line in enumerate(lines):
            path = Path(args.npz)
            line.to_npz(path if len(lines) == 1 else path.with_stem(f"{path.stem}-{i + 1}"))
    from ..views.plot import save_figure
    from ..views.plot.bifurcation import plot_line, plot_lines

    figure = plot_line(lines[0]) if len(lines) == 1 else plot_lines(lines)
    written = save_figure(figure, args.output)
    if args.json:
        import json

        data = {
            "lines": [line.to_dict() for line in lines],
            "seconds": seconds,
            "figure": str(written),
        }
        print(json.dumps(data))
    else:
        print(f"wrote {written}")
    return 0
