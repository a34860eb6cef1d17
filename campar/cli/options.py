"""Flags several commands share, each defined once: the model's parameters, its options
and the transient.

Every command that computes cells (``point``, ``line``, and any command added beside them)
calls ``add_model_arguments`` on its parser and reads the values back with
``model_options`` and ``transient_options``, so a flag means the same everywhere and a
field added to the job's ``model:`` section becomes a flag of all of them at once::

    p = sub.add_parser("mycommand")
    add_model_arguments(p)               # --f0 … --zeta, --tensile, --duty-cycle, …
    ...
    job = point_job(omega=args.omega, **parameter_values(args), **model_options(args),
                    **transient_options(args))
"""

# What the model parameters are, for help texts (their defaults: the paper's base values).
PARAMETER_HELP = {
    "f0": "preload",
    "mu_kn": "contact stiffness ratio",
    "mu_cn": "contact damping ratio",
    "zeta": "spring damping ratio",
}

# What each value of a model option means (docs/model.md): one entry per field of the job's
# ``model:`` section (campar.sweep.job.ModelSettings); a field without one fails every parser.
MODEL_OPTION_HELP = {
    "tensile": "clamp: no tensile force; allow: the paper's formula",
    "duty_cycle": "separation: DC counts ε < 0; force: Pn = 0",
    "cam_velocity": "chain: ẏc = ω dyc/dθ; literal: the paper's eq. 6, dyc/dθ",
}


def option_fields() -> list[str]:
    """The fields of a job's ``model:`` section that are a choice among words (tensile,
    duty_cycle, cam_velocity): each a flag. The cam and contact laws are sections of their
    own, set in job files (docs/design.md)."""
    import typing

    from ..sweep.job import ModelSettings

    fields = ModelSettings.model_fields.items()
    return [name for name, f in fields if typing.get_origin(f.annotation) is typing.Literal]


def flag_of(name: str) -> str:
    """The command-line flag of a job key's last part: ``duty_cycle`` → ``--duty-cycle``."""
    return f"--{name.replace('_', '-')}"


def add_model_arguments(p, *, several: bool = False) -> None:
    """Add the model's flags to the parser ``p``: ``--f0 … --zeta`` (default: the paper's
    base values; ``several``: each takes a list), one flag per model option
    (``add_model_options``) and ``--transient``, ``--revolutions``."""
    add_parameter_arguments(p, several=several)
    add_model_options(p)
    add_transient_arguments(p)


def add_parameter_arguments(p, *, several: bool = False) -> None:
    from ..sweep.job import PAPER_VALUES

    for name, value in PAPER_VALUES.items():
        if several:
            text = f"{PARAMETER_HELP[name]} ({value:g}; several values: a line each)"
            p.add_argument(flag_of(name), type=float, nargs="+", default=[value], help=text)
        else:
            text = f"{PARAMETER_HELP[name]} ({value:g})"
            p.add_argument(flag_of(name), type=float, default=value, help=text)


def add_model_options(p) -> None:
    """One flag per field of a job's ``model:`` section (``--tensile``, ``--duty-cycle``,
    ``--cam-velocity``), its choices and default the job model's."""
    from ..sweep.job import DEFAULT_MODEL, ModelSettings, field_choices

    for name in option_fields():
        default = getattr(DEFAULT_MODEL, name)
        p.add_argument(
            flag_of(name),
            choices=field_choices(ModelSettings, name),
            default=default,
            help=f"{MODEL_OPTION_HELP[name]} ({default})",
        )


def add_transient_arguments(p) -> None:
    from ..sweep.job import DEFAULT_TRANSIENT, TransientSettings, field_choices

    mode, budget = DEFAULT_TRANSIENT.mode, DEFAULT_TRANSIENT.max_revolutions
    p.add_argument(
        "--transient",
        choices=field_choices(TransientSettings, "mode"),
        default=mode,
        help=f"converged: until it settles; fixed: as the paper ({mode})",
    )
    p.add_argument(
        "--revolutions", type=int, default=budget, help=f"transient budget / length ({budget})"
    )


def parameter_values(args) -> dict:
    """``{"f0": …, "mu_kn": …, "mu_cn": …, "zeta": …}`` as parsed (lists with ``several``)."""
    from ..sweep.job import PAPER_VALUES

    return {name: getattr(args, name) for name in PAPER_VALUES}


def model_options(args) -> dict:
    """``{"tensile": …, "duty_cycle": …, "cam_velocity": …}`` as parsed: the job's
    ``model:`` section, and keywords of ``point_job``, ``line_job`` and ``campar.line``."""

    return {name: getattr(args, name) for name in option_fields()}


def transient_options(args) -> dict:
    """``{"transient": mode, "revolutions": budget}`` as parsed (keywords of ``point_job``
    and ``line_job``); JobError for a budget below one revolution."""
    from ..errors import JobError

    if args.revolutions < 1:
        raise JobError(f"--revolutions must be ≥ 1, got {args.revolutions}")
    return {"transient": args.transient, "revolutions": args.revolutions}


def model_flags() -> dict[str, str]:
    """Job keys of the model options and the transient → their flags (``model.tensile`` →
    ``--tensile``), for errors that name the flag the user typed."""

    flags = {f"model.{name}": flag_of(name) for name in option_fields()}
    return {**flags, "transient.mode": "--transient", "transient.max_revolutions": "--revolutions"}


MPI_RANK_ENV = ("PMI_RANK", "OMPI_COMM_WORLD_RANK", "PMIX_RANK")


def launched_rank() -> int:
    """This process's rank as an MPI launcher set it (0 without one): what only rank 0
    prints, every rank computes alike."""
    import os

    rank = next((os.environ[v] for v in MPI_RANK_ENV if v in os.environ), "0")
    return int(rank) if rank.isdigit() else 0
