"""The explorer's bifurcation lines through a map besides its rows: a column (along the
second parameter) and a segment between two cells, each one warm-started chain as
`campar line` runs one — against chains built independently of the explorer: a
one-column map run by the sweep machinery (``chains.start: continue`` starts each row
from the final state of the row before), and a chain of `campar point` cells each
started from the final state of the one before."""

import numpy as np
import pytest
from support.http import get, refused
from support.jobs import EXPLORE_MAP, computed_store

import campar
from campar.errors import CamparError
from campar.explore.lines import column_line, segment_line
from campar.explore.server import serve, shutdown
from campar.views.point import simulate_point

JOB = {**EXPLORE_MAP, "name": "lines"}
SIGMA_TOL = 1e-6  # σn points of one cycle reached from two nearby starts


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    return computed_store(tmp_path_factory, JOB)[0]


def same_cycles(labels, got, expected):
    """Where both cells are the same n-cycle, their σn points y agree (in any order)."""
    compared = 0
    for i, label in enumerate(labels):
        n = int(label.split("-")[0]) if label[0].isdigit() else 0
        if n:
            a = sorted(y for x, y in got if x == i)
            assert np.allclose(a, sorted(expected[i][:n]), atol=SIGMA_TOL), (i, a, expected[i])
            compared += 1
    return compared


def by_cell(line: dict) -> list:
    """The line's σn points as (cell index, y)."""
    index = {x: i for i, x in enumerate(line["first"])}
    return [(index[x], y) for x, y in line["points"]]


def test_a_column_is_the_chain_down_the_column(store, tmp_path):
    col = 3
    ds = campar.open(store)
    line = column_line(store, col)
    assert line["along"] == "column" and line["x"] == "mu_cn"
    assert line["first"] == pytest.approx(ds.mu_cn.values.tolist(), abs=1e-15)
    assert line["values"]["omega"] == [float(ds.omega[col])] * 6
    y, v = (float(a) for a in ds.state.values[0, col])
    reference = tmp_path / "column.zarr"
    campar.run(
        {
            **JOB,
            "name": "column",
            "sweep": {
                "omega": {"from": float(ds.omega[col]), "to": float(ds.omega[col]), "points": 1},
                "mu_cn": JOB["sweep"]["mu_cn"],
            },
            "initial": {"y": y, "v": v},
            "chains": {"start": "continue"},
            "outputs": ["label", "sections"],
            "classify": {"sections": 64},
            "store": str(reference),
        }
    )
    ref = campar.open(reference)
    labels = ref.label.values[:, 0].tolist()
    assert line["labels"] == labels
    sections = ref.sections.values[:, 0, :, 0]
    assert same_cycles(labels, by_cell(line), sections) >= 4


def test_a_segment_is_a_warm_started_chain_between_its_cells(store):
    ds = campar.open(store)
    a, b = (0, 0), (5, 11)
    line = segment_line(store, a, b)
    assert line["along"] == "segment" and line["x"] == "omega"  # 11 columns, 5 rows
    omega, mu = np.array(line["values"]["omega"]), np.array(line["values"]["mu_cn"])
    assert len(omega) == 12
    assert (omega[0], mu[0]) == (float(ds.omega[0]), float(ds.mu_cn[0]))
    assert (omega[-1], mu[-1]) == pytest.approx((float(ds.omega[11]), float(ds.mu_cn[5])))
    for values in (omega, mu):  # evenly spaced between the cells' centres
        assert np.allclose(np.diff(values), np.diff(values)[0])
    state = tuple(float(s) for s in ds.state.values[0, 0])
    labels, sections = [], []
    for w, m in zip(omega, mu, strict=True):
        cell = simulate_point(float(w), mu_cn=float(m), state=state)
        labels.append(cell.label)
        sections.append(np.asarray(cell.sections)[:, 0])
        state = tuple(cell.state)
    assert line["labels"] == labels
    assert same_cycles(labels, by_cell(line), sections) >= 6


def test_a_segment_along_a_column_is_that_column(store):
    column = column_line(store, 7)
    segment = segment_line(store, (0, 7), (5, 7))
    assert segment["x"] == "mu_cn"
    for key in ("labels", "points", "first", "values"):
        assert segment[key] == column[key], key


def test_a_segment_needs_two_cells_and_a_sane_count(store):
    with pytest.raises(CamparError, match="two different cells"):
        segment_line(store, (1, 1), (1, 1))
    with pytest.raises(CamparError, match="2 to 2000 points"):
        segment_line(store, (0, 0), (1, 1), points=1)


@pytest.mark.parametrize(
    "query",
    [
        "/api/line?along=diagonal&row=0&col=0",
        "/api/line?along=segment&row=0&col=0",
        "/api/line?along=segment&row=0&col=0&row2=9&col2=1",
        "/api/line?along=segment&row=0&col=0&row2=1&col2=1&points=1",
        "/api/line?along=segment&row=0&col=0&row2=1&col2=1&points=99999",
        "/api/line?along=column",
        "/api/line?along=column&col=12",
        "/api/line?along=row&row=0&along=column&col=1",
        "/api/branch?row=0&col=0&along=segment",
    ],
)
def test_a_malformed_line_request_gets_one_line(store, query):
    server = serve([store], warm_up=False)
    try:
        refused(server, query, 400, "400 Bad Request: ")
        assert get(server, "/api/stores")[0] == 200  # the server goes on
    finally:
        shutdown(server)
