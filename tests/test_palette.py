"""The maps' categorical palette: CIEDE2000 against its published test data, and every two
colours shown on one map ≥ 10 ΔE00 apart, with every category named in the legend."""

import itertools

import numpy as np
import pytest
from matplotlib.collections import QuadMesh
from matplotlib.colors import to_rgba
from matplotlib.patches import Rectangle

from campar.core.codes import CHAOTIC, FAILED, PERIODIC, QUASIPERIODIC, UNCONVERGED
from campar.views.plot.colour import ciede2000, delta_e00, pairwise_delta_e00, srgb_to_lab
from campar.views.plot.labels import (
    DESIGNED,
    GAP_STYLE,
    MIN_DELTA_E00,
    OTHER,
    OTHER_STYLE,
    POOL,
    distinct_categories,
    map_labels,
)
from campar.views.plot.maps import LEGEND_MAX, MapGrid, plot_map

# Sharma, Wu & Dalal (2005), Table 1: (L1, a1, b1), (L2, a2, b2), ΔE00, all 34 pairs.
SHARMA_PAIRS = [
    (50.0000, 2.6772, -79.7751, 50.0000, 0.0000, -82.7485, 2.0425),
    (50.0000, 3.1571, -77.2803, 50.0000, 0.0000, -82.7485, 2.8615),
    (50.0000, 2.8361, -74.0200, 50.0000, 0.0000, -82.7485, 3.4412),
    (50.0000, -1.3802, -84.2814, 50.0000, 0.0000, -82.7485, 1.0000),
    (50.0000, -1.1848, -84.8006, 50.0000, 0.0000, -82.7485, 1.0000),
    (50.0000, -0.9009, -85.5211, 50.0000, 0.0000, -82.7485, 1.0000),
    (50.0000, 0.0000, 0.0000, 50.0000, -1.0000, 2.0000, 2.3669),
    (50.0000, -1.0000, 2.0000, 50.0000, 0.0000, 0.0000, 2.3669),
    (50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0009, 7.1792),
    (50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0010, 7.1792),
    (50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0011, 7.2195),
    (50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0012, 7.2195),
    (50.0000, -0.0010, 2.4900, 50.0000, 0.0009, -2.4900, 4.8045),
    (50.0000, -0.0010, 2.4900, 50.0000, 0.0010, -2.4900, 4.8045),
    (50.0000, -0.0010, 2.4900, 50.0000, 0.0011, -2.4900, 4.7461),
    (50.0000, 2.5000, 0.0000, 50.0000, 0.0000, -2.5000, 4.3065),
    (50.0000, 2.5000, 0.0000, 73.0000, 25.0000, -18.0000, 27.1492),
    (50.0000, 2.5000, 0.0000, 61.0000, -5.0000, 29.0000, 22.8977),
    (50.0000, 2.5000, 0.0000, 56.0000, -27.0000, -3.0000, 31.9030),
    (50.0000, 2.5000, 0.0000, 58.0000, 24.0000, 15.0000, 19.4535),
    (50.0000, 2.5000, 0.0000, 50.0000, 3.1736, 0.5854, 1.0000),
    (50.0000, 2.5000, 0.0000, 50.0000, 3.2972, 0.0000, 1.0000),
    (50.0000, 2.5000, 0.0000, 50.0000, 1.8634, 0.5757, 1.0000),
    (50.0000, 2.5000, 0.0000, 50.0000, 3.2592, 0.3350, 1.0000),
    (60.2574, -34.0099, 36.2677, 60.4626, -34.1751, 39.4387, 1.2644),
    (63.0109, -31.0961, -5.8663, 62.8187, -29.7946, -4.0864, 1.2630),
    (61.2901, 3.7196, -5.3901, 61.4292, 2.2480, -4.9620, 1.8731),
    (35.0831, -44.1164, 3.7933, 35.0232, -40.0716, 1.5901, 1.8645),
    (22.7233, 20.0904, -46.6940, 23.0331, 14.9730, -42.5619, 2.0373),
    (36.4612, 47.8580, 18.3852, 36.2715, 50.5065, 21.2231, 1.4146),
    (90.8027, -2.0831, 1.4410, 91.1528, -1.6435, 0.0447, 1.4441),
    (90.9257, -0.5406, -0.9208, 88.6381, -0.8985, -0.7239, 1.5381),
    (6.7747, -0.2908, -2.4247, 5.8714, -0.0985, -2.2286, 0.6377),
    (2.0776, 0.0795, -1.1350, 0.9033, -0.0636, -0.5514, 0.9082),
]


def test_ciede2000_reproduces_sharmas_34_test_pairs_both_ways():
    data = np.array(SHARMA_PAIRS)
    lab1, lab2, expected = data[:, :3], data[:, 3:6], data[:, 6]
    np.testing.assert_allclose(ciede2000(lab1, lab2), expected, atol=1e-4, rtol=0)
    np.testing.assert_allclose(ciede2000(lab2, lab1), expected, atol=1e-4, rtol=0)
    assert ciede2000(lab1[16], lab1[16]) == 0.0


def test_srgb_to_lab_d65_reference_values():
    # CIE L*a*b* (D65, 2°) of the sRGB primaries, white and black (IEC 61966-2-1 matrix)
    cases = {
        (1.0, 1.0, 1.0): (100.0, 0.0, 0.0),
        (0.0, 0.0, 0.0): (0.0, 0.0, 0.0),
        (1.0, 0.0, 0.0): (53.2408, 80.0925, 67.2032),
        (0.0, 1.0, 0.0): (87.7347, -86.1827, 83.1793),
        (0.0, 0.0, 1.0): (32.2970, 79.1875, -107.8602),
    }
    for rgb, lab in cases.items():
        np.testing.assert_allclose(srgb_to_lab(rgb), lab, atol=2e-3)
    # a neutral grey has no chroma
    assert np.hypot(*srgb_to_lab((0.5, 0.5, 0.5))[1:]) < 1e-3


def distinct_face_colours(entries) -> dict:
    """name → solid colour of the categories a map shows: gaps (failed, not computed) share
    white and are told apart by their hatches, so white counts once ("gap")."""
    colours = {}
    for e in entries:
        if e.label in GAP_STYLE:
            colours["gap"] = to_rgba(GAP_STYLE[e.label]["facecolor"])
        else:
            colours[e.label] = to_rgba(e.colour)
    return colours


def assert_pairwise_distinct(colours) -> None:
    """Every two colours ≥ MIN_DELTA_E00 apart (a dict name → colour, or a list)."""
    if not isinstance(colours, dict):
        colours = {str(c): c for c in colours}
    names, values = list(colours), list(colours.values())
    d = pairwise_delta_e00(values)
    for i, j in itertools.combinations(range(len(values)), 2):
        assert d[i, j] >= MIN_DELTA_E00, f"{names[i]}, {names[j]}: ΔE00 = {d[i, j]:.2f}"


def test_designed_table_and_pool_are_pairwise_distinct():
    table = [c for name, c in DESIGNED.items() if name not in GAP_STYLE] + ["#ffffff"]
    assert_pairwise_distinct(table)
    assert_pairwise_distinct(list(POOL) + table)
    # the pool keeps the margin of its construction (≥ 12 before rounding to 8-bit hex)
    d = pairwise_delta_e00(list(POOL) + table)
    np.fill_diagonal(d, np.inf)
    assert d[: len(POOL)].min() >= 11.5
    # hatched classes differ by their hatches too
    hatches = {GAP_STYLE[k]["hatch"] for k in GAP_STYLE} | {OTHER_STYLE["hatch"]}
    assert len(hatches) == len(GAP_STYLE) + 1


def arrays_of(cells, shape):
    a = np.array(cells, dtype=np.int64).reshape(*shape, 3)
    return {
        "kind": a[..., 0].astype(np.int8),
        "n": a[..., 1].astype(np.int32),
        "p": a[..., 2].astype(np.int32),
    }


def grid_of(rows, cols):
    return MapGrid(
        np.linspace(6.0, 0.02, cols),
        np.linspace(0.95, 0.5, rows),
        "mu_cn",
        7,
        {"f0": 0.5, "mu_kn": 0.8, "zeta": 0.2},
    )


def drawn_palette(figure):
    """The colours of the categories a label map's mesh draws, and its legend's texts."""
    ax = figure.axes[0]
    mesh = next(c for c in ax.collections if isinstance(c, QuadMesh))
    return list(mesh.get_cmap().colors), [t.get_text() for t in ax.get_legend().get_texts()]


# The labels of the committed Fig. 7 (the (ω, μcn) plane) with their cell counts, where
# 8-p̃ and 14-p̃ were drawn alike and 3-2, 7-5, 11-p̃ all olive.
FIG7_LABELS = {
    (1, 0): 16551,
    (1, 1): 107643,
    (1, 2): 7375,
    (1, 3): 43,
    (2, 1): 6242,
    (2, 2): 11372,
    (3, 1): 3275,
    (3, 2): 1625,
    (4, 2): 87,
    (4, 3): 461,
    (4, 4): 93,
    (5, 4): 326,
    (7, 4): 56,
    (7, 5): 56,
    (8, 6): 196,
    (8, 9): 26,
    (9, 6): 31,
    (11, 8): 29,
    (14, 9): 32,
    (16, 12): 47,
    (5, 3): 9,
    (6, 4): 8,
    (6, 5): 7,
    (9, 7): 6,
    (10, 7): 5,
    (10, 8): 5,
    (12, 9): 4,
    (13, 9): 4,
    (6, 3): 4,
    (7, 6): 3,
    (8, 5): 3,
    (9, 5): 2,
    (10, 6): 2,
    (12, 8): 2,
    (15, 10): 2,
    (3, 3): 2,
}


def fig7_like_map():
    cells = [
        (PERIODIC, n, p)
        for (n, p), count in FIG7_LABELS.items()
        for _ in range(max(1, count // 25))
    ]
    cells += [(CHAOTIC, 0, 0)] * 160 + [(QUASIPERIODIC, 0, 0)] * 7 + [(UNCONVERGED, 0, 0)] * 2
    cells += [(FAILED, 0, 0)] * 3
    side = int(np.ceil(np.sqrt(len(cells))))
    cells += [(PERIODIC, 1, 1)] * (side * side - len(cells))
    return arrays_of(cells, (side, side)), grid_of(side, side)


def test_fig7_label_set_gets_distinct_colours_and_names_every_label():
    arrays, grid = fig7_like_map()
    figure = plot_map(grid, arrays, "labels")
    colours, texts = drawn_palette(figure)
    cells = distinct_categories(map_labels(arrays), LEGEND_MAX)
    assert [to_rgba(c) for c in colours] == [to_rgba(e.colour) for e in cells.entries]
    assert_pairwise_distinct(distinct_face_colours(cells.entries))
    colour = {e.label: e.colour for e in cells.entries}
    # the defects of issue #13: now told apart (or one of them is in the listed "other")
    for a, b in (("8-p~", "14-p~"), ("3-2", "7-5"), ("3-2", "11-p~"), ("7-5", "11-p~")):
        if a in colour and b in colour:
            assert delta_e00(colour[a], colour[b]) >= MIN_DELTA_E00, (a, b)
    other = next((e.members for e in cells.entries if e.label == OTHER), ())
    assert {"3-2", "7-5", "8-p~", "11-p~", "14-p~"} <= set(colour) | set(other)
    legend = "\n".join(texts)
    for entry in map_labels(arrays).entries:  # every label present is named
        name = entry.label.replace("p~", r"$\tilde{p}$").replace("QP", "quasi-periodic")
        assert name in legend, entry.label


@pytest.mark.parametrize("seed", range(6))
def test_any_map_shows_pairwise_distinct_colours_and_lists_its_rare_labels(seed):
    rng = np.random.default_rng(seed)
    rows, cols = 30, 40
    n = rng.integers(1, 24, size=(rows, cols))
    p = rng.integers(0, 14, size=(rows, cols))
    common = rng.random((rows, cols)) < 0.5  # half the cells in a few common labels
    n[common], p[common] = 1, rng.integers(0, 3, size=common.sum())
    kind = rng.choice(
        [PERIODIC] * 12 + [QUASIPERIODIC, CHAOTIC, UNCONVERGED, FAILED], size=(rows, cols)
    )
    arrays = {"kind": kind.astype(np.int8), "n": n.astype(np.int32), "p": p.astype(np.int32)}
    arrays["computed"] = np.ones((rows, cols), bool)
    arrays["computed"][-2:] = False
    for legend in (True, False):
        figure = plot_map(grid_of(rows, cols), arrays, "labels", legend=legend)
        colours, _ = drawn_palette(figure) if legend else (None, None)
        cells = distinct_categories(map_labels(arrays), LEGEND_MAX if legend else None)
        assert_pairwise_distinct(distinct_face_colours(cells.entries))
        present = {e.label for e in map_labels(arrays).entries}
        shown = {e.label for e in cells.entries}
        other = next((e for e in cells.entries if e.label == OTHER), None)
        members = set(other.members) if other else set()
        assert present == (shown - {OTHER}) | members  # every label coloured or listed
        assert not (shown & members)
        if legend:
            designed = sum(e.label in DESIGNED and e.label != OTHER for e in cells.entries)
            assert len(cells.entries) <= max(LEGEND_MAX, designed + 1)
            assert [to_rgba(c) for c in colours] == [to_rgba(e.colour) for e in cells.entries]


def test_other_class_is_hatched_over_exactly_its_cells_and_listed_in_the_legend():
    cells = [(PERIODIC, n, p) for n in range(1, 12) for p in range(0, 6)]  # 66 labels
    cells += [(PERIODIC, 1, 1)] * (72 - len(cells))
    arrays = arrays_of(cells, (8, 9))
    figure = plot_map(grid_of(8, 9), arrays, "labels")
    grouped = distinct_categories(map_labels(arrays), LEGEND_MAX)
    other = next(e for e in grouped.entries if e.label == OTHER)
    assert len(other.members) >= 66 - LEGEND_MAX
    ax = figure.axes[0]
    hatched = [
        r for r in ax.patches if isinstance(r, Rectangle) and r.get_hatch() == OTHER_STYLE["hatch"]
    ]
    area = sum(r.get_width() * r.get_height() for r in hatched)
    cell_area = abs(np.diff(grid_of(8, 9).omega)[0] * np.diff(grid_of(8, 9).second)[0])
    assert area == pytest.approx(other.count * cell_area, rel=1e-9)
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    text = next(t for t in legend if t.startswith("other"))
    for member in other.members:
        assert member in text.replace("\n", ", ")
