"""Typed bifurcation edges of a map (``campar.views.boundaries``, ``campar plot
--bifurcations``): every type at its edge of a constructed map, nothing guessed where the
data cannot tell, the curves on the figure, and a period doubling of a computed map whose
multiplier SciPy's central-difference Jacobian of the section map confirms
(``campar.bench.scipy_model``, an implementation outside campar)."""

import json

import numpy as np
import pytest
from matplotlib.collections import LineCollection
from matplotlib.colors import to_rgb
from matplotlib.legend import Legend
from test_transitions import section_jacobian

from campar.bench.scipy_model import Model
from campar.cli import main
from campar.views.boundaries import (
    NO_MULTIPLIERS,
    TYPES,
    find_boundaries,
    half_gaps,
    store_boundaries,
)
from campar.views.line import bifurcation_line
from campar.views.plot import PlotError, plot_map
from campar.views.plot.curves import CURVE_STYLES
from campar.views.plot.maps import MapGrid
from campar.views.transitions import NEAR, REACH, half_gap

# -- a constructed 3 × 6 map ------------------------------------------------------------------

P, QP, CH = 0, 1, 2  # kinds
OMEGA = np.array([6.0, 5.0, 4.0, 3.0, 2.0, 1.0])  # job order: chains run ω down
SECOND = np.array([0.9, 0.8, 0.7])
STABLE = ((0.3, 0), (0.1, 0))  # multipliers well inside the unit circle
FAR = (-0.4, 0.4)  # ε extremes far from 0 (a deep flight and a deep contact)

# (label, kind, n, p, multipliers ((re, im), (re, im)), (eps_min, eps_max), lyapunov)
CELLS = [
    [  # 1-1 doubles (λ → −1 at column 1); 2-2 enters chaos at column 4
        ("1-1", P, 1, 1, ((-0.9, 0), (0.1, 0)), FAR, -0.1),
        ("1-1", P, 1, 1, ((-0.99, 0), (0.1, 0)), FAR, -0.01),
        ("2-2", P, 2, 2, STABLE, FAR, -0.2),
        ("2-2", P, 2, 2, STABLE, FAR, -0.2),
        ("chaos", CH, 0, 9, None, FAR, 0.05),
        ("chaos", CH, 0, 9, None, FAR, 0.06),
    ],
    [  # a complex pair reaches |λ| = 1 (NS), QP → 1-2 (nothing to tell), 1-2 → 1-1 (p changes
        # with no stored extremum near 0: a grazing elsewhere is not excluded)
        ("1-1", P, 1, 1, ((0.54, 0.72), (0.54, -0.72)), FAR, -0.1),
        ("1-1", P, 1, 1, ((0.594, 0.792), (0.594, -0.792)), FAR, -0.01),
        ("QP", QP, 0, 3, None, FAR, 0.0),
        ("1-2", P, 1, 2, STABLE, FAR, -0.2),
        ("1-2", P, 1, 2, STABLE, FAR, -0.2),
        ("1-1", P, 1, 1, STABLE, FAR, -0.2),
    ],
    [  # a fold of 3-2 (λ → +1), a grazing into 1-0 (a flight 1e-4 deep), a jump 1-0 → 2-0
        ("3-2", P, 3, 2, ((0.8, 0), (0.1, 0)), FAR, -0.1),
        ("3-2", P, 3, 2, ((0.97, 0), (0.1, 0)), FAR, -0.01),
        ("1-1", P, 1, 1, STABLE, (-0.01, 0.4), -0.2),
        ("1-1", P, 1, 1, STABLE, (-1e-4, 0.4), -0.2),
        ("1-0", P, 1, 0, STABLE, (0.02, 0.4), -0.2),
        ("2-0", P, 2, 0, STABLE, (0.3, 0.5), -0.2),
    ],
]

# Edges along ω, as (row, column before | column after): their type.
ALONG_OMEGA = {
    (0, 1, 2): "PD",
    (0, 3, 4): "chaos",
    (1, 1, 2): "NS",
    (1, 2, 3): "unknown",
    (1, 4, 5): "unknown",
    (2, 1, 2): "SN",
    (2, 3, 4): "G",
    (2, 4, 5): "jump",
}


def constructed_map(*, multipliers=True, lyapunov=True):
    """The arrays of CELLS, (second, omega) shaped, as a store holds them."""
    rows, cols = len(CELLS), len(CELLS[0])
    arrays = {
        "kind": np.array([[c[1] for c in row] for row in CELLS], np.int8),
        "n": np.array([[c[2] for c in row] for row in CELLS], np.int32),
        "p": np.array([[c[3] for c in row] for row in CELLS], np.int32),
        "eps_min": np.array([[c[5][0] for c in row] for row in CELLS]),
        "eps_max": np.array([[c[5][1] for c in row] for row in CELLS]),
    }
    if multipliers:
        m = np.full((rows, cols, 2, 2), np.nan)  # NaN where not periodic, as stored
        for i, row in enumerate(CELLS):
            for j, c in enumerate(row):
                if c[4] is not None:
                    m[i, j] = c[4]
        arrays["multipliers"] = m
    if lyapunov:
        arrays["lyapunov"] = np.array([[c[6] for c in row] for row in CELLS])
    return arrays


def by_edge(found):
    """{(axis, before, after): segment}."""
    return {(s.axis, s.before, s.after): s for s in found.segments}


def test_every_type_is_found_at_its_edge_of_a_constructed_map():
    found = find_boundaries(constructed_map(), OMEGA, SECOND, "mu_kn")
    edges = by_edge(found)
    for (row, a, b), expected in ALONG_OMEGA.items():
        s = edges[("omega", (row, a), (row, b))]  # before: the larger ω, computed first
        assert s.type == expected, (row, a, b, s.transition.reason)
    along_omega = [s for s in found.segments if s.axis == "omega"]
    assert len(along_omega) == len(ALONG_OMEGA)  # equal labels never make an edge
    # evidence at the last cell on the side it comes from
    pd = edges[("omega", (0, 1), (0, 2))]
    assert pd.transition.evidence.side == "before" and pd.transition.evidence.value == -0.99
    assert pd.transition.before.farther[0] == -0.9  # the next cell away, same label
    ns = edges[("omega", (1, 1), (1, 2))].transition.evidence
    assert ns.critical == "circle" and ns.distance == pytest.approx(1 - 0.99)
    g = edges[("omega", (2, 3), (2, 4))].transition.evidence
    assert g.side == "before" and g.value == pytest.approx(1e-4)  # the shallow flight
    assert "λ1 0.05" in edges[("omega", (0, 3), (0, 4))].transition.reason
    # the edge drawn: between the cell centres' midpoints, the row's full height
    assert pd.edge == pytest.approx((4.5, 0.95, 4.5, 0.85))
    assert found.counts()["PD"] >= 1 and set(found.counts()) == set(TYPES)


def test_edges_along_the_second_parameter_are_typed_alike():
    found = find_boundaries(constructed_map(), OMEGA, SECOND, "mu_kn")
    edges = by_edge(found)
    # column 1: 1-1 (row 0) | 1-1 (row 1): no edge; 1-1 (row 1) | 3-2 (row 2): the 3-2 side
    # reaches +1 (0.97) but its farther cell (row 3) does not exist, and NEAR is 0.02
    assert ("mu_kn", (0, 1), (1, 1)) not in edges
    s = edges[("mu_kn", (1, 1), (2, 1))]
    assert s.type == "NS" and s.transition.evidence.side == "before"  # row 1's complex pair
    assert s.edge == pytest.approx((5.5, 0.75, 4.5, 0.75))
    assert "mu_kn 0.8" in s.transition.reason
    # column 4: chaos (row 0) above 1-2 (row 1): chaos ends going down the rows
    chaos = edges[("mu_kn", (0, 4), (1, 4))]
    assert chaos.type == "chaos" and "mu_kn decreasing" in chaos.transition.reason


def test_without_multipliers_only_grazing_and_chaos_are_typed():
    found = find_boundaries(constructed_map(multipliers=False), OMEGA, SECOND, "mu_kn")
    edges = by_edge(found)
    for (row, a, b), expected in ALONG_OMEGA.items():
        s = edges[("omega", (row, a), (row, b))]
        assert s.type == (expected if expected in ("G", "chaos") else "unknown"), expected
    assert not found.multipliers and NO_MULTIPLIERS in found.notes
    assert {s.type for s in found.segments} <= {"G", "chaos", "unknown"}


def test_a_chaos_verdict_without_positive_lyapunov_exponent_is_not_typed_chaos():
    arrays = constructed_map()
    arrays["lyapunov"][0, 4] = -0.02
    found = find_boundaries(arrays, OMEGA, SECOND, "mu_kn")
    s = by_edge(found)[("omega", (0, 3), (0, 4))]
    assert s.type == "unknown" and "≤ 0" in s.transition.reason


def test_cells_not_computed_make_no_edge_and_chains_running_up_swap_the_sides():
    arrays = constructed_map()
    arrays["kind"][2, 4:] = -1  # a tile not committed: no G, no jump there
    found = find_boundaries(arrays, OMEGA, SECOND, "mu_kn")
    assert not [s for s in found.segments if (2, 4) in (s.before, s.after)]
    up = by_edge(find_boundaries(constructed_map(), OMEGA, SECOND, "mu_kn", direction="up"))
    pd = up[("omega", (0, 2), (0, 1))]  # computed first: the smaller ω
    assert pd.type == "PD" and pd.transition.evidence.side == "after"
    chaos = up[("omega", (0, 4), (0, 3))]
    assert chaos.type == "chaos" and "chaos ends (ω increasing" in chaos.transition.reason


def test_a_traced_orbit_tells_a_grazing_the_stored_extrema_cannot():
    arrays = constructed_map()

    def trace(row, col, revolutions):  # a new flight 1e-6 deep beside a deep one, on 1-1
        t = np.linspace(0.0, 1.0, 201)
        shallow = 1e-6 if (row, col) == (1, 5) else 0.2
        eps = 0.4 - 0.8 * np.exp(-(((t - 0.3) / 0.05) ** 2))
        eps = eps - (0.4 + shallow) * np.exp(-(((t - 0.7) / 0.05) ** 2))
        return t, eps

    found = find_boundaries(arrays, OMEGA, SECOND, "mu_kn", trace=trace)
    s = by_edge(found)[("omega", (1, 4), (1, 5))]
    assert s.type == "G" and s.transition.evidence.side == "after", s.transition.reason
    assert found.traced and not found.notes


def test_half_gaps_of_a_whole_map_are_the_lines_half_gaps():
    rng = np.random.default_rng(3)
    sections = rng.normal(size=(4, 5, 6, 2))
    n = rng.choice([0, 1, 2, 3, 4, 6, 8], size=(4, 5))  # 8 > S = 6 points kept: None
    sections[0, 0, 1] = np.nan  # a NaN-padded cell
    n[0, 0] = 2
    expected = [[half_gap(sections[i, j], int(n[i, j])) for j in range(5)] for i in range(4)]
    got = half_gaps(sections, n)
    assert np.array_equal(np.isnan(got), [[e is None for e in row] for row in expected])
    assert np.allclose(got[~np.isnan(got)], [e for row in expected for e in row if e is not None])


# -- drawn on the map -------------------------------------------------------------------------


def test_the_curves_are_drawn_on_the_label_and_duty_cycle_maps():
    arrays = constructed_map()
    found = find_boundaries(arrays, OMEGA, SECOND, "mu_kn")
    grid = MapGrid(OMEGA, SECOND, "mu_kn")
    for what, extra in (("labels", {}), ("dc", {"dc": np.full((3, 6), 0.5)})):
        figure = plot_map(grid, {**arrays, **extra}, what, curves=found)
        ax = figure.axes[0]
        drawn = [c for c in ax.collections if isinstance(c, LineCollection)]
        assert len(drawn) == len({s.type for s in found.segments} - {"unknown"})
        legend_texts = [t.get_text() for t in ax.get_legend().get_texts()]
        assert any(t.startswith("PD period doubling (") for t in legend_texts)
        assert any(t.startswith("unknown (") for t in legend_texts)
        # the label map keeps its own legend of n-p beside the curves' one
        assert any(isinstance(a, Legend) for a in ax.artists) == (what == "labels")
    pd_colour = CURVE_STYLES["PD"][1]
    (pd,) = [c for c in drawn if np.allclose(c.get_colors()[0][:3], to_rgb(pd_colour))]
    assert len(pd.get_segments()) == found.counts()["PD"]


# -- a computed map and SciPy ------------------------------------------------------------------

PD_ROWS = {"from": 0.91, "to": 0.905, "points": 2}


@pytest.fixture(scope="module")
def pd_store(tmp_path_factory):
    """Two chains of ω 2.5 → 2.2 (100 cells, as the line of test_transitions) at μkn 0.91 and
    0.905, started from rest, with multipliers: 1-1 period-doubles near ω = 2.365."""
    import yaml

    root = tmp_path_factory.mktemp("pd")
    job = {
        "name": "pd",
        "sweep": {"omega": {"from": 2.5, "to": 2.2, "points": 100}, "mu_kn": PD_ROWS},
        "outputs": ["label", "eps", "multipliers"],
        "tiles": {"rows": 1},
        "store": str(root / "pd.zarr"),
    }
    path = root / "pd.yaml"
    path.write_text(yaml.safe_dump(job, sort_keys=False))
    assert main(["run", str(path)]) == 0
    return root / "pd.zarr"


def test_a_map_period_doubling_matches_its_line_and_scipys_multiplier(pd_store):
    found = store_boundaries(pd_store)
    pd = [s for s in found.of_type("PD") if s.axis == "omega" and s.before[0] == 0]
    (s,) = pd  # on the μkn = 0.91 row
    t = s.transition
    assert (t.before.label, t.after.label) == ("2-2", "1-1")
    # the same row as a line gives the same boundary, typed alike
    line = bifurcation_line((2.5, 2.2), 100, mu_kn=0.91)
    (line_pd,) = [x for x in line.transitions if x.type == "PD"]
    assert (t.before.omega, t.after.omega) == (line_pd.before.omega, line_pd.after.omega)
    assert t.evidence.value == line_pd.evidence.value
    # SciPy: eigenvalues of a central-difference Jacobian of the section map at the stored
    # state of the evidence cell (the 1-1 side's last cell)
    assert t.evidence.side == "after" and t.evidence.distance < REACH
    col = s.after[1]
    from campar.sweep.store import read_store

    with read_store(pd_store) as store:
        state = store.read("state")[0, col]
        stored = store.read("multipliers")[0, col]
    model = Model(t.after.omega, mu_kn=0.91)
    reference = sorted(np.linalg.eigvals(section_jacobian(model, state, 1)), key=abs, reverse=True)
    mine = sorted(stored[:, 0] + 1j * stored[:, 1], key=abs, reverse=True)
    np.testing.assert_allclose(mine, reference, atol=1e-4)
    assert abs(reference[0].imag) < 1e-9 and abs(reference[0] + 1) < NEAR
    assert t.evidence.value == pytest.approx(reference[0].real, abs=1e-4)
    # on the μkn = 0.905 row the budget of the cell at ω 2.3636 ends next to the doubling
    # (SciPy: its 1-cycle −1.000067, its 2-cycle 0.99973): settled on the 2-cycle, and the
    # row's 2-2 meets 1-1 on a period doubling too
    (row2,) = [s for s in found.segments if s.before[0] == 1 and s.axis == "omega"]
    assert row2.type == "PD" and (row2.before, row2.after) == ((1, 45), (1, 46))
    assert (row2.transition.before.label, row2.transition.after.label) == ("2-2", "1-1")
    assert found.counts()["SN"] == 0
    # a zoom keeps the edges inside it, typed alike; tracing changes no multiplier verdict
    zoomed = store_boundaries(pd_store, omega=(2.3, 2.4), trace=True)
    assert zoomed.traced and zoomed.counts() == found.counts()
    assert all(2.3 <= min(z.edge[0], z.edge[2]) <= 2.4 for z in zoomed.segments)


def test_plot_bifurcations_json_counts_every_typed_segment(pd_store, tmp_path, capsys):
    out = tmp_path / "pd.png"
    assert main(["plot", str(pd_store), "--bifurcations", "--json", "-o", str(out)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["multipliers"] and sum(data["counts"].values()) == len(data["segments"])
    assert data["counts"]["PD"] >= 1 and set(data["counts"]) == set(TYPES)
    (pd,) = [
        s
        for s in data["segments"]
        if s["type"] == "PD" and s["axis"] == "omega" and s["cells"][0][0] == 0
    ]
    re, im = pd["evidence"]["value"]
    assert abs(re + 1) < NEAR and im == 0.0 and pd["after"]["mu_kn"] == 0.91
    assert out.exists() and data["figure"] == str(out)
    assert main(["plot", str(pd_store), "--json", "-o", str(out)]) == 2  # needs --bifurcations
    zoomed = ["plot", str(pd_store), "--bifurcations", "--omega", "9:10", "-o", str(out)]
    assert main(zoomed) == 1 and "no cell centre of omega" in capsys.readouterr().err


def test_plot_bifurcations_json_writes_no_image_unless_asked(
    pd_store, tmp_path, monkeypatch, capsys
):
    here = tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    assert main(["plot", str(pd_store), "--bifurcations", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["figure"] is None and list(here.iterdir()) == []
    assert main(["plot", str(pd_store), "--bifurcations", "--json", "-o", "asked.png"]) == 0
    asked = json.loads(capsys.readouterr().out)
    assert asked["figure"] == "asked.png" and [p.name for p in here.iterdir()] == ["asked.png"]
    assert {**asked, "figure": None} == data


def test_a_store_of_both_sweeps_types_the_sweep_asked_for(tmp_path):
    """chains.direction both: each sweep's map typed on its own; "before" is the cell its
    chain computed first (the larger ω down, the smaller up)."""
    import yaml

    job = {
        "name": "both",
        "sweep": {
            "omega": {"from": 2.5, "to": 2.2, "points": 60},
            "mu_kn": {"from": 0.91, "to": 0.9, "points": 3},
        },
        "chains": {"direction": "both"},
        "outputs": ["label", "eps", "multipliers"],
        "tiles": {"rows": 1},
        "store": str(tmp_path / "both.zarr"),
    }
    (tmp_path / "both.yaml").write_text(yaml.safe_dump(job, sort_keys=False))
    assert main(["run", str(tmp_path / "both.yaml")]) == 0
    for direction, first in (("down", -1), ("up", 1)):
        found = store_boundaries(tmp_path / "both.zarr", direction=direction)
        along = [s for s in found.segments if s.axis == "omega"]
        assert along and all(np.sign(s.before[1] - s.after[1]) == first for s in along)
        assert found.counts()["PD"] >= 1  # 1-1 ↔ 2-2 near ω 2.36, met either way
    with pytest.raises(PlotError, match="no sideways map"):
        store_boundaries(tmp_path / "both.zarr", direction="sideways")
