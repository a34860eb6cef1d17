"""`campar plot A B` (side by side, --diff), `--what n` and `p`, misspelled flags, and what
`line --help` says."""

import numpy as np
import pytest
import yaml
from matplotlib.collections import QuadMesh

import campar
from campar.cli import main
from campar.core.codes import Kind
from campar.sweep.job import Job

GRID = {
    "name": "pair",
    "sweep": {
        "omega": {"from": 1.6, "to": 0.4, "points": 9},
        "mu_cn": {"from": 0.99, "to": 0.88, "points": 3},
    },
    "tiles": {"rows": 1},
}


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    """One grid under the clamp and under the paper's unclamped law."""
    root = tmp_path_factory.mktemp("pair")
    path = root / "pair.yaml"
    path.write_text(yaml.safe_dump(GRID, sort_keys=False))
    for law in ("clamp", "allow"):
        assert (
            main(
                [
                    "run",
                    str(path),
                    "--store",
                    str(root / f"{law}.zarr"),
                    "--set",
                    f"model.tensile={law}",
                ]
            )
            == 0
        )
    return root / "clamp.zarr", root / "allow.zarr"


def test_diff_counts_the_cells_whose_labels_differ(pair, tmp_path, capsys):
    a, b = pair
    out = tmp_path / "diff.png"
    assert main(["plot", str(a), str(b), "--diff", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    with campar.open(a) as da, campar.open(b) as db:  # the labels xarray reads, compared here
        differ = int((da["label"].values != db["label"].values).sum())
    assert 0 < differ < 27  # the laws disagree somewhere on this grid, not everywhere
    assert printed.startswith(f"{differ} of 27 cells computed in both differ in their labels")
    assert out.stat().st_size > 0


def test_two_stores_side_by_side(pair, tmp_path, capsys):
    a, b = pair
    out = tmp_path / "both.png"
    assert main(["plot", str(a), str(b), "--what", "dc", "-o", str(out)]) == 0
    assert capsys.readouterr().out.strip() == f"wrote {out}"
    from campar.views.plot import plot_compare

    result = plot_compare(a, b, "labels", tmp_path / "labels.png")
    assert result.compared == 27 and result.differ is None


def test_two_maps_of_different_grids_are_refused_in_one_line(pair, tmp_path, capsys):
    a, _ = pair
    other = tmp_path / "other.yaml"
    other.write_text(yaml.safe_dump(GRID, sort_keys=False))
    store = tmp_path / "other.zarr"
    assert main(["run", str(other), "--store", str(store), "--set", "sweep.omega.points=5"]) == 0
    capsys.readouterr()
    assert main(["plot", str(a), str(store), "--diff", "-o", str(tmp_path / "x.png")]) != 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "are maps of different grids" in err
    assert not (tmp_path / "x.png").exists()
    assert main(["plot", str(a), "--diff"]) == 2  # --diff needs two stores


@pytest.mark.parametrize("what", ["n", "p"])
def test_n_and_p_maps_draw_the_periodic_cells_values(what):
    job = Job.from_dict(GRID)
    rng = np.random.default_rng(1)
    kind = np.where(rng.random(job.shape) < 0.3, Kind.CHAOTIC, Kind.PERIODIC).astype(np.int8)
    arrays = {"kind": kind, "n": rng.integers(1, 9, job.shape), "p": rng.integers(0, 6, job.shape)}
    from campar.views.plot import plot_map

    figure = plot_map(job, arrays, what)
    (mesh,) = [c for c in figure.axes[0].collections if isinstance(c, QuadMesh)]
    drawn = mesh.get_array()  # rows: second increasing; columns: ω increasing (the job's order
    periodic = kind == Kind.PERIODIC  # is ω decreasing; the mesh takes the job's order as is)
    values = np.ma.masked_invalid(np.where(periodic, arrays[what], np.nan))
    np.testing.assert_array_equal(np.ma.getmaskarray(drawn).reshape(job.shape), ~periodic)
    np.testing.assert_array_equal(drawn.reshape(job.shape)[periodic], values[periodic])


def test_plot_what_n_and_p_from_a_store(pair, tmp_path):
    a, _ = pair
    for what in ("n", "p"):
        out = tmp_path / f"{what}.png"
        assert main(["plot", str(a), "--what", what, "-o", str(out)]) == 0 and out.exists()


@pytest.mark.parametrize(
    "argv, hint",
    [
        (["point", "--omega", "3", "--mukn", "0.8"], "did you mean --mu-kn"),
        (["line", "--omega", "3:2", "--cam-velocty", "literal"], "did you mean --cam-velocity"),
        (["run", "job.yaml", "--dryrun"], "did you mean --dry-run"),
        (["pont", "--omega", "3"], "did you mean point"),
    ],
)
def test_a_misspelled_flag_names_the_one_meant_with_its_commands_usage(argv, hint, capsys):
    with pytest.raises(SystemExit) as exit:
        main(argv)
    assert exit.value.code == 2
    err = capsys.readouterr().err
    assert hint in err
    command = argv[0] if argv[0] != "pont" else None
    assert err.startswith(f"usage: campar {command} " if command else "usage: campar ")


def test_an_abbreviated_flag_is_not_taken_for_a_whole_one(capsys):
    with pytest.raises(SystemExit):
        main(["point", "--omega", "3", "--revol", "10"])
    assert "unrecognized arguments: --revol 10 (did you mean --revolutions?)" in (
        capsys.readouterr().err
    )


def test_line_help_says_where_the_line_starts(capsys):
    with pytest.raises(SystemExit):
        main(["line", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "It starts at the larger ω of --omega from rest, (y, y') = (0, 0) at θ = 0" in text
