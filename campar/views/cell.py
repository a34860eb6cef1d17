"""From the map to the cell: one cell of a store as an object that simulates, solves its
cycle, finds its attractors, continues and plots (``campar.cell``, ``campar point --from``).

``cell(store, omega=…, mu_cn=…)`` takes the grid cell nearest the coordinates given (by
the store's axis names), its model (``Job.cell_model``: the grid's values and the job's
sections) and its stored values. ``StoredCell.simulate()`` computes the cell again as its
tile did — its chain replayed from the start up to the cell (``campar.sweep.replay``) —
and so reproduces every stored variable bit for bit while the store's kernel version is
this campar's (``KERNEL_VERSION``); ``differences`` says which values differ.

Reading is done when ``cell`` returns: a StoredCell holds plain values and no open file,
so it may be used from any thread.
"""

import math
from dataclasses import dataclass, field

import numpy as np

from ..core.version import KERNEL_VERSION
from ..errors import JobError
from ..model import Model
from ..sweep.job import DIRECTIONS, Job
from ..sweep.plan import plan_tiles
from .point import PointResult, point_result, trace_steady

MAX_TRACE_REVOLUTIONS = 64


@dataclass(frozen=True)
class StoredCell:
    """One cell of a store: where it lies, its model and its stored values.

    Parameters
    ----------
    path : str
        The store.
    row, col : int
        Its place in the grid (second axis, first axis).
    direction : str or None
        Which chain of a ``both`` store (down, up); None otherwise.
    coordinates : dict
        Its grid values by axis name (``omega``, ``mu_cn``, … or a basin's ``y0``, ``ydot0``).
    model : Model
        Everything its numbers depend on.
    stored : dict
        Every per-cell array's value at the cell, as the store holds it.
    kernel : str or None
        The kernel version that wrote the store (None: a store that does not say).
    job : Job
        The store's job (``campar.sweep.job.Job``): its grid, chains and outputs, from
        which the cell is computed again.

    Examples
    --------
    >>> import campar
    >>> c = campar.cell("results/smoke.zarr", omega=3.0, mu_cn=0.7)
    >>> c.simulate().label, c.differences()
    ('1-1', {})
    """

    path: str
    row: int
    col: int
    direction: str | None
    coordinates: dict
    model: Model
    stored: dict = field(repr=False)
    kernel: str | None
    job: Job = field(repr=False)

    @property
    def current_kernel(self) -> bool:
        """Whether the store was written by this campar's kernel (KERNEL_VERSION)."""
        return self.kernel == str(KERNEL_VERSION)

    def replay(self) -> dict:
        """Every per-cell value of the cell computed again, as its tile computed it."""
        from ..sweep.replay import replay_cell

        return replay_cell(self.job, self.row, self.col, self.direction)

    def differences(self, replayed: dict | None = None) -> dict:
        """{name: (stored, computed)} of every stored variable whose computed value is not
        the stored one bit for bit (NaN payloads included); {} when all are."""
        replayed = self.replay() if replayed is None else replayed
        out = {}
        for name, value in self.stored.items():
            now = np.asarray(replayed[name], dtype=np.asarray(value).dtype)
            if now.tobytes() != np.asarray(value).tobytes():
                out[name] = (value, now)
        return out

    def simulate(self, *, trace: bool = False, replayed: dict | None = None) -> PointResult:
        """The cell as ``campar point --from`` prints it: computed again (``replay``), with
        its orbit sampled over its period (or 64 revolutions) from its final state when
        ``trace`` (for ``plot``)."""
        replayed = self.replay() if replayed is None else replayed
        result = point_result(self.model, replayed)
        if trace and result.kind != "failed":
            n = result.n or min(self.model.classify.window_revolutions, MAX_TRACE_REVOLUTIONS)
            orbit = trace_steady(self.model, result.state, n, result.steps)
            if orbit is not None:
                result = PointResult(**{**result.__dict__, "trace": orbit})
        return result

    def cycle(self, n: int | None = None, **options):
        """The cell's n-cycle (default its stored period) by Newton's method on the
        section map from its stored final state (``campar.continuation.orbit.find_cycle``)."""
        from ..continuation.orbit import find_cycle

        n = int(self.stored["n"]) if n is None else n
        if n < 1:
            raise JobError("the cell is not periodic: give the cycle's period n")
        return find_cycle(n, self.state, model=self.model, **self.model.parameters, **options)

    def attractors(self, k: int = 16, **options):
        """The attractors that ``k`` starts reach at the cell's model, the cell's own final
        state among the starts (``campar.views.attractors.find_attractors``)."""
        from .attractors import find_attractors

        return find_attractors(self.model, count=k, given=[self.state], **options)

    def continue_(self, parameter: str, to: float, **options):
        """The branch of the cell's cycle as ``parameter`` goes from the cell's value to
        ``to``: the cell's model simulated from its stored final state, its cycle (the
        stored period unless ``cycle`` is given) solved for and continued.

        Parameters
        ----------
        parameter : str
            omega, f0, mu_kn, mu_cn, zeta or a law parameter (phi1 … phi4, n, restitution).
        to : float
            The far end of the branch's window.
        **options
            ``continue_from_cell``'s keywords: cycle, switch, settings, curve_types,
            second, second_window, section_map.

        Returns
        -------
        campar.views.continuation.ContinuationResult

        Raises
        ------
        campar.errors.ContinuationError
            The cell is not periodic and no ``cycle`` is given, or Newton fails there.

        Examples
        --------
        >>> import campar
        >>> c = campar.cell("results/smoke.zarr", omega=3.0, mu_cn=0.7)
        >>> result = c.continue_("omega", 2.5)
        >>> result.start.label == c.simulate().label
        True
        """
        from .continuation import continue_from_cell

        start = float(self.model.value(parameter))
        n = int(self.stored.get("n", 0))
        if n >= 1:
            options.setdefault("cycle", n)
        y0, v0 = self.state
        return continue_from_cell(parameter, (start, to), model=self.model, y0=y0, v0=v0, **options)

    def run_on(self, revolutions: int, *, trace: bool = False) -> PointResult:
        """The cell's motion run on from its stored final state for up to ``revolutions``
        revolutions with no early verdict (``chaos_after`` and ``quasiperiodic_after``
        0, the transient converged): whether a chaotic or quasi-periodic label was a long
        transient's, which later settles on a cycle (``campar point --from --run-on``).
        The stored values are used as they are: the cell is not replayed.

        Raises
        ------
        campar.errors.JobError
            ``revolutions`` out of range, or the cell failed (it has no final state).
        """
        from .point import simulate_point

        if not np.all(np.isfinite(self.stored["state"])):
            raise JobError("the cell failed: it has no final state to run on from")
        return simulate_point(
            self.model,
            state=self.state,
            trace=trace,
            transient="converged",
            revolutions=revolutions,
            chaos_after=0,
            quasiperiodic_after=0,
        )

    def plot(self, path=None):
        """The orbit's figure (phase portrait, ε, Pn, yc against t); saved at ``path`` if
        given. Returns the matplotlib figure."""
        from .plot import plot_orbit

        figure = plot_orbit(self.simulate(trace=True))
        if path is not None:
            figure.savefig(path, dpi=150)
        return figure

    @property
    def label(self) -> str:
        """The stored label (``n-p``, ``chaos``, ``QP``, …), as ``campar plot`` reads it."""
        from ..core.codes import cell_label

        s = self.stored
        return cell_label(int(s["kind"]), int(s["n"]), int(s["p"]), self.model.classify.chatter_p)

    @property
    def state(self) -> tuple[float, float]:
        """The stored final state (y, y') at θ = 0: a point of the cell's attractor."""
        y, v = (float(x) for x in self.stored["state"])
        return (y, v)


def cell(store, direction: str | None = None, **coordinates) -> StoredCell:
    """The cell of a store nearest ``coordinates`` (its axes by name, e.g. ``omega=3.0,
    mu_cn=0.5``; an axis of one point may be left out), with its model and stored values.

    Parameters
    ----------
    store : str or pathlib.Path
        A map's or a basin's store (Zarr or HDF5).
    direction : str, optional
        down or up: which chain of a ``chains.direction: both`` store (default down).
    **coordinates : float
        The cell's place by the store's axis names.

    Returns
    -------
    StoredCell
        The cell's place, model and stored values; no file is held open.

    Raises
    ------
    campar.errors.JobError
        An axis unknown or missing, a coordinate not a number or outside its grid
        (by more than one step), the cell not computed yet, a curves store.
    campar.errors.StoreError
        The store cannot be read.

    Examples
    --------
    >>> import campar
    >>> c = campar.cell("results/smoke.zarr", omega=3.0, mu_cn=0.7)  # the nearest cell
    >>> round(c.coordinates["omega"], 4), round(c.coordinates["mu_cn"], 4), c.model.model.tensile
    (2.9333, 0.6917, 'clamp')
    """
    from ..sweep.store import read_store

    coordinates = {key.replace("-", "_"): value for key, value in coordinates.items()}
    with read_store(store) as reader:
        job = reader.job
        if job.kind == "curves":
            raise JobError(f"{store} holds bifurcation curves, not cells")
        row, col = nearest_cell(job, coordinates, store)
        layer, direction = which_layer(job, direction)
        tile = next(
            t
            for t in plan_tiles(job)
            if t.row_start <= row < t.row_stop and t.direction in (None, direction)
        )
        if not reader.done[tile.index]:
            raise JobError(f"{store}: the cell's tile {tile.index} is not computed yet")
        stored = {
            name: reader.read_rows(name, slice(row, row + 1), layer)[0, col]
            for name in reader.names
        }
        kernel = reader.attrs.get("versions", {}).get("kernel")
    axes = {job.first: float(job.first_values[col]), job.second: float(job.second_values[row])}
    return StoredCell(
        str(store), row, col, direction, axes, job.cell_model(row, col), stored, kernel, job
    )


def nearest_cell(job: Job, coordinates: dict, store) -> tuple[int, int]:
    """(row, col) of the grid cell nearest the coordinates (JobError naming the axes)."""
    unknown = sorted(set(coordinates) - {job.first, job.second})
    if unknown:
        raise JobError(
            f"{store}: {unknown[0]} is not an axis of its grid; its axes: {job.first}, {job.second}"
        )
    index = []
    for name, values in ((job.second, job.second_values), (job.first, job.first_values)):
        if name not in coordinates:
            if len(values) > 1:
                raise JobError(
                    f"{store}: give --{name.replace('_', '-')} too, its grid's "
                    f"{'second' if name == job.second else 'first'} axis "
                    f"({values.min():g} … {values.max():g})"
                )
            index.append(0)
            continue
        value = axis_value(name, coordinates[name], values, store)
        index.append(int(np.argmin(np.abs(values - value))))
    return index[0], index[1]


def axis_value(name: str, given, values: np.ndarray, store) -> float:
    """``given`` as a number within the grid's span widened by one step (JobError else:
    the nearest cell of a point far outside the map is not the cell asked for)."""
    try:
        value = float(given)
    except (TypeError, ValueError):
        raise JobError(f"{store}: {name} must be a number, got {given!r}") from None
    low, high = float(values.min()), float(values.max())
    step = (high - low) / (len(values) - 1) if len(values) > 1 else 0.0
    if not math.isfinite(value) or (step > 0 and not low - step <= value <= high + step):
        raise JobError(f"{store}: {name} = {given!r} is outside its grid ({low:g} … {high:g})")
    return value


def which_layer(job: Job, direction: str | None) -> tuple[int | None, str | None]:
    """(layer index of the store's direction dimension or None, the direction)."""
    if job.chains.direction != "both":
        if direction not in (None, job.chains.direction):
            raise JobError(f"the store's chains ran {job.chains.direction} only")
        return None, None
    direction = direction or DIRECTIONS[0]
    if direction not in DIRECTIONS:
        raise JobError(f"--direction: down or up, got {direction!r}")
    return DIRECTIONS.index(direction), direction


def changed_values(differences: dict) -> str:
    """One line naming the values that changed and how (``campar point --from``)."""

    def show(value) -> str:
        arr = np.asarray(value)
        return f"{arr.item():.10g}" if arr.size == 1 else np.array2string(arr, precision=8)

    return "; ".join(f"{name}: {show(a)} → {show(b)}" for name, (a, b) in differences.items())
