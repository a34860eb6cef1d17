"""Map figures: categories and their fixed colours, gaps, zoom, cell geometry, CLI."""

import io
import itertools
import subprocess
import sys
import time
from collections import Counter

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import QuadMesh
from matplotlib.colors import to_rgba
from matplotlib.patches import Rectangle

from campar.cli import main
from campar.core.codes import CHAOTIC, PERIODIC, QUASIPERIODIC, cell_label
from campar.core.codes import FAILED as KIND_FAILED
from campar.sweep.job import Job
from campar.sweep.plan import plan_tiles
from campar.views.plot import MAP_VIEWS, PlotError, parse_range, plot_store
from campar.views.plot.cells import cell_runs
from campar.views.plot.colour import srgb_to_lab
from campar.views.plot.labels import (
    DESIGNED,
    FAILED,
    GAP_STYLE,
    NOT_COMPUTED,
    category_of,
    distinct_categories,
    fallback_colour,
    label_colour,
    legend_text,
    map_kinds,
    map_labels,
    order_key,
)
from campar.views.plot.maps import (
    LEGEND_MAX,
    QUANTITIES,
    MapGrid,
    cell_edges,
    computed_mask,
    plot_map,
    quantity_scale,
    select_cells,
)

P, QP, CH, FA = PERIODIC, QUASIPERIODIC, CHAOTIC, KIND_FAILED


def grid_of(rows, cols, second_name="mu_cn"):
    """Axes in the paper's order: ω 6.0 → 0.02, the second parameter decreasing too."""
    return MapGrid(
        np.linspace(6.0, 0.02, cols),
        np.linspace(0.99, 0.50, rows),
        second_name,
        7,
        {"f0": 0.5, "mu_kn": 0.8, "zeta": 0.2},
    )


def arrays_of(cells):
    """Arrays from a nested list of (kind, n, p) per cell, shaped (second, omega)."""
    a = np.array(cells, dtype=np.int64)
    return {
        "kind": a[..., 0].astype(np.int8),
        "n": a[..., 1].astype(np.int32),
        "p": a[..., 2].astype(np.int32),
    }


def random_map(rows, cols, seed=0):
    """Random cells over common, rare, chattering and non-periodic labels, plus quantities."""
    rng = np.random.default_rng(seed)
    kind = rng.choice([P, P, P, P, QP, CH, FA], size=(rows, cols)).astype(np.int8)
    n = rng.choice([1, 1, 1, 2, 2, 3, 4, 7], size=(rows, cols)).astype(np.int32)
    p = rng.choice([0, 1, 2, 3, 4, 7, 9], size=(rows, cols)).astype(np.int32)
    n[kind != P] = 0
    dc = rng.random((rows, cols))
    dc[kind == FA] = np.nan
    values = {
        "dc": dc,
        "eps_max": rng.random(dc.shape),
        "eps_min": rng.normal(size=dc.shape),
        "pn_max": 10 ** rng.uniform(0, 3, dc.shape),
        "revolutions": rng.integers(2, 500, dc.shape),
        "lyapunov": rng.normal(size=dc.shape),
        "hysteresis": (kind == P) & (rng.random(dc.shape) < 0.3),  # of a both-direction map
        "n_attractors": rng.integers(-1, 6, dc.shape),  # of a census (-1: not computed)
        "attractor_kind": np.where(rng.random((rows, cols, 3)) < 0.7, P, -1).astype(np.int8),
        "attractor_n": rng.choice([1, 2, 3], size=(rows, cols, 3)),
        "attractor_p": rng.choice([0, 1, 2], size=(rows, cols, 3)),
    }
    return {"kind": kind, "n": n, "p": p, **values}


def meshes(figure):
    return [c for ax in figure.axes for c in ax.collections if isinstance(c, QuadMesh)]


def drawn_colours(figure, arrays, grid):
    """RGBA of every cell of the map's mesh after drawing, shaped (second, omega, 4)."""
    figure.canvas.draw()
    mesh = meshes(figure)[0]
    return np.asarray(mesh.get_facecolors()).reshape(*grid.shape, 4)


def png_bytes(figure) -> bytes:
    out = io.BytesIO()
    figure.savefig(out, format="png", dpi=100)
    return out.getvalue()


# -- categories and colours ----------------------------------------------------


def test_legend_entries_are_the_labels_present_with_their_counts():
    arrays = random_map(30, 50)
    cells = map_labels(arrays, chatter_p=7)
    naive = Counter(
        category_of(cell_label(k, n, p, 7))
        for k, n, p in zip(
            arrays["kind"].ravel(), arrays["n"].ravel(), arrays["p"].ravel(), strict=True
        )
    )
    assert {e.label: e.count for e in cells.entries} == dict(naive)
    assert sum(e.count for e in cells.entries) == arrays["kind"].size
    # every cell's category string agrees with status.cell_label
    labels = cells.labels
    for r, c in [(0, 0), (7, 13), (29, 49)]:
        k, n, p = (arrays[x][r, c] for x in ("kind", "n", "p"))
        assert labels[r, c] == category_of(cell_label(k, n, p, 7))


def test_drawn_legend_lists_exactly_the_labels_present():
    grid = grid_of(2, 3)
    arrays = arrays_of([[(P, 1, 1), (P, 2, 2), (P, 1, 1)], [(CH, 0, 40), (P, 1, 1), (P, 3, 2)]])
    figure = plot_map(grid, arrays, "labels")
    texts = [t.get_text() for t in figure.axes[0].get_legend().get_texts()]
    assert texts == ["1-1 (3)", "2-2 (1)", "3-2 (1)", "chaos (1)"]


def test_legend_is_ordered_by_n_then_p_and_chattering_after_its_n():
    arrays = arrays_of(
        [
            [
                (P, 2, 1),
                (CH, 0, 3),
                (P, 1, 9),
                (P, 10, 2),
                (P, 1, 0),
                (QP, 0, 0),
                (P, 2, 0),
                (P, 1, 2),
                (FA, 0, 0),
                (P, 2, 7),
                (P, 1, 6),
            ]
        ]
    )
    order = [e.label for e in map_labels(arrays).entries]
    assert order == [
        "1-0",
        "1-2",
        "1-6",
        "1-p~",
        "2-0",
        "2-1",
        "2-p~",
        "10-2",
        "QP",
        "chaos",
        "failed",
    ]


def test_a_label_has_the_same_colour_in_maps_with_different_label_sets():
    grid = grid_of(2, 3)
    first = arrays_of([[(P, 1, 1), (P, 2, 2), (P, 5, 3)], [(CH, 0, 0), (P, 1, 9), (P, 1, 1)]])
    second = arrays_of([[(P, 5, 3), (P, 4, 4), (QP, 0, 0)], [(P, 2, 2), (P, 3, 1), (P, 1, 12)]])
    seen = {}
    for arrays in (first, second):
        rgba = drawn_colours(plot_map(grid, arrays, "labels"), arrays, grid)
        labels = map_labels(arrays).labels
        for r, c in itertools.product(range(2), range(3)):
            seen.setdefault(labels[r, c], set()).add(tuple(np.round(rgba[r, c], 6)))
    for label in ("2-2", "5-3", "1-p~"):  # in both maps, among different neighbours
        assert len(seen[label]) == 1
        np.testing.assert_allclose(next(iter(seen[label])), label_colour(label), atol=1e-6)


def test_chattering_is_grouped_per_n():
    arrays = arrays_of([[(P, 1, 7), (P, 1, 9), (P, 1, 23), (P, 2, 8), (P, 1, 6)]])
    entries = {e.label: e.count for e in map_labels(arrays, chatter_p=7).entries}
    assert entries == {"1-6": 1, "1-p~": 3, "2-p~": 1}
    assert label_colour("1-7~") == label_colour("1-23~") == label_colour("1-p~")
    assert label_colour("1-p~") != label_colour("2-p~")
    assert legend_text("1-p~") == r"1-$\tilde{p}$"
    # the threshold follows the job's classify.chatter_p
    entries = {e.label for e in map_labels(arrays, chatter_p=5).entries}
    assert entries == {"1-p~", "2-p~"}


def delta_e(colour_a, colour_b) -> float:
    """CIE76 colour difference ΔE*ab of two colours (≈ 2.3: just noticeable)."""
    return float(np.linalg.norm(srgb_to_lab(to_rgba(colour_a)) - srgb_to_lab(to_rgba(colour_b))))


def test_designed_colours_are_pairwise_distinguishable():
    # failed and not computed share white on purpose: their hatches tell them apart
    names = [name for name in DESIGNED if name != NOT_COMPUTED]
    worst = min(delta_e(DESIGNED[a], DESIGNED[b]) for a, b in itertools.combinations(names, 2))
    assert worst >= 15.0
    assert GAP_STYLE[FAILED]["hatch"] != GAP_STYLE[NOT_COMPUTED]["hatch"]


@pytest.mark.process
def test_rare_labels_get_deterministic_colours_away_from_the_designed_ones():
    rare = [(n, p) for n in range(5, 33) for p in [*range(7), None]]
    colours = [fallback_colour(n, p) for n, p in rare]
    assert all(min(delta_e(c, d) for d in DESIGNED.values()) >= 15.0 for c in colours)
    # the same in a fresh process (no dependence on str hashing or call order)
    code = "from campar.views.plot.labels import label_colour as c; print(c('9-3'), c('7-p~'))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == f"{label_colour('9-3')} {label_colour('7-p~')}"


def test_kind_map_counts_kinds():
    arrays = arrays_of([[(P, 1, 1), (P, 2, 2), (QP, 0, 0)], [(CH, 0, 0), (FA, 0, 0), (P, 1, 0)]])
    arrays["computed"] = np.array([[True, True, True], [True, True, False]])
    entries = {e.label: e.count for e in map_kinds(arrays).entries}
    assert entries == {"periodic": 2, "QP": 1, "chaos": 1, "failed": 1, "not computed": 1}


def test_cells_not_computed_have_their_own_category():
    arrays = arrays_of([[(P, 1, 1), (P, 1, 1)], [(P, 0, 0), (P, 0, 0)]])  # zero-filled tile
    entries = {e.label: e.count for e in map_labels(arrays).entries}
    assert entries == {"1-1": 2, "not computed": 2}
    arrays = arrays_of([[(P, 1, 1), (P, 1, 1)], [(-1, -1, -1), (-1, -1, -1)]])  # a store's fill
    assert {e.label: e.count for e in map_labels(arrays).entries} == {"1-1": 2, "not computed": 2}
    assert {e.label: e.count for e in map_kinds(arrays).entries} == {
        "periodic": 2,
        "not computed": 2,
    }
    arrays["computed"] = np.array([[False, True], [True, True]])
    assert {e.label: e.count for e in map_labels(arrays).entries} == {"1-1": 1, "not computed": 3}


def test_a_crowded_legend_keeps_kinds_and_the_largest_labels():
    cells = [[(P, n, p) for n in range(1, 10) for p in range(6)] * 2 + [(CH, 0, 0), (FA, 0, 0)]]
    cells[0] += [(P, 1, 1)] * 50 + [(P, 7, 3)] * 9  # the largest rare label
    entries = map_labels(arrays_of(cells)).entries
    shown = distinct_categories(map_labels(arrays_of(cells)), LEGEND_MAX).entries
    assert len(shown) == LEGEND_MAX
    assert {"1-1", "chaos", "failed", "7-3", "other"} <= {e.label for e in shown}
    hidden = next(e for e in shown if e.label == "other").members
    assert {e.label for e in shown} - {"other"} | set(hidden) == {e.label for e in entries}
    assert [e.label for e in shown] == sorted((e.label for e in shown), key=order_key)


# -- gaps: failed and not computed cells ----------------------------------------


def test_nan_cells_are_masked_and_hatched_in_quantity_maps():
    grid = grid_of(3, 4)
    dc = np.linspace(0, 1, 12).reshape(3, 4)
    dc[1, 2] = np.nan
    computed = np.ones((3, 4), bool)
    computed[2] = False
    figure = plot_map(grid, {"dc": dc, "computed": computed}, "dc")
    ax = figure.axes[0]
    data = meshes(figure)[0].get_array()
    assert data.mask[1, 2] and data.mask[2].all() and data.mask.sum() == 5
    hatches = sorted(p.get_hatch() for p in ax.patches if isinstance(p, Rectangle))
    assert hatches == sorted([GAP_STYLE[FAILED]["hatch"], GAP_STYLE[NOT_COMPUTED]["hatch"]])
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert texts == ["no value (1)", "not computed (4)"]
    assert png_bytes(figure).startswith(b"\x89PNG")


def test_failed_cells_are_transparent_over_the_hatch_in_label_maps():
    grid = grid_of(2, 2)
    arrays = arrays_of([[(P, 1, 1), (FA, 0, 0)], [(P, 1, 1), (P, 2, 2)]])
    figure = plot_map(grid, arrays, "labels")
    data = meshes(figure)[0].get_array()
    assert data.mask.tolist() == [[False, True], [False, False]]
    assert any(p.get_hatch() == GAP_STYLE[FAILED]["hatch"] for p in figure.axes[0].patches)


def test_cell_runs_cover_a_mask_exactly_once():
    rng = np.random.default_rng(3)
    for _ in range(20):
        mask = rng.random((9, 11)) < 0.4
        mask[2:5] = True  # whole rows, like tiles not computed
        cover = np.zeros(mask.shape, int)
        for (c0, c1), (r0, r1) in cell_runs(mask):
            cover[r0:r1, c0:c1] += 1
        assert np.array_equal(cover, mask.astype(int))
    assert len(cell_runs(np.repeat([[True] * 5], 4, axis=0))) == 1


def test_diverging_quantities_are_white_at_zero_whatever_the_signs():
    quantity = QUANTITIES["eps_min"]
    for values in ([-5.0, 0.3], [-2.0, -1.0], [0.5, 2.0]):
        norm, cmap = quantity_scale(quantity, np.array(values), None, None, None)
        assert delta_e(cmap(norm(0.0)), "white") < 8


def test_log_scale_is_automatic_for_wide_positive_ranges_and_refused_otherwise():
    norm, _ = quantity_scale(QUANTITIES["pn_max"], np.array([1.0, 200.0]), None, None, None)
    assert type(norm).__name__ == "LogNorm"
    norm, _ = quantity_scale(QUANTITIES["pn_max"], np.array([1.0, 2.0]), None, None, None)
    assert type(norm).__name__ == "Normalize"
    with pytest.raises(PlotError, match="log scale"):
        quantity_scale(QUANTITIES["eps_min"], np.array([-1.0, 2.0]), True, None, None)


# -- geometry: cell-centred grid, orientation, zoom -----------------------------


def test_cell_edges_put_each_centre_in_the_middle_of_its_cell():
    for centres in (np.linspace(6.0, 0.02, 7), np.linspace(0.5, 0.99, 4), np.array([0.3])):
        edges = cell_edges(centres)
        np.testing.assert_allclose(0.5 * (edges[1:] + edges[:-1]), centres, atol=1e-12)


def test_the_mesh_is_centred_on_the_grid_and_axes_increase():
    grid = grid_of(3, 5)
    figure = plot_map(grid, arrays_of([[(P, 1, 1)] * 5] * 3), "labels")
    ax = figure.axes[0]
    coords = meshes(figure)[0].get_coordinates()  # (rows + 1, cols + 1, 2) corners
    centres = 0.25 * (coords[:-1, :-1] + coords[1:, :-1] + coords[:-1, 1:] + coords[1:, 1:])
    np.testing.assert_allclose(centres[0, :, 0], grid.omega)
    np.testing.assert_allclose(centres[:, 0, 1], grid.second)
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x0 < x1 and y0 < y1  # ω to the right and μcn upwards, though both run downwards
    assert x0 < 0.02 < x1 and x1 > 6.0
    assert r"\omega" in ax.get_xlabel() and r"\mu_{\mathrm{cn}}" in ax.get_ylabel()
    assert r"$\mu_{\mathrm{kn}}$ = 0.8" in ax.get_title(loc="left")


def test_zoom_selects_the_cells_whose_centres_lie_in_the_ranges():
    grid = grid_of(11, 21)  # ω step 0.299, second step 0.049
    values = np.arange(11 * 21, dtype=float).reshape(11, 21)
    sub, arrays = select_cells(grid, {"dc": values}, omega=(2.0, 3.5), second=(0.6, 0.8))
    cols = np.flatnonzero((grid.omega >= 2.0) & (grid.omega <= 3.5))
    rows = np.flatnonzero((grid.second >= 0.6) & (grid.second <= 0.8))
    np.testing.assert_array_equal(sub.omega, grid.omega[cols])
    np.testing.assert_array_equal(sub.second, grid.second[rows])
    np.testing.assert_array_equal(arrays["dc"], values[np.ix_(rows, cols)])
    # bounds in either order; grid values typed as bounds are inside despite rounding
    sub2, _ = select_cells(grid, {"dc": values}, omega=(3.5, 2.0), second=(0.8, 0.6))
    np.testing.assert_array_equal(sub2.omega, sub.omega)
    end, _ = select_cells(grid, {}, omega=(float(f"{grid.omega[3]:.12g}"), 6.0))
    assert len(end.omega) == 4
    with pytest.raises(PlotError, match="no cell centre of mu_cn"):
        select_cells(grid, {}, second=(0.1, 0.2))


def test_a_zoomed_figure_shows_only_the_selected_cells():
    grid = grid_of(11, 21)
    arrays = arrays_of([[(P, 1, 1)] * 10 + [(P, 2, 2)] * 11] * 11)
    figure = plot_map(grid, arrays, "labels", omega=(0.0, 2.9))  # ω columns 11 … 20
    entries = [t.get_text() for t in figure.axes[0].get_legend().get_texts()]
    assert entries == ["2-2 (110)"]  # counts are those of the zoomed panel
    edges = cell_edges(grid.omega)
    x0, x1 = figure.axes[0].get_xlim()
    assert x0 == pytest.approx(edges[-1]) and x1 == pytest.approx(edges[11])


# -- views, store, CLI -------------------------------------------------------------


@pytest.mark.parametrize("what", MAP_VIEWS)
def test_every_view_renders_headless(what):
    grid = grid_of(6, 9)
    figure = plot_map(grid, random_map(6, 9), what)
    assert isinstance(figure.canvas, FigureCanvasAgg)
    assert png_bytes(figure).startswith(b"\x89PNG")


def test_views_and_quantities_agree():
    assert set(MAP_VIEWS) == {
        "labels",
        "kind",
        "hysteresis",
        "multistability",
        "attractor_sets",
        *QUANTITIES,
    }
    with pytest.raises(PlotError, match="choose one of"):
        plot_map(grid_of(2, 2), random_map(2, 2), "steps")
    with pytest.raises(PlotError, match="needs the arrays n, p"):
        plot_map(grid_of(2, 2), {"kind": np.zeros((2, 2))}, "labels")


@pytest.mark.process
def test_importing_the_views_loads_neither_pyplot_nor_the_kernel():
    code = (
        "import sys, campar.views.plot.maps\n"
        "bad = ('matplotlib.pyplot', 'numba', 'campar.core.integrator', 'campar.core.kernel',"
        " 'campar.sweep.tile')\n"
        "print([m for m in bad if m in sys.modules])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_a_400_by_400_map_renders_to_png(tmp_path):
    rows = cols = 400
    w, s = np.meshgrid(np.linspace(6.0, 0.02, cols), np.linspace(0.95, 0.70, rows))
    p = np.clip(np.floor(9.0 * (2.2 - w) / 1.8 + 3 * (s - 0.7)), 0, 12).astype(np.int32)
    p[w > 2.2] = 1
    arrays = random_map(rows, cols)
    periodic = arrays["kind"] == P
    arrays["n"] = np.where(periodic & (np.sin(5 * w + 20 * s) > 0.7), 2, 1).astype(np.int32)
    arrays["p"] = np.where(periodic, p * arrays["n"], 0).astype(np.int32)
    arrays["kind"][np.sin(40 * w) * np.cos(60 * s) < 0.5] = P  # mostly periodic, like a real map
    grid = MapGrid(w[0], s[:, 0], "mu_kn", 7, {"f0": 0.5, "mu_cn": 0.8, "zeta": 0.2})
    for what in ("labels", "dc"):
        start = time.process_time()  # CPU: the other processes of a busy machine do not count
        path = tmp_path / f"{what}.png"
        plot_map(grid, arrays, what).savefig(path, dpi=300)
        elapsed = time.process_time() - start
        print(f"400×400 {what} map → PNG at 300 dpi: {elapsed:.2f} CPU s")
        assert path.read_bytes().startswith(b"\x89PNG")
        # one mesh: seconds; a renderer that draws cell by cell (160 000 artists): minutes.
        # The bound catches that, not a slower CPU.
        assert elapsed < 30.0


def test_parse_range():
    assert parse_range("2.5:3") == (2.5, 3.0)
    assert parse_range("6:-1e-2") == (6.0, -0.01)
    for bad in ("2.5", "a:b", "1:2:3"):
        with pytest.raises(Exception, match="expected A:B"):
            parse_range(bad)


SMOKE = {
    "name": "t",
    "tiles": {"rows": 2},
    "sweep": {
        "omega": {"from": 6.0, "to": 0.02, "points": 5},
        "mu_cn": {"from": 0.99, "to": 0.5, "points": 4},
    },
}


def test_computed_mask_marks_the_rows_of_done_tiles():
    job = Job.from_dict(SMOKE)
    mask = computed_mask(job, [False, True])
    assert mask.shape == (4, 5)
    assert not mask[:2].any() and mask[2:].all()
    with pytest.raises(PlotError, match="2 tiles"):
        computed_mask(job, [True])


@pytest.fixture(params=[".zarr", ".h5"])
def store_path(request, tmp_path):
    """A real result store of the SMOKE job (Zarr or HDF5) with its first tile committed."""
    from campar.sweep.store import cell_arrays, open_store

    job = Job.from_dict(SMOKE)
    data = random_map(4, 5, seed=1)
    arrays = {a.name: data.get(a.name, np.zeros(a.shape)).astype(a.dtype) for a in cell_arrays(job)}
    path = tmp_path / f"t{request.param}"
    with open_store(path, job) as store:
        tile = plan_tiles(job)[0]
        store.write_tile(tile, {name: a[tile.rows] for name, a in arrays.items()})
    return path


# Each view once, the backends in turn: a store is read the same way whichever view is
# drawn (its arrays by name), and a view is drawn the same way from either backend (labels
# from an HDF5 store: test_plot_store_draws_uncommitted_tiles_as_not_computed).
@pytest.mark.parametrize(
    ("store_path", "what"),
    [(".zarr", "labels"), (".h5", "dc"), (".h5", "kind")],
    indirect=["store_path"],
)
def test_cli_plot_writes_a_figure_of_a_store(store_path, tmp_path, capsys, what):
    out = tmp_path / "map.png"
    argv = ["plot", str(store_path), "--what", what, "-o", str(out), "--omega", "0:4"]
    assert main(argv) == 0
    assert out.read_bytes().startswith(b"\x89PNG")
    assert str(out) in capsys.readouterr().out


def test_plot_store_draws_uncommitted_tiles_as_not_computed(store_path, tmp_path):
    path = plot_store(store_path, "labels", tmp_path / "m.png")
    assert path.read_bytes().startswith(b"\x89PNG")
    figure = plot_map(*read_map(store_path), "labels")
    texts = [t.get_text() for t in figure.axes[0].get_legend().get_texts()]
    assert texts[-1] == "not computed (10)"  # tile 1: chains 2 and 3, 5 ω each


def read_map(path):
    from campar.sweep.store import read_store

    with read_store(path) as store:
        arrays = {name: store.read(name) for name in ("kind", "n", "p")}
        arrays["computed"] = computed_mask(store.job, store.done)
        return store.job, arrays


def test_cli_plot_reports_a_bad_request(store_path, tmp_path, capsys):
    out = str(tmp_path / "x.png")
    assert main(["plot", str(store_path), "--second", "0.1:0.2", "-o", out]) == 1
    assert "no cell centre of mu_cn" in capsys.readouterr().err
    assert main(["plot", str(store_path), "--what", "lyapunov", "-o", out]) == 1
    assert "holds no lyapunov" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["plot", "s.zarr", "--omega", "3"])
    with pytest.raises(SystemExit):
        main(["plot", "s.zarr", "--what", "sections"])
