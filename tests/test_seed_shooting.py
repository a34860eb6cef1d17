"""A map's curve seeds with and without its unknown edges typed by shooting
(``store_seeds(..., shoot=)``, ``campar curves --no-shoot``, the report's ``Size.shoot``).

The map is a corner of the (ω, μkn) plane across a 1-1 | 1-2 boundary whose grazings the
stored ε extrema cannot show (test_shot_edges.py checks those edges against SciPy): the
seeds without shooting are none of them, with shooting every one."""

import pytest
from support.jobs import SHOT_CORNER

from campar.sweep.job import Job
from campar.sweep.runner import run_job
from campar.views.boundaries import store_boundaries
from campar.views.map_curves import store_seeds


@pytest.fixture(scope="module")
def corner(tmp_path_factory):
    path = tmp_path_factory.mktemp("corner") / "corner.zarr"
    run_job(Job.from_dict(SHOT_CORNER), path)
    return path


def test_seeds_come_from_the_shot_edges_only_when_asked(corner):
    plain = store_boundaries(corner)
    shot = store_boundaries(corner, shoot=True)
    unknown = [s for s in plain.segments if s.type == "unknown"]
    assert len(unknown) >= 2 and plain.counts()["G"] == 0  # ε cannot show these grazings
    assert shot.counts()["unknown"] == 0 and shot.counts()["G"] == len(unknown)
    assert store_seeds(corner, ("G",), shoot=False) == []
    tasks = store_seeds(corner, ("G",))  # the default: campar curves' and the report's
    # seeds on the periodic sides of the shot edges, every shot edge seeded
    cells = {seed.cell for task in tasks for seed in task}
    assert cells <= {c for s in unknown for c in (s.before, s.after)}
    assert all({s.before, s.after} & cells for s in unknown)


def test_campar_curves_no_shoot_seeds_only_from_the_typed_edges(
    corner, tmp_path, monkeypatch, capsys
):
    """Without shooting the corner has no G edge to seed from: one line, exit 2; with it
    the job's tasks are store_seeds' (the run itself is stopped before any curve is
    continued)."""
    from campar import api
    from campar.cli import main
    from campar.paper import setups

    jobs = []

    class Stop(Exception):
        pass

    def run(job, **_):
        jobs.append(job)
        raise Stop

    monkeypatch.setattr(api, "run", run)
    args = ["curves", str(corner), "--types", "G", "--store", str(tmp_path / "c.zarr")]
    assert main([*args, "--no-shoot"]) == 2
    err = capsys.readouterr().err.strip()
    assert "no typed edge of G" in err and len(err.splitlines()) == 1
    with pytest.raises(Stop):
        main(args)
    assert [list(t) for t in jobs[0].curves.tasks] == store_seeds(corner, ("G",))
    assert setups.SIZES["small"].shoot and setups.SIZES["full"].shoot  # the report shoots
