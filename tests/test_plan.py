"""The planner (campar.sweep.plan): tiles cover each cell once, chains run through ω in
``chains.direction``, pending tiles follow the done mask. Expected values are computed
here from the definitions (a tile is ``tiles.rows`` consecutive chains; a chain is one
row of the grid; an axis is ``points`` evenly spaced values, ends included)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from support.jobs import plane_job

from campar.sweep.job import Job
from campar.sweep.plan import (
    auto_tile_rows,
    cell_seconds,
    chain_order,
    chain_parameters,
    first_column_parameters,
    pending_tiles,
    plan_tiles,
)

SECONDS = ("f0", "mu_kn", "mu_cn", "zeta")
BASE = {"f0": 0.5, "mu_kn": 0.8, "mu_cn": 0.8, "zeta": 0.2}  # MODEL.md's base values
RANGES = {"f0": (0.0, 3.0), "mu_kn": (0.05, 0.95), "mu_cn": (0.05, 0.95), "zeta": (0.0, 1.0)}


def drawn_axis(draw, ends, most: int) -> dict:
    """An axis of 1 … most points; with more than one point its ends differ (a job with
    equal ends and several points is refused)."""
    start, stop, points = draw(ends), draw(ends), draw(st.integers(1, most))
    return {"from": start, "to": stop, "points": points if start != stop else 1}


@st.composite
def jobs(draw):
    """A job with 1–60 chains of 1–30 cells, 1–12 chains a tile, any second parameter,
    either direction and either start of the chains."""
    second = draw(st.sampled_from(SECONDS))
    lo, hi = RANGES[second]
    ends = st.floats(lo, hi, allow_nan=False)
    sweep = {
        "omega": drawn_axis(draw, st.floats(0.1, 6.0), 30),
        second: drawn_axis(draw, ends, 60),
    }
    chains = {
        "direction": draw(st.sampled_from(["down", "up"])),
        "start": draw(st.sampled_from(["rest", "continue"])),
    }
    rows = draw(st.integers(1, 12))
    return Job.from_dict(
        {"name": "plan", "sweep": sweep, "tiles": {"rows": rows}, "chains": chains}
    )


def axis(spec: dict) -> np.ndarray:
    """``points`` values from ``from`` to ``to``: from + k (to − from) / (points − 1)."""
    n = spec["points"]
    step = (spec["to"] - spec["from"]) / (n - 1) if n > 1 else 0.0
    return np.array([spec["from"] + k * step for k in range(n)])


@given(jobs())
@settings(max_examples=200, deadline=None)
def test_tiles_cover_every_cell_exactly_once_in_consecutive_chains(job):
    chains, cells = job.shape
    size = job.tiles.rows
    tiles = plan_tiles(job)
    assert len(tiles) == math.ceil(chains / size)
    assert [t.index for t in tiles] == list(range(len(tiles)))
    count = np.zeros(job.shape, int)
    for tile in tiles:
        count[tile.rows, :] += 1
        assert tile.n_rows == tile.row_stop - tile.row_start
        assert 1 <= tile.n_rows <= size
    assert (count == 1).all()
    # consecutive chains, every tile full but the last
    assert tiles[0].row_start == 0 and tiles[-1].row_stop == chains
    assert all(a.row_stop == b.row_start for a, b in zip(tiles[:-1], tiles[1:], strict=True))
    assert all(t.n_rows == size for t in tiles[:-1])
    assert tiles[-1].n_rows == chains - size * (len(tiles) - 1)


@given(jobs())
@settings(max_examples=50, deadline=None)
def test_the_plan_depends_on_the_job_alone(job):
    """Not on the store, nor on anything but the grid and tiles.rows: a rerun, a resume
    on other ranks or a copy of the job to another store plan the same tiles."""
    again = Job.from_dict({**job.to_dict(), "store": "elsewhere.zarr", "name": "other"})
    assert plan_tiles(again) == plan_tiles(job)


@given(jobs(), st.data())
@settings(max_examples=200, deadline=None)
def test_pending_tiles_are_the_unset_ones_in_index_order(job, data):
    n = len(plan_tiles(job))
    done = np.array(data.draw(st.lists(st.booleans(), min_size=n, max_size=n)), bool)
    pending = pending_tiles(job, done)
    assert [t.index for t in pending] == [i for i in range(n) if not done[i]]
    # a pending tile is the planned tile, rows and all
    assert all(t == plan_tiles(job)[t.index] for t in pending)
    assert pending_tiles(job, np.ones(n, bool)) == []
    assert pending_tiles(job, np.zeros(n, bool)) == plan_tiles(job)


def test_a_done_mask_of_another_job_is_refused():
    job = Job.from_dict(plane_job("x", (6, 1, 3), ("mu_cn", 0.9, 0.5, 10), tiles={"rows": 4}))
    assert len(plan_tiles(job)) == 3  # ⌈10 / 4⌉
    for shape in [(2,), (4,), (3, 1)]:
        with pytest.raises(ValueError, match="the job has 3 tiles"):
            pending_tiles(job, np.zeros(shape, bool))


@given(jobs(), st.data())
@settings(max_examples=200, deadline=None)
def test_a_chain_runs_through_omega_in_its_direction_at_one_second_value(job, data):
    data_in = job.to_dict()
    second = job.second
    row = data.draw(st.integers(0, job.shape[0] - 1))
    par = chain_parameters(job, row)
    assert set(par) == {"omega", *SECONDS}
    # every ω of the axis once, decreasing (down) or increasing (up)
    omega = sorted(axis(data_in["sweep"]["omega"]), reverse=job.chains.direction == "down")
    np.testing.assert_allclose(par["omega"], omega, rtol=1e-12, atol=1e-12)
    # chain_order maps the chain's cells to the stored (axis-order) columns, each once
    order = chain_order(job)
    assert sorted(order) == list(range(len(omega)))
    np.testing.assert_array_equal(job.omega[order], par["omega"])
    # the second parameter is this chain's value throughout; the rest are the base values
    value = axis(data_in["sweep"][second])[row]
    np.testing.assert_allclose(par[second], value, rtol=1e-12, atol=1e-12)
    for name in SECONDS:
        assert par[name].shape == (len(omega),)
        if name != second:
            assert (par[name] == BASE[name]).all(), name


@given(jobs())
@settings(max_examples=100, deadline=None)
def test_the_first_column_runs_along_the_second_axis_where_every_chain_starts(job):
    """chains.start: continue seeds each row from this chain: the second parameter from
    ``from`` to ``to``, at the ω every row's chain starts with (its largest going down)."""
    data_in = job.to_dict()
    par = first_column_parameters(job)
    omega = axis(data_in["sweep"]["omega"])
    start = omega.max() if job.chains.direction == "down" else omega.min()
    assert par["omega"].shape == (job.shape[0],)
    np.testing.assert_allclose(par["omega"], start, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(
        par[job.second], axis(data_in["sweep"][job.second]), rtol=1e-12, atol=1e-12
    )
    for name in SECONDS:
        if name != job.second:
            assert (par[name] == BASE[name]).all(), name


def test_the_papers_plane_chains_run_from_its_starting_corner():
    """jobs/mu_cn.yaml (read as plain YAML here): every chain runs ω from 6.0 down to 0.02,
    the first from μcn's ``from``, the last at its ``to``."""
    from pathlib import Path

    import yaml

    from campar.sweep.job import load_job

    path = Path(__file__).resolve().parents[1] / "jobs" / "mu_cn.yaml"
    raw = yaml.safe_load(path.read_text())["sweep"]
    job = load_job(path)
    first, last = chain_parameters(job, 0), chain_parameters(job, job.shape[0] - 1)
    assert (first["omega"][0], raw["omega"]["from"]) == (6.0, 6.0)
    assert first["omega"][-1] == pytest.approx(0.02)
    assert (np.diff(first["omega"]) < 0).all()
    assert first["mu_cn"][0] == raw["mu_cn"]["from"]
    assert last["mu_cn"][0] == pytest.approx(raw["mu_cn"]["to"])


# -- tiles.rows: auto --------------------------------------------------------------------


@given(
    rows=st.integers(1, 5000),
    columns=st.integers(1, 5000),
    lanes=st.integers(1, 2000),
    direct=st.booleans(),
)
@settings(max_examples=300, deadline=None)
def test_auto_tile_rows_keep_the_master_paced_and_balance_where_the_grid_allows(
    rows, columns, lanes, direct
):
    from campar.sweep.plan import COMMITS_PER_SECOND, TILES_PER_LANE, WRITER_HEADROOM

    job = Job.from_dict(
        {
            "name": "auto",
            "tiles": {"rows": "auto"},
            "sweep": {
                "omega": {"from": 6.0, "to": 1.0, "points": columns},
                "mu_cn": {"from": 0.9, "to": 0.6, "points": rows},
            },
        }
    )
    chosen, why = auto_tile_rows(job, lanes, direct)
    assert 1 <= chosen <= rows
    tile_seconds = chosen * columns * cell_seconds(job)
    paced = lanes / tile_seconds <= COMMITS_PER_SECOND[direct] / WRITER_HEADROOM * (1 + 1e-9)
    n_tiles = -(-rows // chosen)
    balanced = n_tiles >= TILES_PER_LANE * lanes
    assert paced or chosen == rows  # the master keeps up, unless a tile is the whole grid
    if paced and chosen > 1 and not balanced:  # a smaller tile would break the pace
        smaller = (chosen - 1) * columns * cell_seconds(job)
        limit = COMMITS_PER_SECOND[direct] / WRITER_HEADROOM * (1 - 1e-9)  # ceil's rounding
        assert lanes / smaller > limit or chosen <= 4
        assert "some idle at the end" in why or chosen <= 4


def test_auto_tile_rows_keep_the_default_where_it_works_and_grow_for_many_ranks():
    job = Job.from_dict(
        {
            "name": "plane",
            "tiles": {"rows": "auto"},
            "sweep": {
                "omega": {"from": 6.0, "to": 0.02, "points": 400},
                "mu_cn": {"from": 0.95, "to": 0.70, "points": 400},
            },
        }
    )
    assert auto_tile_rows(job, 2, True)[0] == 4  # the layout of jobs/mu_cn.yaml
    assert auto_tile_rows(job, 64, False)[0] > auto_tile_rows(job, 64, True)[0] > 4
    with pytest.raises(ValueError, match="chosen when its store is created"):
        plan_tiles(job)
    assert plan_tiles(job.with_tile_rows(7))[-1].row_stop == 400
    assert job.with_tile_rows(7).tiles.rows == 7
