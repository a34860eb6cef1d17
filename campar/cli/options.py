"""Flags every command that computes a cell shares, generated from the model's schema.

Every key of a Model (campar.model.FIELDS: the force law's options, the cam, the contact,
the start, the integrator, the transient, the classification) is a flag named as the
key's last part (``--rise`` for ``model.cam.rise``, ``--rtol`` for ``integrator.rtol``;
``--y0``, ``--v0``, ``--transient``, ``--revolutions`` for the start and the transient's
mode and length), so a key added to the schema is a flag of every such command at once.
Beside them: ``--set KEY=VALUE`` (a key as a job writes it, e.g. ``model.cam.rise=cycloidal``),
``--job FILE`` (the job's model: its sections and fixed parameters), and the parameters'
own flags, which each command defines for itself (a value, a range, a list)::

    p = sub.add_parser("mycommand")
    add_parameter_arguments(p)            # --f0 … --zeta
    add_model_fields(p)                   # --tensile … --sections, --set, --job
    ...
    model = model_of(args, omega=args.omega, **parameter_values(args))

A value is read as a job file reads it (YAML), so a flag, ``--set``, a job file and
a Python keyword give the same model and the same message for the same bad value.
"""

import argparse

# What the model parameters are, for help texts (their defaults: the paper's base values).
PARAMETER_HELP = {
    "f0": "preload",
    "mu_kn": "contact stiffness ratio",
    "mu_cn": "contact damping ratio",
    "zeta": "spring damping ratio",
}
FIELD_DEST = "model_field:"  # argparse dest prefix of a generated flag


def flag_of(name: str) -> str:
    """The command-line flag of a job key's last part: ``duty_cycle`` → ``--duty-cycle``."""
    return f"--{name.replace('_', '-')}"


def add_parameter_arguments(p, *, several: bool = False, kind=float, metavar=None) -> None:
    """``--f0 … --zeta``, each unset unless given (the model's default then: the paper's
    base values); ``several``: each takes a list."""
    from ..model.sections import PAPER_VALUES

    for name, value in PAPER_VALUES.items():
        text = f"{PARAMETER_HELP[name]} ({value:g}"
        text += "; several values: a line each)" if several else ")"
        nargs = "+" if several else None
        p.add_argument(flag_of(name), type=kind, nargs=nargs, metavar=metavar, help=text)


def add_model_fields(p, *, skip=()) -> None:
    """One flag per key of the model (``campar.model.FIELDS``) but those in ``skip``, and
    ``--set KEY=VALUE``, ``--job FILE``; each unset unless given."""
    from ..model import FIELDS

    group = p.add_argument_group(
        "model", "every key of the model (jobs/README.md); unset: the job's default"
    )
    group.add_argument(
        "--job",
        metavar="FILE",
        help="take the model of this job file (its sections and fixed parameters)",
    )
    group.add_argument(
        "--set",
        metavar="KEY=VALUE",
        action="append",
        default=[],
        help="a key of the model as a job writes it, e.g. model.cam.rise=cycloidal (repeatable)",
    )
    for field in FIELDS.values():
        if field.key in skip:
            continue
        group.add_argument(
            field.flag,
            dest=FIELD_DEST + field.key,
            metavar="|".join(field.choices) if field.choices else "VALUE",
            default=argparse.SUPPRESS,
            help=field.help(),
        )


def given_fields(args) -> dict[str, str]:
    """{key: text} of the model's flags given on the command line."""
    return {
        dest.removeprefix(FIELD_DEST): value
        for dest, value in vars(args).items()
        if dest.startswith(FIELD_DEST)
    }


def read_value(key: str, text):
    """A flag's or --set's text as a job file reads it (YAML: numbers, true/false, text);
    a number the YAML spelling misses (``nan``, ``inf``) as that number, so the model
    refuses it as a number."""
    import math

    from ..sweep.overrides import parse_assignment

    _, value = parse_assignment(f"{key}={text}")
    if isinstance(value, str):
        try:
            number = float(value)
        except ValueError:
            return value
        return number if not math.isfinite(number) else value
    return value


def model_of(args, **parameters):
    """The Model of the command line: ``--job``'s model, then ``--set``, then the model's
    flags, then ``parameters`` (None values left out); JobError for a bad key or value."""
    from ..model import Model

    base = job_model(args.job) if getattr(args, "job", None) is not None else None
    fields = {}
    for text in getattr(args, "set", []):
        key, _, raw = text.partition("=")
        if not _:
            from ..errors import JobError

            raise JobError(f"--set expects KEY=VALUE (e.g. model.cam.rise=cycloidal), got {text!r}")
        fields[key.strip()] = read_value(key.strip(), raw)
    fields.update({key: read_value(key, text) for key, text in given_fields(args).items()})
    fields.update({name: value for name, value in parameters.items() if value is not None})
    return Model.build(base, **fields)


def job_model(path) -> dict:
    """A job file's model as a mapping: its model sections and fixed parameters."""
    from ..sweep.job import MODEL_SECTIONS, load_job

    job = load_job(path)
    data = {name: getattr(job, name).model_dump(mode="json") for name in MODEL_SECTIONS}
    return {**job.fixed, **data}


def parameter_values(args) -> dict:
    """``{"f0": …, "mu_kn": …, "mu_cn": …, "zeta": …}`` as parsed (None: not given)."""
    from ..model.sections import PAPER_VALUES

    return {name: getattr(args, name) for name in PAPER_VALUES}


MPI_RANK_ENV = ("PMI_RANK", "OMPI_COMM_WORLD_RANK", "PMIX_RANK")


def launched_rank() -> int:
    """This process's rank as an MPI launcher set it (0 without one): what only rank 0
    prints, every rank computes alike."""
    import os

    rank = next((os.environ[v] for v in MPI_RANK_ENV if v in os.environ), "0")
    return int(rank) if rank.isdigit() else 0
