"""Options shared by several commands: the model's parameters and options, one
definition each."""

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
    from ..sweep.job import DEFAULT_TRANSIENT, PAPER_VALUES, TransientSettings, field_choices

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
    from ..sweep.job import DEFAULT_MODEL, ModelSettings, field_choices

    law = DEFAULT_MODEL.tensile
    p.add_argument("--tensile", choices=field_choices(ModelSettings, "tensile"), default=law,
                   help=f"clamp: no tensile force; allow: the paper's formula ({law})")  # fmt: skip


def add_law_options(p) -> None:
    """--duty-cycle and --cam-velocity: the paper's ambiguities (docs/model.md)."""
    from ..sweep.job import DEFAULT_MODEL, ModelSettings, field_choices

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
