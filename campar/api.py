"""What the ``campar`` commands do, from Python: ``campar.run`` computes a job's map into its
store, ``campar.forecast`` says what that run would cost, ``campar.line`` computes a
bifurcation line. Each returns what its command writes (the store's path, the line).

May import core, sweep and views (the layers below the command line).
"""

from pathlib import Path

from .errors import JobError
from .sweep.job import (
    Job,
    load_job,
)
from .views.line import DEFAULT_POINTS, BifurcationLine


def job_of(job, settings: dict | None = None) -> Job:
    """A validated Job from a Job, a job file's path, a store's path (its job, writing into
    it) or a job mapping, with the dotted keys of ``settings`` changed
    (``campar.sweep.overrides``)."""
    from .sweep.overrides import with_settings
    from .sweep.store import is_store, stored_job

    if isinstance(job, Job):
        found = job
    elif isinstance(job, dict):
        found = Job.from_dict(job)
    elif isinstance(job, (str, Path)) and is_store(job):
        found = stored_job(job)  # a store's own job: resume it, with the table it keeps
    elif isinstance(job, (str, Path)):
        found = load_job(job)
    else:
        raise JobError(f"a job is a Job, a job file's path or a mapping, got {type(job).__name__}")
    return with_settings(found, settings or {})


def run(
    job,
    *,
    store: str | Path | None = None,
    settings: dict | None = None,
    overwrite: bool = False,
    grace: float = 30.0,
    max_store: int | None = None,
    max_memory: int | None = None,
) -> Path:
    """Compute every pending cell of a job's map into its store, as ``campar run`` does.

    Serial in this process, or one rank of an MPI run when the script runs under
    ``mpirun`` (every rank calls ``run`` alike). A store of the same job resumes where
    it stopped; its progress goes to the ``campar.run`` logger.

    Parameters
    ----------
    job : Job, str, Path or dict
        The job: a validated ``Job``, the path of a YAML job file, or a job mapping
        as a file holds it.
    store : str or Path, optional
        The result store (a Zarr directory, or HDF5 for ``.h5``); default the job's
        ``store:``.
    settings : dict, optional
        Dotted job keys and their values, as ``campar run --set KEY=VALUE`` takes
        them, e.g. ``{"sweep.omega.points": 200, "model.tensile": "allow"}``;
        the changed job is validated as a job file is.
    overwrite : bool
        Replace a store that holds another job (default: refuse it).
    grace : float
        Seconds to wait for tiles in flight after a stop signal.
    max_store, max_memory : int, optional
        Refuse a job whose store (uncompressed) or whose ranks' memory would exceed
        this many bytes (``campar.sweep.budget``'s defaults if None).

    Returns
    -------
    Path
        The store's path; read it with ``campar.open``.

    Raises
    ------
    JobError
        The job is invalid, names no store, is over the limits, or the store holds
        another job (before anything is computed).
    Interrupted
        A stop signal ended the run (its exit code is 75); calling ``run`` again
        resumes it.
    CamparError
        A tile failed twice, or the store could not be written.

    Examples
    --------
    >>> import tempfile, campar
    >>> store = campar.run("jobs/smoke.yaml", store=tempfile.mkdtemp() + "/smoke.zarr",
    ...                    settings={"sweep.omega.points": 8})
    >>> campar.open(store)["label"].shape
    (24, 8)
    """
    from .sweep.runner import run_job

    job = job_of(job, settings)  # before anything touches the disk
    path = job.store if store is None else store  # an empty --store is refused, not ignored
    run_job(
        job,
        path,
        overwrite=overwrite,
        grace=grace,
        max_store=max_store,
        max_memory=max_memory,
        tile_work=work_of(job),
    )
    return Path(path)


def forecast(
    job,
    *,
    store: str | Path | None = None,
    settings: dict | None = None,
    ranks: int = 1,
    overwrite: bool = False,
    max_store: int | None = None,
    max_memory: int | None = None,
):
    """What ``run`` would do with these arguments, writing nothing (``campar run --dry-run``).

    The time is estimated by computing a few of the job's chains here and timing them
    (``campar.sweep.forecast``); their results are dropped.

    Parameters
    ----------
    job, store, settings
        As for ``run``.
    ranks : int
        The MPI ranks the run would have (``tiles.rows: auto`` depends on them).
    overwrite, max_store, max_memory
        As for ``run``.

    Returns
    -------
    campar.sweep.forecast.Forecast
        Cells, tiles, what the store holds already, its size, each rank's memory and
        an estimated time (``describe()``: the text ``--dry-run`` prints).

    Raises
    ------
    JobError
        The job or ``settings`` are invalid.

    Examples
    --------
    >>> import campar
    >>> plan = campar.forecast("jobs/smoke.yaml", store="/nonexistent/smoke.zarr")
    >>> plan.cells, plan.tiles, plan.pending_cells, plan.store_state
    (960, 12, 960, 'new')
    """
    from .sweep.forecast import forecast as plan

    if ranks < 1:
        raise JobError(f"ranks must be ≥ 1, got {ranks}")
    job = job_of(job, settings)
    return plan(
        job,
        store,
        ranks=ranks,
        overwrite=overwrite,
        max_store=max_store,
        max_memory=max_memory,
        tile_work=work_of(job),
    )


def work_of(job):
    """What computes the job's tiles where the kernel does not: a curves job's tasks."""
    if job.kind != "curves":
        return None
    from .continuation.tasks import CURVES_WORK  # the shooting loads only for curves

    return CURVES_WORK


def line(
    omega: tuple[float, float],
    points: int = DEFAULT_POINTS,
    model=None,
    **fields,
) -> BifurcationLine:
    """A bifurcation line along ω, as ``campar line`` computes it.

    One continuation chain: the line starts at the larger ω of ``omega`` from the model's
    start (rest: (y, y') = (0, 0) at θ = 0), and each next cell (ω decreasing) starts
    from the previous cell's final state — exactly one row of a map with this model.

    Parameters
    ----------
    omega : (float, float)
        The ω range, either order, two different finite numbers (equal ones for one
        point); computed from the larger value down.
    points : int
        ω values, evenly spaced, at least 2.
    model : Model or mapping, optional
        The line's model (``campar.Model``; its ω is replaced by the range's).
    **fields
        Any key of the model by its name, as ``campar.simulate_point`` takes them: the
        parameters ``f0``, ``mu_kn``, ``mu_cn``, ``zeta`` (default the paper's base
        values); ``tensile`` ("clamp" or "allow"), ``duty_cycle``, ``cam_velocity``; the
        cam's ``rise``, ``fall``, ``phi1`` … ``phi4``; the contact's ``law``, ``n``,
        ``restitution``; ``transient``, ``revolutions``; ``rtol``; ``sections`` (σn points
        kept per non-periodic cell, default DEFAULT_SECTIONS); … (jobs/README.md).

    Returns
    -------
    BifurcationLine
        The cells in the order computed: ω, σn points, n, p, kind, duty cycle, final
        states, Floquet multipliers, and the typed transitions between labels
        (``to_npz`` writes what ``campar line --npz`` writes, ``to_dict`` what
        ``--json`` prints; ``campar.views.plot.plot_line`` draws its figure).

    Raises
    ------
    JobError
        A key unknown or a value out of range.

    Examples
    --------
    >>> import campar
    >>> result = campar.line((1.0, 0.9), points=3)
    >>> result.omega.round(2).tolist(), result.labels
    ([1.0, 0.95, 0.9], ['1-1', '1-1', '1-1'])
    """
    from .views.line import compute_line, line_spec

    if points < 2:
        raise JobError(f"a line has at least 2 points, got {points}")
    return compute_line(line_spec(omega, points, model, **fields))
