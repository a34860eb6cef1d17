"""A curves job's tiles are the continuation's work, handed to the runner by its caller:
nothing is registered when a module is imported, and the runner refuses a curves job
without that work before anything touches the disk."""

import numpy as np
import pytest
from support.jobs import plane_job

import campar
from campar.bench import scipy_shooting
from campar.continuation.tasks import CURVES_WORK
from campar.sweep.curves_job import curves_job_data
from campar.sweep.job import Job
from campar.sweep.plan import plan_tiles
from campar.sweep.runner import run_job
from campar.sweep.tile import run_tile

MAP = plane_job(
    "tongue", (4.2, 2.2, 28), ("mu_kn", 0.93, 0.85, 10), outputs=["label", "multipliers"]
)


def curves_job(tmp_path) -> Job:
    """A curves job of one task: the 1-cycles' PD edge of a coarse (ω, μkn) map."""
    map_job = Job.from_dict(MAP)
    seed = {
        "type": "PD",
        "n": 1,
        "p": 1,
        "cell": [8, 17],
        "parameters": {"zeta": 0.2, "mu_cn": 0.8, "f0": 0.5, "omega": 2.9407, "mu_kn": 0.8589},
        "state": [0.37229608779767565, -0.8340353849465995],
        "axis": "omega",
        "neighbour": 2.8667,
        "plane": ["omega", "mu_kn"],
        "window": [[2.2, 4.2], [0.85, 0.93]],
        "spacing": [2.0 / 27, 0.08 / 9],
        "model": map_job.model.model_dump(mode="json"),
        "cells": 20,
    }
    data = curves_job_data(
        map_job, tmp_path / "map.zarr", [[seed]], types=("PD",), points=40, store=""
    )
    return Job.from_dict({**data, "store": str(tmp_path / "curves.zarr")})


def test_a_curves_job_is_refused_without_its_work_before_the_disk_is_touched(tmp_path):
    job = curves_job(tmp_path)
    with pytest.raises(ValueError, match="CURVES_WORK"):
        run_job(job)
    with pytest.raises(ValueError, match="CURVES_WORK"):
        run_tile(job, plan_tiles(job)[0])
    assert not (tmp_path / "curves.zarr").exists()
    with pytest.raises(ValueError, match="curves job"):
        run_job(Job.from_dict(MAP), tmp_path / "map.zarr", tile_work=CURVES_WORK)


def test_campar_run_hands_the_work_over_and_the_curve_is_made_of_pd_points(tmp_path):
    job = curves_job(tmp_path)
    assert campar.forecast(job).pending_cells == job.shape[0] * job.shape[1]
    campar.run(job)
    ds = campar.open(tmp_path / "curves.zarr")
    values = np.asarray(ds["curve_values"].values)[0]
    states = np.asarray(ds["curve_state"].values)[0]
    found = np.isfinite(values[:, 0])
    assert found.sum() >= 10
    for k in np.flatnonzero(found)[[0, -1]]:  # both ends: a PD point by SciPy's shooting
        parameters = {"omega": values[k, 0], "mu_kn": values[k, 1]}
        jac = scipy_shooting.jacobian(parameters, states[k], 1)
        assert abs(np.linalg.det(np.eye(2) + jac)) <= 1e-5
