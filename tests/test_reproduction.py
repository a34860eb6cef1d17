"""From the map to the cell: ``campar point --from`` and ``campar.cell`` reproduce every stored
variable of a map's cell bit for bit (the chain replayed from its start), on stores of a
paper plane, a design job with a non-default law and angles, a paper-literal ``tensile:
allow`` job and a plane run both ways, in Zarr and HDF5; a store another kernel wrote is
refused in one line unless ``--recompute``."""

import json
from pathlib import Path

import numpy as np
import pytest

import campar
import campar.cli
from campar.core.codes import Kind, cell_label
from campar.model import Model
from campar.sweep.job import cell_job, load_job
from campar.sweep.overrides import with_settings

JOBS = Path(__file__).resolve().parents[1] / "jobs"
SMALL = {"sweep.omega.points": 12, "tiles.rows": 4}
# (job file, its second axis, the store's suffix): 12 × 8 grids of the real jobs.
STORES = [
    ("mu_cn.yaml", "mu_cn", ".zarr"),  # a paper plane: 2-D continuation, multipliers
    ("design_rise_cycloidal.yaml", "phi1", ".h5"),  # cycloidal laws, swept rise angle, separation
    ("mu_cn_literal.yaml", "mu_cn", ".h5"),  # tensile: allow, the paper's literal formula
    ("mu_kn_both.yaml", "mu_kn", ".zarr"),  # both directions, sections
]
CELLS_PER_STORE = 26  # 104 cells in all


@pytest.fixture(scope="module")
def stores(tmp_path_factory):
    root = tmp_path_factory.mktemp("stores")
    out = []
    for name, second, suffix in STORES:
        job = with_settings(load_job(JOBS / name), {**SMALL, f"sweep.{second}.points": 8})
        path = root / f"{job.name}{suffix}"
        campar.run(job, store=path)
        out.append((job, path))
    return out


def test_a_hundred_random_cells_reproduce_bit_for_bit(stores):
    rng = np.random.default_rng(35)
    checked = 0
    for job, path in stores:
        rows, cols = job.shape
        with campar.open(path) as ds:  # the store's values, read independently of campar.cell
            arrays = {name: ds[name].values for name in ds.data_vars}
        for _ in range(CELLS_PER_STORE):
            row, col = int(rng.integers(rows)), int(rng.integers(cols))
            direction = str(rng.choice(["down", "up"])) if job.chains.direction == "both" else None
            coords = {job.first: job.first_values[col], job.second: job.second_values[row]}
            stored = campar.cell(path, direction=direction, **coords)
            assert (stored.row, stored.col) == (row, col)
            assert stored.current_kernel
            layer = () if direction is None else (("down", "up").index(direction),)
            for name, value in stored.stored.items():
                if name not in ("kind", "status", "flags"):  # codes: decoded in the Dataset
                    np.testing.assert_array_equal(value, arrays[name][(*layer, row, col)], name)
            assert stored.differences() == {}, (job.name, row, col, direction)
            checked += 1
    assert checked >= 100


def test_point_from_a_design_store_gives_its_label_duty_cycle_and_extremes(stores, capsys):
    job, path = stores[1]
    assert job.model.cam.rise == "cycloidal" and "phi1" in job.sweep
    row, col = 5, 4
    argv = ["point", "--from", str(path), "--omega", str(job.omega[col])]
    assert campar.cli.main([*argv, "--phi1", str(job.second_values[row]), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    stored = campar.cell(path, omega=job.omega[col], phi1=job.second_values[row]).stored
    label = cell_label(Kind(int(stored["kind"])), int(stored["n"]), int(stored["p"]))
    assert data["label"] == label
    assert data["eps_min"] == stored["eps_min"] and data["eps_max"] == stored["eps_max"]
    assert data["cell"]["reproduced"] and data["cell"]["changed"] == []
    assert data["model"]["model"]["cam"]["phi1"] == job.second_values[row]
    # the duty cycle, which this job does not store: the cycle's, simulated from its state
    point = campar.simulate_point(job.cell_model(row, col), state=stored["state"])
    assert point.label == label
    assert data["dc"] == pytest.approx(point.dc, abs=1e-6)


def test_point_from_prints_the_cell_and_says_it_reproduces(stores, capsys):
    job, path = stores[0]
    argv = ["point", "--from", str(path), "--omega", "3", "--mu-cn", "0.8"]
    assert campar.cli.main(argv) == 0
    out = capsys.readouterr().out
    assert "bit for bit" in out and f"of {path}" in out
    assert campar.cli.main([*argv, "--cycle", "1"]) == 0
    assert "cycle" in capsys.readouterr().out


def test_a_store_of_another_kernel_is_named_and_recomputed_on_request(stores, capsys, monkeypatch):
    job, path = stores[0]
    import campar.core.version
    import campar.views.cell

    written_by = campar.core.version.KERNEL_VERSION
    monkeypatch.setattr(campar.core.version, "KERNEL_VERSION", 999)
    monkeypatch.setattr(campar.views.cell, "KERNEL_VERSION", 999)
    argv = ["point", "--from", str(path), "--omega", "3", "--mu-cn", "0.8"]
    assert campar.cli.main(argv) == 2
    err = capsys.readouterr().err
    assert f"kernel version {written_by}, this campar's is 999" in err and err.count("\n") == 1
    real = campar.views.cell.StoredCell.replay

    def changed(self):
        values = real(self)
        return {**values, "dc": values["dc"] + 0.5}

    monkeypatch.setattr(campar.views.cell.StoredCell, "replay", changed)
    assert campar.cli.main([*argv, "--recompute"]) == 0
    out = capsys.readouterr().out
    assert f"computed with kernel 999 (the store's: {written_by}); changed: dc:" in out


def test_from_refuses_what_would_change_the_stored_model(stores, capsys):
    job, path = stores[0]
    base = ["point", "--from", str(path), "--omega", "3", "--mu-cn", "0.8"]
    assert campar.cli.main([*base, "--rtol", "1e-9"]) == 2
    assert "--rtol would change it" in capsys.readouterr().err
    # a flag not named by its key's last part (transient.max_revolutions)
    assert campar.cli.main([*base, "--revolutions", "3000"]) == 2
    assert "--revolutions would change it" in capsys.readouterr().err
    assert campar.cli.main(["point", "--from", str(path), "--omega", "3"]) == 2
    assert "give --mu-cn too" in capsys.readouterr().err
    assert campar.cli.main([*base, "--zeta", "0.3"]) == 2
    assert "zeta is not an axis of its grid" in capsys.readouterr().err


def test_a_point_with_cycloidal_laws_is_the_cell_of_its_one_cell_map(tmp_path, capsys):
    argv = ["point", "--omega", "2", "--rise", "cycloidal", "--fall", "cycloidal", "--json"]
    assert campar.cli.main(argv) == 0
    point = json.loads(capsys.readouterr().out)
    model = Model.build(omega=2.0, rise="cycloidal", fall="cycloidal")
    path = campar.run(
        cell_job(model, outputs=("label", "dc", "eps", "pn")), store=tmp_path / "c.zarr"
    )
    stored = campar.cell(path).stored
    for name in ("dc", "eps_min", "eps_max", "pn_max", "revolutions", "steps", "n", "p"):
        assert point[name] == stored[name], name
    assert point["state"] == stored["state"].tolist()
    assert point["model"]["model"]["cam"]["rise"] == "cycloidal"


def test_a_stored_cell_simulates_solves_finds_attractors_and_plots(stores, tmp_path):
    job, path = stores[0]
    stored = campar.cell(path, omega=3.0, mu_cn=0.8)
    result = stored.simulate(trace=True)
    assert result.trace is not None and result.state == stored.state
    if result.n:
        orbit = stored.cycle()
        assert orbit.n == result.n
        # the cell's final state lies on its cycle: within the transient's tolerance
        gaps = np.abs(np.array(orbit.sections) - np.array(stored.state)).max(axis=1)
        assert gaps.min() < 1e-5
    census = stored.attractors(4)
    assert any(a.label == result.label for a in census.attractors)
    stored.plot(tmp_path / "orbit.png")
    assert (tmp_path / "orbit.png").stat().st_size > 1000
