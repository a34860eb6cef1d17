"""``campar point --from STORE``: a stored cell computed again and checked bit for bit."""

from ..errors import JobError
from .options import given_fields, parameter_values
from .point_output import format_cycle, format_point, run_attractors, save_orbit, warn

# Flags that name a basin's axes (its starts y0, ydot0 at θ = 0).
BASIN_FLAGS = {"initial.y": "y0", "initial.v": "ydot0"}
# Exit code of a cell that does not reproduce with the store's own kernel: a fault.
NOT_REPRODUCED = 1


def coordinates_of(args) -> dict:
    """The coordinates --from looks the cell up by: the parameters given, a law
    parameter's flag (--phi1, --n, …) and a basin's --y0 --v0; JobError for a model flag
    that would change the stored model."""
    from ..model.laws import LAW_PARAMETERS
    from ..model.model import FIELDS

    coords = {"omega": args.omega, **parameter_values(args)}
    coords = {name: value for name, value in coords.items() if value is not None}
    for key, text in given_fields(args).items():
        name = key.rsplit(".", 1)[-1]
        if name in LAW_PARAMETERS and key.startswith("model."):
            coords[name] = float(text)
        elif key in BASIN_FLAGS:
            coords[BASIN_FLAGS[key]] = float(text)
        else:
            hint = (
                "; --run-on N runs the stored cell on for N revolutions"
                if key == "transient.max_revolutions"
                else ""
            )
            raise JobError(
                f"--from takes the cell's model from the store; {FIELDS[key].flag} "
                f"would change it: leave it out (or compute the cell without --from){hint}"
            )
    if args.job or args.set:
        raise JobError("--from takes the cell's model from the store: without --job and --set")
    return coords


def run_from(args) -> int:
    import json

    from ..core.version import KERNEL_VERSION
    from ..views.cell import cell, changed_values

    try:
        coords = coordinates_of(args)
    except ValueError as exc:
        raise JobError(f"--from: a coordinate must be a number ({exc})") from None
    if args.plot:
        from ..views.output import figure_file

        figure_file(args.plot)  # before computing
    stored = cell(args.store, direction=args.direction, **coords)
    where = ", ".join(f"{k}={v:.10g}" for k, v in stored.coordinates.items())
    header = f"cell (row {stored.row}, column {stored.col}) of {args.store} at {where}"
    if stored.direction:
        header += f", chain {stored.direction}"
    if args.run_on is not None:
        return run_on(args, stored, header)  # from the stored state: any kernel's store
    if not stored.current_kernel and not args.recompute:
        raise JobError(
            f"{args.store} was written by kernel version {stored.kernel or 'unknown'}, this "
            f"campar's is {KERNEL_VERSION}: its cells do not reproduce bit for bit; "
            "--recompute computes the cell with this kernel and says which values changed"
        )
    if args.attractors is not None:
        print(header)
        return run_attractors(args, stored.model, stored.state)
    if args.cycle is not None:
        orbit = stored.cycle(args.cycle)
        print(json.dumps(orbit.to_dict()) if args.json else f"{header}\n{format_cycle(orbit)}")
        return 0
    replayed = stored.replay()
    result = stored.simulate(trace=bool(args.plot), replayed=replayed)
    differences = stored.differences(replayed)
    reproduced = not differences
    if args.json:
        data = result.to_dict()
        data["cell"] = {
            **where_of(args, stored),
            "kernel": stored.kernel,
            "reproduced": reproduced,
            "changed": sorted(differences),
        }
        print(json.dumps(data))
    else:
        print(header)
        print(format_point(result))
        n = len(stored.stored)
        if stored.current_kernel:
            print(
                f"  reproduces the store's {n} values of the cell bit for bit"
                if reproduced
                else f"  differs from the store: {changed_values(differences)}"
            )
        else:
            changed = changed_values(differences) if differences else "none of its values"
            print(
                f"  computed with kernel {KERNEL_VERSION} (the store's: "
                f"{stored.kernel or 'unknown'}); changed: {changed}"
            )
    if args.plot:
        save_orbit(result, args.plot)
    if differences and stored.current_kernel:
        warn(f"campar point --from: the cell does not reproduce: {', '.join(differences)}")
        return NOT_REPRODUCED
    return 0


def where_of(args, stored) -> dict:
    """The JSON ``cell`` object's place of the cell: its store, row, column, chain and
    coordinates."""
    return {
        "store": args.store,
        "row": stored.row,
        "column": stored.col,
        "direction": stored.direction,
        "coordinates": stored.coordinates,
    }


def run_on(args, stored, header: str) -> int:
    """``--run-on N``: the stored cell's motion run on from its final state (any kernel's
    store: the stored values are the start, not reproduced), its label against the stored
    one."""
    import json

    label, revolutions = stored.label, int(stored.stored["revolutions"])
    after = stored.run_on(args.run_on, trace=bool(args.plot))
    holds = after.label == label
    if args.json:
        data = after.to_dict()
        data["cell"] = {
            **where_of(args, stored),
            "stored_label": label,
            "stored_revolutions": revolutions,
            "run_on": args.run_on,
            "holds": holds,
        }
        print(json.dumps(data))
    else:
        print(header)
        print(f"  stored: {label} after {revolutions} revolutions")
        print(f"run on from its final state for up to {args.run_on} revolutions:")
        print(format_point(after))
        print(
            f"  the stored label holds ({after.revolutions} revolutions run on)"
            if holds
            else f"  the stored label does not hold: the motion is {after.label} after "
            f"{after.revolutions} more revolutions"
        )
    if args.plot:
        save_orbit(after, args.plot)
    return 0
