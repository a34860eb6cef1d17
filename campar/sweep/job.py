"""Job files: the YAML schema, its defaults and validation, and the grid axes.

A job is parsed in one place (``load_job`` / ``Job.from_dict``) into frozen,
validated settings; nothing else in campar sees raw dicts. Every field has a
default, so a job file only states what differs from the paper's set-up.
Errors name the offending key and what is allowed, e.g.

    job file jobs/x.yaml: sweep.mu_cn.to: must be in (0, 1), got 1.5
"""

import hashlib
import json
import typing
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, ValidationError, field_validator, model_validator

from ..errors import JobError
from ..model import Model
from ..model.files import read_bounded
from ..model.laws import LAW_PARAMETERS, check_law_axis
from ..model.sections import (  # noqa: F401 (the model's sections, the job's too)
    DEFAULT_CLASSIFY,
    DEFAULT_INITIAL,
    DEFAULT_INTEGRATOR,
    DEFAULT_MODEL,
    DEFAULT_TRANSIENT,
    MODEL_OPTION_DEFAULTS,
    PAPER_VALUES,
    PARAMETERS,
    TRANSIENT_OPTION_DEFAULTS,
    ClassifySettings,
    InitialState,
    IntegratorSettings,
    ModelSettings,
    TransientSettings,
    field_choices,
    with_paper_values,
)
from ..model.settings import (  # noqa: F401 (their home for the schema's users)
    MAX_COUNT,
    MAX_POINTS,
    MAX_START,
    MAX_STARTS,
    MAX_STEPS,
    Axis,
    Settings,
    check_parameter,
    wants_number,
)
from .curves_job import CURVE_AXES, CurvesSettings, check_curves_axes, check_curves_job
from .job_file import MAX_JOB_BYTES, check_store_path, format_validation_error, parse_job_text

MAP_AXES = (*PARAMETERS, *LAW_PARAMETERS)
# The job's sections that are a Model's (campar.model.Model): with the grid's parameters
# they make each cell's model.
MODEL_SECTIONS = ("model", "integrator", "transient", "classify", "initial")
# The axes of a basin job: the initial state (y, y') at θ = 0, y along the first
# (columns), y' along the second (rows); its parameters are all fixed.
BASIN_AXES = ("y0", "ydot0")

# The sweep directions of a ``chains.direction: both`` job, in the order of the store's
# ``direction`` dimension (its tiles: every row range down, then every one up).
DIRECTIONS = ("down", "up")

OUTPUT_NAMES = ("label", "dc", "eps", "pn", "sections", "multipliers", "lyapunov", "separation")
DEFAULT_OUTPUTS = ("label", "dc", "eps", "pn")


def cell_edges(centres) -> np.ndarray:
    """Edges (n+1) of grid cells with the given centres (n), in the same order: midpoints
    between neighbours, the outer edges half a spacing beyond the end centres (a single
    cell: ±1 % of its value). How maps draw cells and where their boundaries lie."""
    c = np.asarray(centres, float)
    if c.size == 1:
        half = 0.5 * max(abs(c[0]) * 0.02, 1e-6)
        return np.array([c[0] - half, c[0] + half])
    mid = 0.5 * (c[1:] + c[:-1])
    return np.concatenate([[2 * c[0] - mid[0]], mid, [2 * c[-1] - mid[-1]]])


class TileSettings(Settings):
    rows: int | str = 4
    """Continuation chains (values of the second parameter) per tile; auto: chosen by
    ``campar run`` when it creates the store, from the grid, the ranks and who writes
    (``plan.auto_tile_rows``), then kept: the store's job holds the number."""

    @field_validator("rows", mode="before")
    @classmethod
    def whole_number_or_auto(cls, value):
        if value == "auto" or (type(value) is int and 1 <= value <= MAX_POINTS):
            return value
        raise ValueError(f"must be an integer from 1 to {MAX_POINTS} (an axis' most), or auto")


class ChainSettings(Settings):
    """Where each continuation chain (one row of the grid, along ω) starts, and which way."""

    start: Literal["rest", "continue"] = "rest"
    """rest: the first cell of every chain starts from ``initial``; continue: from the
    attractor found at the first cell of the previous chain, from the plane's starting
    corner on (the paper's 2-D continuation: the first column is one chain along the
    second axis, from ``initial`` at its first value)."""
    direction: Literal["down", "up", "both"] = "down"
    """down: every chain runs ω decreasing (the paper's direction); up: increasing; both:
    every chain both ways, each from the same start, the store's per-cell arrays gaining
    a ``direction`` dimension (down, up). The store keeps the job's ω order either way.
    A ``both`` job always stores ``sections`` (added to its outputs if not listed): the
    two directions' cycles are compared by their section points (``hysteresis``)."""


class AttractorSettings(Settings):
    """A census of coexisting attractors at every cell (``campar.sweep.multistable``)."""

    starts: Annotated[int, Field(ge=2, le=MAX_STARTS)]
    """Starts per cell (K): rest, then Halton points over a box of (y, y') at θ = 0, as
    ``campar point --attractors K``; the chain's own end state is one more record."""
    cap: Annotated[int, Field(ge=1, le=64)] = 4
    """Attractors stored per cell (C), most frequent first (n_attractors counts them all)."""


# Job sections whose absence (None) leaves a job's hash as it was before they existed.
OPTIONAL_SECTIONS = ("attractors", "curves")

# The defaults of the sweep's own sections (the model's: campar.model.sections).
DEFAULT_TILES = TileSettings()
DEFAULT_CHAINS = ChainSettings()


class Job(Settings):
    """A validated job, frozen, every key explicit: jobs/README.md gives each key's meaning.

    Parameters
    ----------
    name, sweep, fixed, model, initial, integrator, transient : the job's sections
    classify, outputs, tiles, chains, attractors, curves, store : the job's sections

    Examples
    --------
    >>> import campar
    >>> job = campar.load_job("jobs/smoke.yaml")
    >>> job.shape, job.fixed["mu_kn"], job.chains.direction
    ((24, 40), 0.8, 'down')
    """

    name: Annotated[str, Field(min_length=1, max_length=200, pattern=r"^[A-Za-z0-9_.\-]+$")]
    sweep: dict[str, Axis]
    fixed: dict[str, float] = {}
    model: ModelSettings = DEFAULT_MODEL
    initial: InitialState = DEFAULT_INITIAL
    integrator: IntegratorSettings = DEFAULT_INTEGRATOR
    transient: TransientSettings = DEFAULT_TRANSIENT
    classify: ClassifySettings = DEFAULT_CLASSIFY
    outputs: tuple[str, ...] = DEFAULT_OUTPUTS
    tiles: TileSettings = DEFAULT_TILES
    chains: ChainSettings = DEFAULT_CHAINS
    attractors: AttractorSettings | None = None
    """Coexisting attractors of every cell (None: off, the usual map alone)."""
    curves: CurvesSettings | None = None
    """A map's bifurcation curves as tasks (sweep point, task; ``campar curves``)."""
    store: str | None = None
    """Path of the result store; '.h5'/'.hdf5' selects HDF5, anything else Zarr."""

    @field_validator("store")
    @classmethod
    def a_store_path(cls, store: str | None) -> str | None:
        return None if store is None else check_store_path(store)

    @model_validator(mode="before")
    @classmethod
    def fill_fixed(cls, data):
        # The normalised job states every parameter: unswept, unfixed ones take the paper's value.
        sweep = data.get("sweep") if isinstance(data, dict) else None
        if isinstance(sweep, dict) and tuple(sweep) != CURVE_AXES:  # curves: the map's fixed
            fixed = data.get("fixed") or {}
            if isinstance(fixed, dict):
                fixed = dict(fixed)
                for name, value in PAPER_VALUES.items():
                    if name not in data["sweep"]:
                        fixed.setdefault(name, value)
                data = {**data, "fixed": fixed}
        return data

    @field_validator("sweep")
    @classmethod
    def omega_and_one_more(cls, sweep: dict[str, Axis]) -> dict[str, Axis]:
        keys = list(sweep)
        if tuple(keys) == CURVE_AXES:  # a curves job: tasks × points (curves_job)
            return sweep
        if tuple(keys) == BASIN_AXES:  # a basin: initial states, finite (Settings) and bounded
            for name, axis in sweep.items():
                for end, value in (("from", axis.start), ("to", axis.stop)):
                    if abs(value) > MAX_START:
                        raise ValueError(
                            f"{name}.{end}: a start is within ±{MAX_START:g}, got {value:g}"
                        )
            return sweep
        unknown = [k for k in keys if k not in MAP_AXES]
        if unknown:
            raise ValueError(
                f"unknown parameter {unknown[0]!r}; allowed: {', '.join(MAP_AXES)} "
                f"(a map), or exactly {', '.join(BASIN_AXES)} (a basin)"
            )
        if len(keys) != 2 or keys[0] != "omega":
            raise ValueError(
                "must list omega (the continuation axis) first and exactly one second "
                f"parameter (a map), or {', '.join(BASIN_AXES)} (a basin), got {keys}"
            )
        for name, axis in sweep.items():
            if name in LAW_PARAMETERS:
                continue  # checked against the model's laws (law_axis_fits_the_model)
            for end, value in (("from", axis.start), ("to", axis.stop)):
                try:
                    check_parameter(name, value)
                except ValueError as exc:
                    raise ValueError(f"{name}.{end}: {str(exc).removeprefix(name + ' ')}") from None
        return sweep

    @field_validator("fixed")
    @classmethod
    def known_fixed(cls, fixed: dict[str, float]) -> dict[str, float]:
        for name, value in fixed.items():
            if name not in PARAMETERS:
                raise ValueError(f"unknown parameter {name!r}; allowed: {', '.join(PARAMETERS)}")
            try:
                check_parameter(name, value)
            except ValueError as exc:
                raise ValueError(str(exc)) from None
        return fixed

    @field_validator("outputs")
    @classmethod
    def known_outputs(cls, outputs: tuple[str, ...]) -> tuple[str, ...]:
        for name in outputs:
            if name not in OUTPUT_NAMES:
                raise ValueError(f"unknown output {name!r}; allowed: {', '.join(OUTPUT_NAMES)}")
        if "label" not in outputs:
            outputs = ("label", *outputs)
        return tuple(dict.fromkeys(outputs))

    @model_validator(mode="before")
    @classmethod
    def matched_cycles_store_sections(cls, data):
        # The two directions' cycles, or a basin's attractors, are compared by their σn
        # points (views.dataset, views.basins): such jobs store them whether or not their
        # outputs list them; a basin its cells' multipliers too (the kernel computes them
        # there anyway: its cells are ``campar point --attractors`` records).
        if not isinstance(data, dict):
            return data
        wanted = ()
        if isinstance(data.get("sweep"), dict) and tuple(data["sweep"]) == BASIN_AXES:
            wanted = ("sections", "multipliers")
        elif isinstance(data.get("chains"), dict) and data["chains"].get("direction") == "both":
            wanted = ("sections",)
        outputs = data.get("outputs", DEFAULT_OUTPUTS)
        if isinstance(outputs, (list, tuple)):
            missing = tuple(name for name in wanted if name not in outputs)
            if missing:
                data = {**data, "outputs": (*outputs, *missing)}
        return data

    @model_validator(mode="after")
    def whole_cycles_where_cycles_are_matched(self):
        sections, n_max = self.classify.sections, self.classify.n_max
        matched = self.chains.direction == "both" or self.kind == "basin"
        if matched and sections is not None and sections < n_max:
            what = "a basin" if self.kind == "basin" else "chains.direction both"
            raise ValueError(
                f"classify.sections: {what} compares whole cycles of up to classify.n_max = "
                f"{n_max} section points; sections must be ≥ n_max or unset, got {sections}"
            )
        return self

    @model_validator(mode="after")
    def law_axis_fits_the_model(self):
        if self.kind == "map":
            check_law_axis(self.model, self.second, self.sweep[self.second])
        return self

    @model_validator(mode="after")
    def sweep_and_fixed_disjoint(self):
        both = set(self.sweep) & set(self.fixed)
        if both:
            raise ValueError(f"{sorted(both)[0]} is both swept and fixed")
        return self

    @model_validator(mode="after")
    def curves_and_their_axes(self):
        check_curves_job(self)
        check_curves_axes(self)
        return self

    @model_validator(mode="after")
    def basin_fixes_every_parameter(self):
        if self.kind != "basin":
            return self
        if "omega" not in self.fixed:
            raise ValueError("a basin job (sweep y0, ydot0) fixes omega: fixed: {omega: …}")
        # What a map's chains need has no meaning for a basin, whose every cell starts
        # from its own grid point: such keys are mistakes, not settings to ignore.
        unused = {
            "chains": self.chains != DEFAULT_CHAINS,
            "initial": self.initial != DEFAULT_INITIAL,
            "attractors": self.attractors is not None,
            "separation": self.wants("separation"),  # a speed along a map's ω rows
        }
        for key in (key for key, given in unused.items() if given):
            raise ValueError(
                f"{key}: a basin job's cells each start from their own (y0, ydot0); leave {key} out"
            )
        return self

    # -- derived views -------------------------------------------------------

    @property
    def kind(self) -> str:
        """ "map": chains along ω over a parameter plane; "basin": one parameter point,
        every cell a start (y0, ydot0) of its own (``campar.sweep.basin``); "curves": a map's
        bifurcation curves, tasks × points (``campar.sweep.curves_job``)."""
        if tuple(self.sweep) == CURVE_AXES:
            return "curves"
        return "basin" if tuple(self.sweep) == BASIN_AXES else "map"

    @property
    def first(self) -> str:
        """Name of the first axis, along each row (columns): omega, or y0 of a basin."""
        return list(self.sweep)[0]

    @property
    def second(self) -> str:
        """Name of the second axis, one value per row: the map's second parameter, or
        ydot0 of a basin."""
        return list(self.sweep)[1]

    @property
    def first_values(self) -> np.ndarray:
        return self.sweep[self.first].values()

    @property
    def omega(self) -> np.ndarray:
        """The ω axis of a map job (a basin's ω is ``parameter("omega")``)."""
        if self.kind != "map":
            raise ValueError(f"job {self.name} is a {self.kind} job, without an ω axis")
        return self.first_values

    @property
    def second_values(self) -> np.ndarray:
        return self.sweep[self.second].values()

    @property
    def shape(self) -> tuple[int, int]:
        """(second, first): the layout of every per-cell array, (rows, columns)."""
        return self.sweep[self.second].points, self.sweep[self.first].points

    def parameter(self, name: str) -> float:
        """Value of a parameter that is not swept."""
        return self.fixed[name]

    def model_at(self, first: float, second: float) -> Model:
        """The Model of the cell at (``first``, ``second``) on the job's axes: a map's ω
        and second parameter (a law parameter set in the model's cam or contact), the
        rest the job's; a basin's start (y0, ydot0) at its fixed parameters."""
        sections = {name: getattr(self, name) for name in MODEL_SECTIONS}
        if self.kind == "basin":
            start = InitialState(y=float(first), v=float(second))
            return Model(**self.fixed, **{**sections, "initial": start})
        if self.kind != "map":
            raise ValueError(f"job {self.name} is a {self.kind} job: its cells have no model")
        values = {**self.fixed, "omega": float(first)}
        name, value = self.second, float(second)
        if name in LAW_PARAMETERS:
            options = self.model
            if LAW_PARAMETERS[name] == "cam":
                options = options.model_copy(update={"cam": options.cam.with_angle(name, value)})
            else:
                contact = options.contact.model_copy(update={name: value})
                options = options.model_copy(update={"contact": contact})
            sections["model"] = options
        else:
            values[name] = value
        return Model(**values, **sections)

    def cell_model(self, row: int, col: int) -> Model:
        """The Model of cell (row, col) of the job's grid (``model_at``)."""
        return self.model_at(self.first_values[col], self.second_values[row])

    def law(self, row: int = 0):
        """The kernel's Law (core.model.Law) of chain ``row`` (``laws.row_law``)."""
        from ..model.laws import row_law

        return row_law(self.model, self.second, self.second_values, row)

    @property
    def directions(self) -> tuple[str, ...]:
        """The sweep directions the job computes: ("down", "up") for ``both``, else one."""
        return DIRECTIONS if self.chains.direction == "both" else (self.chains.direction,)

    def one_direction(self, direction: str) -> "Job":
        """This job with every chain run one way only: a ``both`` job's tiles of that
        direction compute exactly what this job computes (same start rule, settings)."""
        if direction not in DIRECTIONS:
            raise ValueError(f"direction must be one of {', '.join(DIRECTIONS)}, got {direction!r}")
        chains = self.chains.model_copy(update={"direction": direction})
        return self.model_copy(update={"chains": chains})

    def with_tile_rows(self, rows: int) -> "Job":
        """This job with ``tiles.rows`` fixed (``auto`` resolved): same numbers, the layout
        of its store's chunks and its tiles is what changes."""
        return self.model_copy(update={"tiles": TileSettings(rows=rows)})

    @property
    def n_sections(self) -> int:
        """σn points stored per cell: ``classify.sections``, else n_max; a basin's cells
        keep a whole read window (the section cloud a non-periodic attractor is matched by)."""
        if self.classify.sections:
            return self.classify.sections
        if self.kind == "basin":
            return max(self.classify.n_max, self.classify.window_revolutions)
        return self.classify.n_max

    def wants(self, output: str) -> bool:
        return output in self.outputs

    def to_dict(self) -> dict:
        """The normalised job: every field explicit, as stored with the results (an optional
        section that is off is left out, so such a job's store is as before it existed)."""
        data = self.model_dump(mode="json", by_alias=True)
        return {k: v for k, v in data.items() if not (k in OPTIONAL_SECTIONS and v is None)}

    def digest(self) -> str:
        """Hash of everything that changes the numbers (not the store path)."""
        return job_digest(self.to_dict())

    @classmethod
    def from_dict(cls, data: dict, source: str = "job") -> "Job":
        if not isinstance(data, dict):
            got = "an empty file" if data is None else f"a {type(data).__name__}"
            raise JobError(f"{source}: a job is a mapping of keys (key: value lines), got {got}")
        try:
            return cls.model_validate(data)
        except ValidationError as exc:
            raise JobError(format_validation_error(exc, source, allowed_keys)) from None


def job_digest(data: dict) -> str:
    """``Job.digest`` of a normalised job as ``to_dict`` gives it, or as a store holds it
    (so a store can check its job against its hash without this campar's defaults)."""
    data = {
        key: value
        for key, value in data.items()
        if key != "store" and not (key in OPTIONAL_SECTIONS and value is None)
    }
    for section, defaults in (
        ("model", MODEL_OPTION_DEFAULTS),
        ("transient", TRANSIENT_OPTION_DEFAULTS),
    ):
        if isinstance(data.get(section), dict):
            data[section] = {
                key: value
                for key, value in data[section].items()
                if key not in defaults or defaults[key] != value
            }
    text = json.dumps(data, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def allowed_keys(loc: tuple) -> list[str]:
    """The keys a job may have at ``loc`` (the location of the mapping holding a bad key)."""
    node = Job
    parts = iter(loc)
    for part in parts:
        annotation = node.model_fields[part].annotation
        if typing.get_origin(annotation) is dict:  # sweep: {parameter: Axis}
            next(parts, None)
            annotation = typing.get_args(annotation)[1]
        if not hasattr(annotation, "model_fields"):  # an optional section: X | None
            annotation = next(a for a in typing.get_args(annotation) if hasattr(a, "model_fields"))
        node = annotation
    return [field.alias or name for name, field in node.model_fields.items()]


def load_job(path: str | Path) -> Job:
    """Read and validate a YAML job file (jobs/README.md: every key and its default).

    Parameters
    ----------
    path : str or pathlib.Path
        The job file.

    Returns
    -------
    Job
        The validated job.

    Raises
    ------
    campar.errors.JobError
        The file unreadable, not YAML, or a key unknown, repeated, mistyped or out of range.

    Examples
    --------
    >>> import campar
    >>> campar.load_job("jobs/smoke.yaml").integrator.method
    'dop853'
    """
    path = Path(path)
    try:  # a FIFO, a device or a directory refused before a byte is read; at most the limit
        data = read_bounded(path, MAX_JOB_BYTES, "job file")
    except ValueError as exc:  # also a NUL byte in the path
        raise JobError(str(exc)) from None
    return Job.from_dict(parse_job_text(data, f"job file {path}"), source=f"job file {path}")


def cell_job(model: Model | None = None, outputs=DEFAULT_OUTPUTS, name="cell", **fields) -> Job:
    """The 1 × 1 map of a Model (``fields`` changing it, as ``Model.build`` takes them; ω
    and f0 swept over one value each): a map whose one cell computes what
    ``campar.simulate_point(model)`` computes."""
    data = Model.build(model, **fields).to_dict()
    fixed = {key: data.pop(key) for key in ("mu_kn", "mu_cn", "zeta")}
    sweep = {
        key: {"from": value, "to": value, "points": 1}
        for key, value in (("omega", data.pop("omega")), ("f0", data.pop("f0")))
    }
    data["model"]["cam"].pop("table_sha256", None)  # computed again as the job is read
    return Job.from_dict(
        {"name": name, "sweep": sweep, "fixed": fixed, **data, "outputs": list(outputs)},
        source=name,
    )
