"""The ``campar`` command: argument parsing and dispatch only.

Each subcommand is a ``add_<name>(subparsers)`` function that registers its
parser and sets ``handler`` to a function in the module that owns the logic,
so every behaviour is reachable from Python without the CLI.
"""

import argparse
import gc
import os
import sys

# Before numpy is imported: one OpenBLAS thread. campar's work runs on its own threads and
# ranks, and BLAS only ever sees tiny matrices; numpy's and SciPy's OpenBLAS pools (SciPy
# comes with numba's BLAS check) spin idle after their start, ~0.13 s of CPU a process
# taken from the kernel's cores (benchmarks/RESULTS.md). The caller's setting wins.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from . import __version__  # noqa: E402
from .errors import CamparError, Interrupted, JobError  # noqa: E402

# Registered subcommands, in the order ``campar --help`` lists them.
SUBCOMMANDS = []


def subcommand(add):
    SUBCOMMANDS.append(add)
    return add


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="campar",
        description="Two-parameter bifurcation maps of the cam–follower impact oscillator.",
    )
    parser.add_argument("--version", action="version", version=f"campar {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for add in SUBCOMMANDS:
        add(sub)
    return parser


def main(argv=None) -> int:
    """The program (``argv`` None: a stop signal after the work is done is ignored), or a
    command from Python (``argv`` a list: the caller's signal handlers are restored)."""
    from .sweep.signals import finished, guard_start, restore_signals

    saved = guard_start()  # a stop signal from here on: one line, never a traceback
    command = "campar"
    try:
        args = build_parser().parse_args(argv)
        command = f"campar {args.command}"
        return int(args.handler(args) or 0)
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
            # over all the program built (after a cold compile numba's IR, ~0.5 s).
            gc.freeze()


def repeated_by_other_rank(exc: CamparError) -> bool:
    """Under mpirun, an error every rank meets alike (the job, a signal before the start) or
    one the master reports: printed by rank 0 only."""
    rank = next((os.environ[v] for v in MPI_RANK_ENV if v in os.environ), "0")
    alike = isinstance(exc, (JobError, Interrupted)) or getattr(exc, "rank", 0)
    return rank.isdigit() and int(rank) > 0 and bool(alike)


MPI_RANK_ENV = ("PMI_RANK", "OMPI_COMM_WORLD_RANK", "PMIX_RANK")


# -- subcommands -------------------------------------------------------------
# (each block: one ``@subcommand`` function; keep the logic in its own module)


# What the model parameters are, for help texts (their defaults: the paper's base values).
PARAMETER_HELP = {
    "f0": "preload",
    "mu_kn": "contact stiffness ratio",
    "mu_cn": "contact damping ratio",
    "zeta": "spring damping ratio",
}


def add_model_arguments(p, *, several: bool = False) -> None:
    """--f0 … --zeta (default: the paper's base values; ``several``: each takes a list),
    --tensile, --transient and --revolutions, with the job model's defaults."""
    from .sweep.job import DEFAULT_TRANSIENT, PAPER_VALUES, TransientSettings, field_choices

    for name, value in PAPER_VALUES.items():
        flag = f"--{name.replace('_', '-')}"
        if several:
            text = f"{PARAMETER_HELP[name]} ({value:g}; several values: a line each)"
            p.add_argument(flag, type=float, nargs="+", default=[value], help=text)
        else:
            text = f"{PARAMETER_HELP[name]} ({value:g})"
            p.add_argument(flag, type=float, default=value, help=text)
    add_tensile_argument(p)
    mode, budget = DEFAULT_TRANSIENT.mode, DEFAULT_TRANSIENT.max_revolutions
    p.add_argument("--transient", choices=field_choices(TransientSettings, "mode"), default=mode,
                   help=f"converged: until it settles; fixed: as the paper ({mode})")  # fmt: skip
    p.add_argument("--revolutions", type=int, default=budget,
                   help=f"transient budget / length ({budget})")  # fmt: skip


def add_tensile_argument(p) -> None:
    from .sweep.job import DEFAULT_MODEL, ModelSettings, field_choices

    law = DEFAULT_MODEL.tensile
    p.add_argument("--tensile", choices=field_choices(ModelSettings, "tensile"), default=law,
                   help=f"clamp: no tensile force; allow: the paper's formula ({law})")  # fmt: skip


def add_law_options(p) -> None:
    """--duty-cycle and --cam-velocity: the paper's ambiguities (docs/model.md)."""
    from .sweep.job import DEFAULT_MODEL, ModelSettings, field_choices

    dc, cam = DEFAULT_MODEL.duty_cycle, DEFAULT_MODEL.cam_velocity
    p.add_argument(
        "--duty-cycle",
        choices=field_choices(ModelSettings, "duty_cycle"),
        default=dc,
        help=f"separation: DC counts ε < 0; force: Pn = 0 ({dc})",
    )
    p.add_argument("--cam-velocity", choices=field_choices(ModelSettings, "cam_velocity"),
                   default=cam, help="chain: ẏc = ω dyc/dθ; literal: the paper's eq. 6, "
                   f"dyc/dθ ({cam})")  # fmt: skip


@subcommand
def add_point(sub):
    from .sweep.job import DEFAULT_INITIAL, DEFAULT_INTEGRATOR, IntegratorSettings, field_choices

    p = sub.add_parser("point", help="simulate one cell and classify its steady motion")
    p.add_argument("--omega", type=float, required=True, help="cam speed / natural frequency")
    add_model_arguments(p)
    add_law_options(p)
    p.add_argument("--y0", type=float, default=DEFAULT_INITIAL.y, help="initial y at θ = 0")
    p.add_argument("--v0", type=float, default=DEFAULT_INITIAL.v, help="initial y' at θ = 0")
    rtol, method = DEFAULT_INTEGRATOR.rtol, DEFAULT_INTEGRATOR.method
    p.add_argument("--rtol", type=float, default=rtol, help=f"integrator rtol ({rtol:g})")
    p.add_argument("--method", choices=field_choices(IntegratorSettings, "method"),
                   default=method, help=f"integrator ({method})")  # fmt: skip
    p.add_argument("--multipliers", action="store_true", help="Floquet multipliers")
    p.add_argument("--lyapunov", action="store_true", help="largest Lyapunov exponent")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="FILE.png", help="phase portrait, ε(t), Pn(t) and yc(t)")
    p.add_argument("--attractors", type=int, metavar="K",
                   help="run K starts (rest, --y0/--v0, a spread over a box of (y, y')) "
                   "and list the distinct attractors with basin fractions")  # fmt: skip
    p.set_defaults(handler=run_point)


# Keys of the one-cell job ``campar point`` builds, and the flags that set them.
POINT_FLAGS = {
    "integrator.rtol": "--rtol", "integrator.method": "--method", "initial.y": "--y0",
    "initial.v": "--v0", "transient.mode": "--transient",
    "transient.max_revolutions": "--revolutions", "model.tensile": "--tensile",
    "model.duty_cycle": "--duty-cycle", "model.cam_velocity": "--cam-velocity",
}  # fmt: skip


def naming_flags(handler):
    """A handler whose JobErrors name the command's flags instead of the job's keys."""

    def run(args) -> int:
        try:
            return handler(args)
        except JobError as exc:
            text = str(exc)
            for key, flag in POINT_FLAGS.items():
                text = text.replace(f"point: {key}:", f"{flag}:")
            raise JobError(text) from None

    return run


@naming_flags
def run_point(args) -> int:
    import json

    from .views.point import simulate_point

    if args.revolutions < 1:
        raise JobError(f"--revolutions must be ≥ 1, got {args.revolutions}")
    settings = dict(f0=args.f0, mu_kn=args.mu_kn, mu_cn=args.mu_cn, zeta=args.zeta,
                    tensile=args.tensile, duty_cycle=args.duty_cycle,
                    cam_velocity=args.cam_velocity, transient=args.transient,
                    revolutions=args.revolutions, rtol=args.rtol, method=args.method)  # fmt: skip
    if args.attractors is not None:
        return run_attractors(args, settings)
    if args.plot:
        from .views.output import figure_file

        figure_file(args.plot)  # before computing
    result = simulate_point(
        args.omega,
        y0=args.y0,
        v0=args.v0,
        **settings,
        multipliers=args.multipliers,
        lyapunov=args.lyapunov,
        trace=bool(args.plot),
    )
    if args.json:
        print(json.dumps(result.to_dict()))
    else:
        print(format_point(result))
    if args.plot:
        from .views.plot import plot_orbit

        plot_orbit(result).savefig(args.plot, dpi=150)
    return 0


def run_attractors(args, settings) -> int:
    import json

    from .views.attractors import describe_attractors, find_attractors

    given = [(args.y0, args.v0)] if (args.y0, args.v0) != (0.0, 0.0) else []
    if args.attractors < len(given) + 1:
        raise JobError(f"--attractors must be ≥ {len(given) + 1} (rest and --y0/--v0), "
                       f"got {args.attractors}")  # fmt: skip
    if args.plot:
        raise JobError("--plot draws one orbit: use it without --attractors, from an "
                       "attractor's state (--y0 --v0)")  # fmt: skip
    census = find_attractors(args.omega, count=args.attractors, given=given,
                             lyapunov=args.lyapunov, **settings)  # fmt: skip
    print(json.dumps(census.to_dict()) if args.json else describe_attractors(census))
    return 0


def format_point(r) -> str:
    par = ", ".join(f"{k}={v}" for k, v in r.parameters.items())
    lines = [
        f"{r.label}  ({r.kind}; {r.status})  at {par}",
        f"  duty cycle {r.dc:.4f}   ε min {r.eps_min:.4f}   ε max {r.eps_max:.4f}   "
        f"Pn max {r.pn_max:.4f}",
        f"  {r.revolutions} revolutions, {r.steps} steps" + (
            f", flags: {', '.join(r.flags)}" if r.flags else ""),
    ]  # fmt: skip
    if r.multipliers is not None:
        mult = ", ".join(f"{m.real:+.6f}{m.imag:+.6f}j (|λ|={abs(m):.6f})" for m in r.multipliers)
        lines.append(f"  Floquet multipliers: {mult}")
    if r.lyapunov is not None:
        lines.append(f"  largest Lyapunov exponent: {r.lyapunov:+.6f} per unit time")
    return "\n".join(lines)


@subcommand
def add_plot(sub):
    from .views.plot import STORE_VIEWS, parse_range  # cheap: matplotlib loads only to draw

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
    from .views.plot import plot_store

    if (args.json or args.trace) and not args.bifurcations:
        raise JobError("--json and --trace go with --bifurcations")
    found = None
    if args.bifurcations:
        from .views.boundaries import store_boundaries
        from .views.output import figure_file

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
            from .views.boundaries import describe_boundaries

            print(describe_boundaries(found, limit=0))
        print(f"wrote {path}")
    return 0


@subcommand
def add_separation(sub):
    p = sub.add_parser("separation", help="separation speed of each row of stores made with the "
                       "separation output, several laws on one plot (docs/design.md)")  # fmt: skip
    p.add_argument("stores", nargs="+", help="result stores (one curve each)")
    p.add_argument("--plot", metavar="FILE.png", help="draw the curves into this figure")
    p.set_defaults(handler=run_separation)


def run_separation(args) -> int:
    from .views.separation import describe_curves, separation_curve

    if args.plot:
        from .views.output import figure_file

        figure_file(args.plot)  # before reading the stores
    curves = [separation_curve(store) for store in args.stores]
    print(describe_curves(curves))
    if args.plot:
        from .views.plot.design import plot_separation
        from .views.plot.style import save_figure

        print(f"wrote {save_figure(plot_separation(curves), args.plot)}")
    return 0


@subcommand
def add_run(sub):
    p = sub.add_parser("run", help="compute a job's map into its store (resumes; MPI under mpirun)")
    p.add_argument("job", help="job file (YAML)")
    p.add_argument("--store", metavar="PATH", help="result store (default: the job's store:)")
    p.add_argument("--overwrite", action="store_true", help="replace a store of another job")
    p.add_argument("--grace", type=float, default=30.0, metavar="SECONDS",
                   help="after a signal, wait so long for tiles in flight (30)")  # fmt: skip
    from .sweep.budget import DEFAULT_MAX_MEMORY, DEFAULT_MAX_STORE, format_size, parse_size

    store, memory = format_size(DEFAULT_MAX_STORE), format_size(DEFAULT_MAX_MEMORY)
    p.add_argument("--max-store", type=parse_size, metavar="SIZE",
                   help=f"refuse a job whose store exceeds SIZE unpacked ({store})")  # fmt: skip
    p.add_argument("--max-memory", type=parse_size, metavar="SIZE",
                   help=f"refuse a job whose ranks each need over SIZE ({memory})")  # fmt: skip
    p.set_defaults(handler=run_run)


def run_run(args) -> int:
    from .sweep.job import load_job

    job = load_job(args.job)  # before anything touches the disk
    from .sweep.runner import run_job, setup_logging
    from .sweep.signals import finished

    setup_logging()
    limits = dict(max_store=args.max_store, max_memory=args.max_memory)
    run_job(job, args.store, overwrite=args.overwrite, grace=args.grace, **limits)
    finished()  # the map is complete: a signal now changes nothing
    return 0


@subcommand
def add_status(sub):
    p = sub.add_parser("status", help="how far a store has got: tiles, cells, failures, runs")
    p.add_argument("store", help="result store (Zarr directory or HDF5 file)")
    p.set_defaults(handler=run_status)


def run_status(args) -> int:
    from .sweep.progress import describe
    from .sweep.store import read_store

    with read_store(args.store) as reader:
        print(describe(reader))
    return 0


@subcommand
def add_verify(sub):
    p = sub.add_parser("verify", help="read every committed tile back and check its checksum; "
                       "lists damaged tiles (exit 65 if any)")  # fmt: skip
    p.add_argument("store", help="result store (Zarr directory or HDF5 file)")
    p.set_defaults(handler=run_verify)


def run_verify(args) -> int:
    from .errors import StoreDamaged
    from .sweep.progress import verify_report

    text, intact = verify_report(args.store)
    print(text)
    return 0 if intact else StoreDamaged.exit_code


@subcommand
def add_warm_up(sub):
    text = "compile the numerical core into numba's cache once: a first point or map starts at once"
    p = sub.add_parser("warm-up", help=text)
    p.set_defaults(handler=run_warm_up)


def run_warm_up(args) -> int:
    from .sweep.tile import warm_up

    print(f"campar warm-up: the kernel is compiled and cached ({warm_up():.1f} s)")
    return 0


@subcommand
def add_bench(sub):
    from .bench import add_parser  # cheap: each benchmark imports its numerics when it runs

    add_parser(sub)  # `campar bench NAME …`: the registry in campar/bench/__init__.py


@subcommand
def add_line(sub):
    from .views.line import DEFAULT_SECTIONS  # cheap: numba loads only to compute
    from .views.plot import parse_range  # cheap: matplotlib loads only to draw

    p = sub.add_parser("line", help="bifurcation diagram: σn points y and detachments p "
                       "against ω (continuation, ω decreasing)")  # fmt: skip
    p.add_argument(
        "--omega",
        metavar="A:B",
        type=parse_range,
        required=True,
        help="ω range; computed from the larger value down (the paper's direction)",
    )
    p.add_argument("--points", type=int, default=2000, help="ω values (2000)")
    add_model_arguments(p, several=True)
    p.add_argument("--sections", type=int, default=DEFAULT_SECTIONS,
                   help=f"σn points kept per non-periodic cell ({DEFAULT_SECTIONS})")  # fmt: skip
    p.add_argument(
        "-o",
        "--output",
        metavar="FILE",
        default="line.png",
        help="figure; format from the suffix (default line.png)",
    )
    p.add_argument("--npz", metavar="FILE", help="also save the arrays (FILE, or FILE-1.npz, …)")
    p.add_argument("--json", action="store_true", help="print one JSON object: each line's "
                   "runs of labels and its transitions (ω, type, multiplier evidence)")  # fmt: skip
    p.set_defaults(handler=run_line)  # fmt: skip


def run_line(args) -> int:
    import time
    from pathlib import Path

    from .views.line import compute_lines, describe_line, line_job, varied_parameters
    from .views.transitions import describe_transitions

    if args.points < 2:
        raise JobError(f"--points must be ≥ 2, got {args.points}")
    from .views.output import figure_file, writable_file

    figure_file(args.output)  # before computing
    if args.npz:
        writable_file(args.npz, "arrays")
    sets = varied_parameters({"f0": args.f0, "mu_kn": args.mu_kn, "mu_cn": args.mu_cn,
                              "zeta": args.zeta})  # fmt: skip
    jobs = [line_job(args.omega, args.points, tensile=args.tensile, sections=args.sections,
                     transient=args.transient, revolutions=args.revolutions, **params)
            for params in sets]  # fmt: skip
    start = time.perf_counter()
    lines = compute_lines(jobs)
    seconds = time.perf_counter() - start
    if not args.json:
        for line in lines:
            print(describe_line(line))
            print(f"  transitions (ω decreasing):\n{describe_transitions(line.transitions)}"
                  if line.transitions else "  no transitions")  # fmt: skip
        print(f"{sum(len(line.omega) for line in lines)} cells in {seconds:.2f} s")
    if args.npz:
        for i, line in enumerate(lines):
            path = Path(args.npz)
            line.to_npz(path if len(lines) == 1 else path.with_stem(f"{path.stem}-{i + 1}"))
    from .views.plot import save_figure
    from .views.plot.bifurcation import plot_line, plot_lines

    figure = plot_line(lines[0]) if len(lines) == 1 else plot_lines(lines)
    written = save_figure(figure, args.output)
    if args.json:
        import json

        data = {"lines": [line.to_dict() for line in lines], "seconds": seconds,
                "figure": str(written)}  # fmt: skip
        print(json.dumps(data))
    else:
        print(f"wrote {written}")
    return 0


@subcommand
def add_gallery(sub):
    p = sub.add_parser("gallery", help="compute and draw the paper's whole figure set")
    from .sweep.job import ModelSettings, field_choices

    p.add_argument("outdir", help="directory for the PNGs, their job files and index.md")
    p.add_argument("--tensile", choices=("both", *field_choices(ModelSettings, "tensile")),
                   default="both", help="force law(s) to draw: both (default; clamp with plain "
                   "names, allow with '-allow' names), clamp or allow")  # fmt: skip
    add_plane_arguments(p)
    p.set_defaults(handler=run_gallery)


def add_plane_arguments(p) -> None:
    """--size and --stores of the commands that compute the paper's planes first."""
    p.add_argument(
        "--size",
        choices=("small", "full"),
        default="small",
        help="small: 48×48 planes, under a minute (CI); full: the jobs' 400×400",
    )
    p.add_argument(
        "--stores", metavar="DIR", help="plane stores, reused (default results/paper-SIZE)"
    )


def run_gallery(args) -> int:
    from .paper.gallery import make_gallery
    from .sweep.runner import setup_logging

    setup_logging()  # the planes' progress lines
    make_gallery(args.outdir, args.size, args.tensile, args.stores)
    return 0


@subcommand
def add_report(sub):
    p = sub.add_parser(
        "report",
        help="write the reproduction report: the paper's claims "
        "against campar under both force laws, and the Liouville check",
    )
    p.add_argument("path", help="Markdown file to write (the committed one is docs/paper.md)")
    add_plane_arguments(p)
    p.set_defaults(handler=run_report)


def run_report(args) -> int:
    from .paper.report import write_report
    from .sweep.runner import setup_logging

    setup_logging()  # the planes' progress lines
    write_report(args.path, args.size, args.stores)
    return 0


if __name__ == "__main__":
    sys.exit(main())
