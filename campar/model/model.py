"""``Model``: one frozen value that says everything a cell's computation depends on.

Its keys are a job's keys: the parameters ``omega``, ``f0``, ``mu_kn``, ``mu_cn``, ``zeta``
(a job sweeps two of them and fixes the rest), and the sections ``model`` (the force
law's options, ``cam``, ``contact``), ``initial``, ``integrator``, ``transient`` and
``classify`` (campar.model.sections). ``FIELDS`` lists every settable key once, with the
command-line flag generated from it; ``Model.build`` is the one place a model is made
from keywords, flags or a job's sections, so a bad value gives one message whatever the
entry.
"""

import difflib
import math
import typing
from dataclasses import dataclass

from pydantic import ValidationError, field_validator

from ..errors import JobError
from .laws import ANGLES, TAKES_UP, CamSettings
from .sections import (
    DEFAULT_CLASSIFY,
    DEFAULT_INITIAL,
    DEFAULT_INTEGRATOR,
    DEFAULT_MODEL,
    DEFAULT_TRANSIENT,
    PAPER_VALUES,
    PARAMETERS,
    ClassifySettings,
    InitialState,
    IntegratorSettings,
    ModelSettings,
    TransientSettings,
)
from .settings import Settings, check_parameter, short_repr

SECTIONS = ("model", "initial", "integrator", "transient", "classify")

# Flags whose name is not the key's last part: the start's (y0, v0 as a point has always
# called them) and the transient's mode and length (its section's name, its unit).
FLAG_NAMES = {
    "initial.y": "y0",
    "initial.v": "v0",
    "transient.mode": "transient",
    "transient.max_revolutions": "revolutions",
}
# Keys that are no one's to set: the cam table's hash is computed when the table is read.
DERIVED = ("model.cam.table_sha256",)


class Model(Settings):
    """Everything one cell's numbers depend on, validated and frozen.

    Parameters
    ----------
    omega, f0, mu_kn, mu_cn, zeta : float
        Cam speed ω (required) and the paper's other parameters (default its base values).
    model, initial, integrator, transient, classify : the job sections of the same names
        The force law's options, cam and contact; the start (y, y') at θ = 0; the
        integrator; the transient; the classification (jobs/README.md: every key).

    Examples
    --------
    >>> from campar.model import Model
    >>> m = Model.build(omega=2.0, rise="cycloidal", rtol=1e-9)
    >>> m.model.cam.rise, m.integrator.rtol, m.mu_kn
    ('cycloidal', 1e-09, 0.8)
    >>> m.replace(mu_kn=0.91).mu_kn
    0.91
    """

    omega: float
    f0: float = PAPER_VALUES["f0"]
    mu_kn: float = PAPER_VALUES["mu_kn"]
    mu_cn: float = PAPER_VALUES["mu_cn"]
    zeta: float = PAPER_VALUES["zeta"]
    model: ModelSettings = DEFAULT_MODEL
    initial: InitialState = DEFAULT_INITIAL
    integrator: IntegratorSettings = DEFAULT_INTEGRATOR
    transient: TransientSettings = DEFAULT_TRANSIENT
    classify: ClassifySettings = DEFAULT_CLASSIFY

    @field_validator(*PARAMETERS)
    @classmethod
    def in_range(cls, value: float, info) -> float:
        return check_parameter(info.field_name, value)

    @property
    def parameters(self) -> dict[str, float]:
        """ω, f0, μkn, μcn, ζ (PARAMETERS order)."""
        return {name: getattr(self, name) for name in PARAMETERS}

    @property
    def start(self) -> tuple[float, float]:
        """The start (y, y') at θ = 0 (``initial``)."""
        return (self.initial.y, self.initial.v)

    @property
    def n_sections(self) -> int:
        """σn points kept of a cell: ``classify.sections``, else ``classify.n_max``."""
        return self.classify.sections or self.classify.n_max

    def to_dict(self) -> dict:
        """Every key, as a job file writes it (the cam table's hash included)."""
        return self.model_dump(mode="json")

    def replace(self, **fields) -> "Model":
        """This model with ``fields`` changed (any key ``build`` takes), validated."""
        return Model.build(self, **fields)

    def value(self, key: str):
        """The value at a dotted key (``model.cam.rise``) or a field's name (``rise``)."""
        node = self
        for part in field_key(key).split("."):
            node = getattr(node, part)
        return node

    @classmethod
    def build(cls, base=None, source: str | None = None, **fields) -> "Model":
        """A validated Model: ``base`` (a Model, a mapping of a job's keys, or ω as a
        number; None: the defaults) with ``fields`` set, each named by its key
        (``"model.cam.rise"``), its name (``rise``) or its flag's name (``y0``,
        ``revolutions``). A cam angle given alone leaves the others and the near dwell
        (the far dwell, when the near dwell is given) takes up the difference, as when a
        map sweeps it. JobError with one line, "[SOURCE: ]KEY: problem", for a key
        unknown or a value out of range."""
        if isinstance(base, Model):
            data = base.to_dict()
            # the table's hash follows the table: recomputed if the table changes
            if any(field_key(k).startswith("model.cam.table") for k in fields):
                data["model"]["cam"].pop("table_sha256", None)
        elif isinstance(base, dict):
            data = {key: dict(v) if isinstance(v, dict) else v for key, v in base.items()}
        elif base is None:
            data = {}
        elif isinstance(base, (int, float)) and not isinstance(base, bool):
            data = {"omega": base}
        else:
            raise JobError(f"a model is a Model, a mapping or ω, got {type(base).__name__}")
        for name, value in fields.items():
            assign(data, field_key(name), value)
        angles = [field_key(name) for name in fields if field_key(name) in ANGLE_KEYS]
        if len(angles) == 1:
            take_up(data, angles[0].rsplit(".", 1)[-1], base)
        try:
            return cls.model_validate(data)
        except ValidationError as exc:
            message = model_error(exc)
            raise JobError(f"{source}: {message}" if source else message) from None


@dataclass(frozen=True)
class ModelField:
    """One settable key of a Model: its dotted ``key``, its ``flag`` (with the dashes),
    the Python ``annotation``, its ``default`` and the ``choices`` of a word-valued key."""

    key: str
    flag: str
    annotation: object
    default: object
    choices: tuple[str, ...] = ()

    @property
    def name(self) -> str:
        """The keyword of ``Model.build`` and ``campar.simulate_point``: the flag's name
        with underscores (``y0``, ``rise``, ``n_max``)."""
        return self.flag.removeprefix("--").replace("-", "_")

    def help(self) -> str:
        what = "|".join(self.choices) if self.choices else type_word(self.annotation)
        return f"{what} ({self.key}; default {self.default})"


def type_word(annotation) -> str:
    args = [a for a in typing.get_args(annotation) if a is not type(None)]
    inner = [type_word(a) for a in args] if args else []
    if annotation is bool or bool in args:
        return "true|false"
    if annotation is int or "INT" in inner:
        return "INT"
    if annotation is float or "X" in inner:
        return "X"
    return "TEXT"


def leaf_fields(settings: type[Settings], prefix: str = "") -> list[tuple[str, object, object]]:
    """(dotted key, annotation, default) of every leaf of a settings class."""
    out = []
    for name, f in settings.model_fields.items():
        key = f"{prefix}{name}"
        if isinstance(f.default, Settings):
            out += leaf_fields(type(f.default), f"{key}.")
        else:
            out.append((key, f.annotation, f.default))
    return out


def _fields() -> dict[str, ModelField]:
    out = {}
    for key, annotation, default in leaf_fields(Model):
        if key in PARAMETERS or key in DERIVED:
            continue  # each command has its own parameter flags (a value, a range, a list)
        name = FLAG_NAMES.get(key, key.rsplit(".", 1)[-1])
        choices = ()
        if typing.get_origin(annotation) is typing.Literal:
            choices = tuple(typing.get_args(annotation))
        out[key] = ModelField(key, f"--{name.replace('_', '-')}", annotation, default, choices)
    flags = [f.flag for f in out.values()]
    clash = {flag for flag in flags if flags.count(flag) > 1}
    if clash:  # a new key whose last part another has: name it in FLAG_NAMES
        raise RuntimeError(f"model keys share the flags {sorted(clash)}")
    return out


FIELDS = _fields()
# Every name a key goes by (key, flag's name) → the key; the parameters are their own.
_KEYS = {
    **{name: name for name in PARAMETERS},
    **{f.key: f.key for f in FIELDS.values()},
    **{f.name: f.key for f in FIELDS.values()},
    **{key: key for key in DERIVED},
}


def field_key(name: str) -> str:
    """The dotted key of a field's name, flag's name or key (a parameter also as a job
    writes it, ``fixed.mu_kn``); JobError if none."""
    name = name.removeprefix("--").replace("-", "_").removeprefix("fixed.")
    if name in _KEYS:
        return _KEYS[name]
    raise JobError(
        f"{name}: not a key of the model (its keys: jobs/README.md; its flags: campar point --help)"
    )


def assign(data: dict, key: str, value) -> None:
    """``data[a][b][c] = value`` for the key ``a.b.c``, making the mappings between."""
    parts = key.split(".")
    node = data
    for part in parts[:-1]:
        child = node.get(part)
        node[part] = child = dict(child) if isinstance(child, dict) else {}
        node = child
    node[parts[-1]] = value


ANGLE_KEYS = tuple(f"model.cam.{name}" for name in ANGLES)


def take_up(data: dict, name: str, base) -> None:
    """An angle given alone: TAKES_UP's angle takes up the difference, so the four still
    sum to 2π — as when a map sweeps it (``CamSettings.with_angle``, the same sum, so the
    same bits)."""
    cam = data["model"]["cam"]
    before = base.model.cam if isinstance(base, Model) else CamSettings()
    value = cam[name]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return  # the schema's message for a value that is no number
    if value == getattr(before, name):
        return  # the angles as they are, bit for bit
    other = TAKES_UP[name]
    current = {key: cam.get(key, getattr(before, key)) for key in ANGLES}
    rest = sum(current[key] for key in ANGLES if key not in (name, other))
    cam[other] = 2.0 * math.pi - rest - value


def model_error(exc: ValidationError) -> str:
    """One line for every problem pydantic found, each "KEY: problem, got VALUE"; a
    parameter's own message names it already (``mu_kn must be in (0, 1), got 2.0``)."""
    problems = []
    for err in exc.errors():
        where = ".".join(str(part) for part in err["loc"])
        message = err["msg"].removeprefix("Value error, ")
        if err["type"] == "extra_forbidden":
            problems.append(f"{where}: unknown key")
        elif where in PARAMETERS and err["type"] == "value_error":
            problems.append(message)
        elif err["type"] == "literal_error" and where in FIELDS:
            got = err.get("input")
            near = difflib.get_close_matches(str(got), FIELDS[where].choices, n=1)
            hint = f" (did you mean {near[0]}?)" if near else ""
            problems.append(f"{where}: {message}, got {short_repr(got)}{hint}")
        elif err["type"] == "missing":
            problems.append(f"{where}: required")
        elif isinstance(err.get("input"), dict):  # a section's own check: the message says
            problems.append(f"{where}: {message}")
        else:
            problems.append(f"{where}: {message}, got {short_repr(err.get('input'))}")
    return "; ".join(problems)
