"""``campar point``: one cell, its classification, its attractors."""

from ..errors import JobError
from .options import (
    add_model_arguments,
    model_flags,
    model_options,
    parameter_values,
    transient_options,
)


def add_point(sub):
    from ..sweep.job import DEFAULT_INITIAL, DEFAULT_INTEGRATOR, IntegratorSettings, field_choices

    p = sub.add_parser("point", help="simulate one cell and classify its steady motion")
    p.add_argument("--omega", type=float, required=True, help="cam speed / natural frequency")
    add_model_arguments(p)
    p.add_argument("--y0", type=float, default=DEFAULT_INITIAL.y, help="initial y at θ = 0")
    p.add_argument("--v0", type=float, default=DEFAULT_INITIAL.v, help="initial y' at θ = 0")
    rtol, method = DEFAULT_INTEGRATOR.rtol, DEFAULT_INTEGRATOR.method
    p.add_argument("--rtol", type=float, default=rtol, help=f"integrator rtol ({rtol:g})")
    p.add_argument(
        "--method",
        choices=field_choices(IntegratorSettings, "method"),
        default=method,
        help=f"integrator ({method})",
    )
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
    p.set_defaults(handler=run_point)


# Keys of the one-cell job ``campar point`` builds, and the flags that set them (with the
# model's, ``model_flags``).
POINT_FLAGS = {
    "integrator.rtol": "--rtol",
    "integrator.method": "--method",
    "initial.y": "--y0",
    "initial.v": "--v0",
}


def naming_flags(handler):
    """A handler whose JobErrors name the command's flags instead of the job's keys."""

    def run(args) -> int:
        try:
            return handler(args)
        except JobError as exc:
            text = str(exc)
            for key, flag in {**POINT_FLAGS, **model_flags()}.items():
                text = text.replace(f"point: {key}:", f"{flag}:")
            raise JobError(text) from None

    return run


@naming_flags
def run_point(args) -> int:
    import json

    from ..views.point import simulate_point

    settings = {
        **parameter_values(args),
        **model_options(args),
        **transient_options(args),
        "rtol": args.rtol,
        "method": args.method,
    }
    if args.attractors is not None:
        return run_attractors(args, settings)
    if args.cycle is not None:
        return run_cycle(args, settings)
    if args.plot:
        from ..views.output import figure_file

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
        from ..views.plot import plot_orbit

        plot_orbit(result).savefig(args.plot, dpi=150)
    return 0


def run_attractors(args, settings) -> int:
    import json

    from ..views.attractors import describe_attractors, find_attractors

    given = [(args.y0, args.v0)] if (args.y0, args.v0) != (0.0, 0.0) else []
    if args.attractors < len(given) + 1:
        raise JobError(
            f"--attractors must be ≥ {len(given) + 1} (rest and --y0/--v0), got {args.attractors}"
        )
    if args.plot:
        raise JobError(
            "--plot draws one orbit: use it without --attractors, from an "
            "attractor's state (--y0 --v0)"
        )
    census = find_attractors(
        args.omega, count=args.attractors, given=given, lyapunov=args.lyapunov, **settings
    )
    print(json.dumps(census.to_dict()) if args.json else describe_attractors(census))
    return 0


def run_cycle(args, settings) -> int:
    import json

    from ..continuation.orbit import find_cycle
    from ..views.point import simulate_point

    if args.cycle < 1:
        raise JobError(f"--cycle must be ≥ 1, got {args.cycle}")
    if args.plot or args.lyapunov:
        raise JobError("--cycle reports the cycle's multipliers: without --plot and --lyapunov")
    guess = (args.y0, args.v0)
    if guess == (0.0, 0.0):  # from rest: the simulated cell's end state is the guess
        guess = simulate_point(args.omega, **settings).state
    model = {name: settings[name] for name in ("tensile", "duty_cycle", "cam_velocity")}
    parameters = {name: settings[name] for name in ("f0", "mu_kn", "mu_cn", "zeta")}
    orbit = find_cycle(args.cycle, guess, model=model, omega=args.omega, **parameters)
    print(json.dumps(orbit.to_dict()) if args.json else format_cycle(orbit))
    return 0


def format_cycle(orbit) -> str:
    par = ", ".join(f"{k}={v:g}" for k, v in orbit.parameters.items())
    stability = "stable" if orbit.stable else "unstable"
    mult = ", ".join(f"{m.real:+.8f}{m.imag:+.8f}j (|λ|={abs(m):.8f})" for m in orbit.multipliers)
    points = "  ".join(f"({y:.10f}, {v:.10f})" for y, v in orbit.sections)
    return "\n".join(
        [
            f"{orbit.label} cycle ({stability}) at {par}",
            f"  section points: {points}",
            f"  Floquet multipliers: {mult}",
            f"  |P^n(x) - x| ≤ 1e-10 after {orbit.iterations} Newton iterations (--json: "
            f"its value); duty cycle {orbit.dc:.4f}, ε min {orbit.eps_min:.4f}, "
            f"ε max {orbit.eps_max:.4f}, Pn max {orbit.pn_max:.4f}",
        ]
    )


def format_point(r) -> str:
    par = ", ".join(f"{k}={v}" for k, v in r.parameters.items())
    lines = [
        f"{r.label}  ({r.kind}; {r.status})  at {par}",
        f"  duty cycle {r.dc:.4f}   ε min {r.eps_min:.4f}   ε max {r.eps_max:.4f}   "
        f"Pn max {r.pn_max:.4f}",
        f"  {r.revolutions} revolutions, {r.steps} steps"
        + (f", flags: {', '.join(r.flags)}" if r.flags else ""),
    ]
    if r.multipliers is not None:
        mult = ", ".join(f"{m.real:+.6f}{m.imag:+.6f}j (|λ|={abs(m):.6f})" for m in r.multipliers)
        lines.append(f"  Floquet multipliers: {mult}")
    if r.lyapunov is not None:
        lines.append(f"  largest Lyapunov exponent: {r.lyapunov:+.6f} per unit time")
    return "\n".join(lines)
