"""What ``campar point`` prints and saves of a cell, a cycle or a census: shared by a
point computed from its flags and one taken from a store (``point_from``)."""

import sys

from ..errors import JobError


def save_orbit(result, path) -> None:
    from ..views.plot import plot_orbit

    plot_orbit(result).savefig(path, dpi=150)


def run_attractors(args, model, state) -> int:
    """The census of ``model``'s cell; ``state``, a start tried right after rest."""
    import json

    from ..views.attractors import describe_attractors, find_attractors

    given = [state] if state != (0.0, 0.0) else []
    if args.attractors < len(given) + 1:
        raise JobError(
            f"--attractors must be ≥ {len(given) + 1} (rest and --y0/--v0), got {args.attractors}"
        )
    census = find_attractors(model, count=args.attractors, given=given, lyapunov=args.lyapunov)
    print(json.dumps(census.to_dict()) if args.json else describe_attractors(census))
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
    if r.model is not None:
        changed = non_default_keys(r.model)
        if changed:
            lines.append("  model: " + ", ".join(f"{k}={v}" for k, v in changed.items()))
    if r.multipliers is not None:
        mult = ", ".join(f"{m.real:+.6f}{m.imag:+.6f}j (|λ|={abs(m):.6f})" for m in r.multipliers)
        lines.append(f"  Floquet multipliers: {mult}")
    if r.lyapunov is not None:
        lines.append(f"  largest Lyapunov exponent: {r.lyapunov:+.6f} per unit time")
    return "\n".join(lines)


def non_default_keys(model) -> dict:
    """The model's keys (not its parameters, nor the force law's options the first line
    names) whose value is not the default."""
    from ..model import FIELDS

    shown = ("model.tensile", "model.duty_cycle", "model.cam_velocity")
    return {
        f.key: model.value(f.key)
        for f in FIELDS.values()
        if f.key not in shown and model.value(f.key) != f.default
    }


def warn(text: str) -> None:
    print(text, file=sys.stderr)
