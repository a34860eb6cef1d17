"""The ``campar`` command: argument parsing and dispatch only.

Each subcommand is a ``add_<name>(subparsers)`` function that registers its
parser and sets ``handler`` to a function in the module that owns the logic,
so every behaviour is reachable from Python without the CLI.
"""

import argparse
import sys

from . import __version__
from .errors import CamparError, JobError

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
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.handler(args) or 0)
    except CamparError as exc:
        print(f"campar {args.command}: {exc}", file=sys.stderr)
        return exc.exit_code


# -- subcommands -------------------------------------------------------------
# (each block: one ``@subcommand`` function; keep the logic in its own module)


@subcommand
def add_point(sub):
    p = sub.add_parser("point", help="simulate one cell and classify its steady motion")
    p.add_argument("--omega", type=float, required=True, help="cam speed / natural frequency")
    p.add_argument("--f0", type=float, default=0.5, help="preload (default 0.5)")
    p.add_argument("--mu-kn", type=float, default=0.8, help="contact stiffness ratio (0.8)")
    p.add_argument("--mu-cn", type=float, default=0.8, help="contact damping ratio (0.8)")
    p.add_argument("--zeta", type=float, default=0.2, help="spring damping ratio (0.2)")
    p.add_argument("--tensile", choices=("clamp", "allow"), default="clamp")
    p.add_argument("--y0", type=float, default=0.0, help="initial y at θ = 0")
    p.add_argument("--v0", type=float, default=0.0, help="initial y' at θ = 0")
    p.add_argument("--transient", choices=("converged", "fixed"), default="converged")
    p.add_argument("--revolutions", type=int, default=500, help="transient budget / length")
    p.add_argument("--rtol", type=float, default=1e-8)
    p.add_argument("--method", choices=("dp54", "rk4"), default="dp54")
    p.add_argument("--multipliers", action="store_true", help="Floquet multipliers")
    p.add_argument("--lyapunov", action="store_true", help="largest Lyapunov exponent")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="FILE.png", help="phase portrait, ε(t), Pn(t) and yc(t)")
    p.set_defaults(handler=run_point)


def run_point(args) -> int:
    import json

    from .point import simulate_point

    if args.revolutions < 1:
        raise JobError(f"--revolutions must be ≥ 1, got {args.revolutions}")
    result = simulate_point(
        args.omega,
        f0=args.f0,
        mu_kn=args.mu_kn,
        mu_cn=args.mu_cn,
        zeta=args.zeta,
        tensile=args.tensile,
        y0=args.y0,
        v0=args.v0,
        transient=args.transient,
        revolutions=args.revolutions,
        rtol=args.rtol,
        method=args.method,
        multipliers=args.multipliers,
        lyapunov=args.lyapunov,
        trace=bool(args.plot),
    )
    if args.json:
        print(json.dumps(result.to_dict()))
    else:
        print(format_point(result))
    if args.plot:
        from .plot import plot_orbit

        plot_orbit(result).savefig(args.plot, dpi=150)
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
    from .plot import MAP_VIEWS, parse_range  # cheap: matplotlib loads only to draw

    p = sub.add_parser("plot", help="draw a map of a result store (n-p labels, duty cycle, …)")
    p.add_argument("store", help="result store of `campar run` (Zarr directory or HDF5 file)")
    p.add_argument("--what", choices=MAP_VIEWS, default="labels", help="default: n-p labels")
    p.add_argument("-o", "--output", metavar="FILE", help="image; format from the suffix "
                   "(.png, .pdf, .svg); default STORE-WHAT.png here")  # fmt: skip
    p.add_argument("--omega", metavar="A:B", type=parse_range, help="zoom to ω in [A, B]")
    p.add_argument("--second", metavar="C:D", type=parse_range,
                   help="zoom to the second parameter in [C, D]")  # fmt: skip
    p.set_defaults(handler=run_plot)


def run_plot(args) -> int:
    from .plot import plot_store

    path = plot_store(args.store, args.what, args.output, omega=args.omega, second=args.second)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
