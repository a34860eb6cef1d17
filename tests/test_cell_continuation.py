"""Continuation from a stored cell and from a Model: ``StoredCell.continue_`` starts on the
cycle ``campar continue`` starts on at the same cell, and ``continue_from_cell`` continues
the Model it is given (its parameters, not the paper's), its first cycle the one
``find_cycle`` solves for on that Model."""

import json

import numpy as np
import pytest

import campar
import campar.cli
from campar.continuation.orbit import find_cycle
from campar.model import Model
from campar.sweep.job import cell_job
from campar.views.continuation import continue_from_cell
from campar.views.point import simulate_point

# A 3-cycle off the paper's μkn (the paper's own value gives another motion at ω = 6).
MODEL = Model.build(omega=6.0, mu_kn=0.91)
END = 5.95  # a short window: the start is what is compared


@pytest.fixture(scope="module")
def stored_cell(tmp_path_factory):
    path = tmp_path_factory.mktemp("cell") / "cell.zarr"
    campar.run(cell_job(MODEL), store=path)
    return campar.cell(path)


def test_a_stored_cell_continues_from_the_cycle_campar_continue_starts_on(stored_cell, capsys):
    result = stored_cell.continue_("omega", END)
    argv = ["continue", "--omega", f"6:{END}", "--mu-kn", "0.91", "--json"]
    assert campar.cli.main(argv) == 0
    command = json.loads(capsys.readouterr().out)
    assert result.start.label == command["start"]["label"] == "3-1"
    assert result.start.parameters["mu_kn"] == 0.91
    assert np.allclose(result.start.sections, command["start"]["sections"], rtol=0, atol=1e-10)
    # the same branch: the same steps to the window's end
    last = command["branch"]["points"][-1]
    assert result.root.values[-1] == pytest.approx(last["value"], abs=1e-10)
    assert np.allclose(result.root.sections[-1], last["sections"], rtol=0, atol=1e-8)


def test_continuing_a_model_starts_on_that_models_cycle():
    result = continue_from_cell("omega", (6.0, END), {}, model=MODEL)
    assert result.start.parameters == pytest.approx(MODEL.parameters)
    guess = simulate_point(MODEL).state
    reference = find_cycle(3, guess, model=MODEL, **MODEL.parameters)
    assert result.start.label == reference.label == "3-1"
    assert np.allclose(result.start.sections, reference.sections, rtol=0, atol=1e-10)


def test_fixed_parameters_take_precedence_over_the_models():
    paper = MODEL.replace(mu_kn=0.8)
    result = continue_from_cell("omega", (6.0, END), {"mu_kn": 0.91}, model=paper)
    assert result.start.parameters["mu_kn"] == 0.91
    assert result.start.label == "3-1"
