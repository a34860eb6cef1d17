"""Small job files, the shared reference cells and serial reference maps computed in the
test's own process (no runner, no store)."""

import json
import os
from pathlib import Path

import numpy as np
import pytest

from campar.sweep.job import Job
from campar.sweep.plan import plan_tiles
from campar.sweep.tile import run_tile

# Cells computed with SciPy DOP853 at rtol 1e-10 outside campar.
REFERENCE_CASES = Path(__file__).resolve().parents[1] / "data" / "reference_cases.json"


def reference_case(case_id: int) -> dict:
    """The shared reference cell with this id (its parameters, start and expected result)."""
    (case,) = [c for c in json.loads(REFERENCE_CASES.read_text())["cases"] if c["id"] == case_id]
    return case


def case_arguments(case: dict) -> list[str]:
    """`campar point` options that set every parameter and the start of a reference cell."""
    return [
        "--omega",
        str(case["omega"]),
        "--f0",
        str(case["f0"]),
        "--mu-kn",
        str(case["mu_kn"]),
        "--mu-cn",
        str(case["mu_cn"]),
        "--zeta",
        str(case["zeta"]),
        "--tensile",
        "clamp" if case["clamp"] else "allow",
        "--y0",
        str(case["initial_state"]["y"]),
        "--v0",
        str(case["initial_state"]["yd"]),
    ]


# 6 × 12 cells, one chain a tile; "slow" fixes a long transient so a tile takes
# a noticeable fraction of a second (time to signal or kill a run mid-way).
SMALL_JOB = {
    "name": "small",
    "sweep": {
        "omega": {"from": 6.0, "to": 1.0, "points": 12},
        "mu_cn": {"from": 0.9, "to": 0.6, "points": 6},
    },
    "classify": {"window_revolutions": 16},
    "tiles": {"rows": 1},
}
SLOW = {"transient": {"mode": "fixed", "max_revolutions": 1500}}


def plane_job(name: str, omega: tuple, second: tuple, **sections) -> dict:
    """A job over the (ω, second) plane, every other parameter at the paper's value (the
    job fills unfixed ones in): ``omega`` is (from, to, points), ``second`` is (parameter,
    from, to, points); ``sections`` are the job's other sections as keywords."""
    axis, *span = second
    sweep = {"omega": dict(zip(("from", "to", "points"), omega, strict=True))}
    sweep[axis] = dict(zip(("from", "to", "points"), span, strict=True))
    return {"name": name, "sweep": sweep, **sections}


# A corner of the (ω, μkn) plane across a 1-1 | 1-2 boundary: new flights appear between
# its cells (grazings), which the stored ε extrema cannot show, so its edges there are
# unknown until typed by shooting (test_shot_edges.py, test_seed_shooting.py).
SHOT_CORNER = plane_job(
    "corner",
    (1.50, 1.43, 6),
    ("mu_kn", 0.95, 0.945, 2),
    chains={"start": "continue"},
    outputs=["label", "dc", "eps", "pn", "multipliers"],
)


# The explorer's tests' map: 6 × 12 cells of the (ω, μcn) plane, two rows a tile.
EXPLORE_MAP = plane_job(
    "explore",
    (6.0, 1.0, 12),
    ("mu_cn", 0.9, 0.6, 6),
    outputs=["label", "dc", "eps", "pn", "multipliers"],
    tiles={"rows": 2},
)


def merge(base: dict, extra: dict) -> dict:
    """``base`` with ``extra``'s keys set, nested dicts merged key by key."""
    out = dict(base)
    for key, value in extra.items():
        out[key] = merge(out[key], value) if isinstance(value, dict) and key in out else value
    return out


def short_curves(patch: pytest.MonkeyPatch, points: int = 40) -> None:
    """Continued curves of at most ``points`` points: a tiny gallery or report runs
    ``campar curves`` beside every map it draws, and the curves' points, not the map's
    cells, set its cost."""
    from functools import partial

    from campar.views import map_curves

    patch.setattr(map_curves, "curves_job", partial(map_curves.curves_job, points=points))


# One serial computation per job a session: the maps are pure functions of the job.
_REFERENCES: dict[str, dict[str, np.ndarray]] = {}


def reference_arrays(job: Job) -> dict[str, np.ndarray]:
    """The whole map computed tile by tile in this process, without runner or store."""
    key = job.digest()
    if key not in _REFERENCES:
        tiles = [run_tile(job, tile) for tile in plan_tiles(job)]
        _REFERENCES[key] = {name: np.concatenate([t[name] for t in tiles]) for name in tiles[0]}
    return _REFERENCES[key]


def assert_same_map(reader, job: Job) -> None:
    """Every array of a finished store equals the serial reference, bit for bit."""
    reference = reference_arrays(job)
    assert reader.done.all()
    assert sorted(reader.names) == sorted(reference)
    for name, expected in reference.items():
        got = reader.read(name)
        assert got.dtype == expected.dtype, name
        assert np.array_equal(got, expected, equal_nan=True), name


def computed_store(tmp_path_factory, data: dict) -> tuple[Path, Job]:
    """A Zarr store of the job ``data`` computed in this process, and the job (for
    module-scoped fixtures: one computation shared by a module's tests)."""
    import campar.sweep.runner as runner

    job = Job.from_dict(data)
    path = tmp_path_factory.mktemp(job.name) / f"{job.name}.zarr"
    runner.run_job(job, path)
    return path, job


def resume_after_interrupt(monkeypatch, job, path, index: int) -> None:
    """Run ``job`` into ``path`` with SIGTERM sent while tile ``index`` computes (the run
    ends Interrupted, the tile pending), then run it again to completion. The signal
    reaches the computing thread; the main thread sees it within its wait (0.05 s), or
    later on a loaded machine: ``index`` should leave two tiles after it."""
    import signal

    import campar.sweep.runner as runner
    from campar.errors import Interrupted
    from campar.sweep.store import read_store

    def tile_with_signal(job, tile):
        if tile.index == index:
            os.kill(os.getpid(), signal.SIGTERM)
        return run_tile(job, tile)

    monkeypatch.setattr(runner, "run_tile", tile_with_signal)
    with pytest.raises(Interrupted):
        runner.run_job(job, path)
    with read_store(path) as reader:
        assert not reader.done.all()
    monkeypatch.setattr(runner, "run_tile", run_tile)
    assert runner.run_job(job, path).outcome == "complete"
