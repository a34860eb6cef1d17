"""The gallery's attractor-structure figures (hysteresis, multistability, curves with zooms)
and the report's section on jumps, tongues and irreversible transitions, checked against
counts made here from the raw store arrays (xarray, not campar.open)."""

import re
from math import gcd

import numpy as np
import pytest
import xarray as xr
import yaml
from support.jobs import short_curves

from campar.core.codes import Kind, Status
from campar.paper import setups as paper
from campar.paper import structure

PNG = b"\x89PNG\r\n\x1a\n"
NEW_STEMS = (
    *(f"{plane}_{view}" for plane in paper.PLANES for view in ("hysteresis", "multistability")),
    "fig2_omega_f0_curves_zooms",
    "fig4_mu_kn_curves_zooms",
)
# The zooms' curves seeded from their typed edges alone: seeds typed by shooting the
# unknown edges have their own tests (test_seed_shooting.py, test_shot_edges.py).
TINY = paper.Size(plane=8, line=60, census=6, zoom=5, shoot=False)
BASIN = 16  # starts per axis of the tiny gallery's basin: both attractors still reached


@pytest.fixture(scope="module")
def stores(tmp_path_factory):
    """The planes' stores the gallery's figures and the report's section share: the
    section computes at the gallery's size, so it reuses the clamp's and adds the allow's."""
    return tmp_path_factory.mktemp("stores")


@pytest.fixture(scope="module")
def structure_gallery(tmp_path_factory, stores):
    """The structure figures of a tiny gallery under the clamp (8 × 8 planes, 6 × 6
    censuses, zooms 5 cells across, a 16 × 16 basin, curves of at most 10 points, none
    seeded by shooting), drawn as make_gallery draws them, with the index."""
    from campar.paper import gallery
    from campar.paper.structure_figures import draw_structure

    out = tmp_path_factory.mktemp("structure")
    with pytest.MonkeyPatch.context() as mp:
        mp.setitem(paper.SIZES, "small", TINY)
        mp.setattr(structure, "BASIN_SMALL", BASIN)
        short_curves(mp, points=10)
        g = gallery.Gallery(out / "g", "small", "clamp", stores, log=lambda _: None)
        g.outdir.mkdir()
        draw_structure(g)
        gallery.write_index(g.outdir, "small", "clamp", [g], 0.0)
    return g


@pytest.mark.slow  # a tiny gallery's structure figures: minutes
def test_the_structure_figures_are_written_with_sidecars_and_index_entries(structure_gallery):
    g = structure_gallery
    index = (g.outdir / "index.md").read_text()
    for stem in NEW_STEMS:
        png = g.outdir / f"{stem}.png"
        assert png.read_bytes().startswith(PNG), stem
        meta = yaml.safe_load(png.with_suffix(".yaml").read_text())
        assert meta["tensile"] == "clamp" and meta["start"] == "continue"
        assert meta["caption"] in index and f"[{stem}.png]" in index
        assert any("x" in a for a in meta["axes"]) and any("y" in a for a in meta["axes"])
        if stem.endswith("_hysteresis"):
            assert meta["direction"] == "both"
            job = yaml.safe_load((g.outdir / meta["job"]).read_text())
            assert job["chains"] == {"start": "continue", "direction": "both"}
        elif stem.endswith("_multistability"):
            job = yaml.safe_load((g.outdir / meta["job"]).read_text())
            assert job["attractors"]["starts"] == structure.CENSUS_STARTS
            assert job["sweep"]["omega"]["points"] == TINY.census
        else:
            assert meta["direction"] == "down" and len(meta["zooms"]) == 3
            for zoom in meta["zooms"]:  # every zoom panel's job is written beside it
                job = yaml.safe_load((g.outdir / zoom["job"]).read_text())
                assert job["chains"]["start"] == "continue" and job["sweep"]["omega"]["from"] == 6.0


@pytest.mark.slow  # a tiny gallery's structure figures: minutes
def test_the_basin_figure_shows_the_bistable_cells_two_attractors(structure_gallery):
    g = structure_gallery
    png = g.outdir / "bistable_basin.png"
    assert png.read_bytes().startswith(PNG)
    meta = yaml.safe_load(png.with_suffix(".yaml").read_text())
    assert (meta["start"], meta["direction"]) == ("grid", "none")
    # the two attractors rest and the start reach there (1-1, 3-2: SciPy confirms
    # both, tests/test_multistability.py), each with its share of the starts
    assert sorted(a.split()[0] for a in meta["attractors"]) == ["1-1", "3-2"]
    job = yaml.safe_load((g.outdir / meta["job"]).read_text())
    assert list(job["sweep"]) == ["y0", "ydot0"] and job["fixed"]["omega"] == 5.8
    assert job["sweep"]["y0"]["points"] == BASIN


def test_zoom_jobs_are_finer_than_their_plane_and_cover_their_window():
    for plane, zooms in structure.ZOOMS.items():
        parent = paper.plane_job(plane, "full")
        dw, ds = structure.spacing(parent)
        for zoom in zooms:
            job = structure.zoom_job(plane, zoom.key, "full")
            zw, zs = structure.spacing(job)
            assert zw < dw / 1.5 and zs < ds / 1.5, (plane, zoom.key, zw, dw, zs, ds)
            omega, second = job.omega, job.second_values
            assert omega.min() <= min(zoom.omega) + 1e-9 and omega.max() >= max(zoom.omega)
            assert second.min() <= min(zoom.second) + 1e-12
            assert second.max() >= max(zoom.second) - 1e-12
            inside = (omega >= min(zoom.omega) - 1e-9) & (omega <= max(zoom.omega) + 1e-9)
            assert inside.sum() >= paper.SIZES["full"].zoom - 1  # its own cells, not a crop
            assert len(second) == paper.SIZES["full"].zoom
            # the paper's path: ω down from the plane's first column, rows continued
            assert omega[0] == parent.omega[0] and job.chains.start == "continue"
            assert (second[0] > second[-1]) == (parent.second_values[0] > parent.second_values[-1])


# -- the report's numbers against counts from the raw arrays ------------------------------


@pytest.fixture(scope="module")
def section(stores):
    from campar.paper.structure_report import structure_section

    with pytest.MonkeyPatch.context() as mp:
        mp.setitem(paper.SIZES, "small", TINY)
        short_curves(mp)
        text = "\n".join(structure_section("small", stores, log=lambda _: None))
    return text, stores


def settled(kind, status, n, sections):
    ok = (kind == Kind.PERIODIC) & (status == Status.OK) & (n >= 1) & (n <= sections.shape[-2])
    for idx in zip(*np.nonzero(ok), strict=True):
        ok[idx] &= bool(np.isfinite(sections[idx][: n[idx]]).all())
    return ok


def same_cycle(a, na, b, nb, tol=1e-5) -> bool:
    """Two cycles' σn points equal after a cyclic shift, over their common period."""
    period = na * nb // gcd(na, nb)
    x = np.array([a[k % na] for k in range(period)])
    y = np.array([b[k % nb] for k in range(period)])
    return any(np.abs(x - np.roll(y, s, axis=0)).max() <= tol for s in range(period))


def raw_counts(path):
    """Hysteretic cells and down-sweep label changes crossed back at the same edge, from
    the raw arrays of a both store."""
    ds = xr.open_zarr(path, mask_and_scale=False)
    layers = [
        {k: ds[k].isel(direction=d).values for k in ("kind", "status", "n", "p", "sections")}
        for d in (0, 1)
    ]
    both = settled(*(layers[0][k] for k in ("kind", "status", "n", "sections")))
    both &= settled(*(layers[1][k] for k in ("kind", "status", "n", "sections")))
    hysteretic = 0
    for i, j in zip(*np.nonzero(both), strict=True):
        a, b = layers[0], layers[1]
        hysteretic += not same_cycle(
            a["sections"][i, j], int(a["n"][i, j]), b["sections"][i, j], int(b["n"][i, j])
        )

    # labels as (kind, n, p) with n, p only for periodic cells (chatter grouped: p ≥ 7)
    def key(layer):
        periodic = layer["kind"] == Kind.PERIODIC
        return np.stack(
            [layer["kind"], np.where(periodic, layer["n"], 0), np.where(periodic, layer["p"], 0)],
            axis=-1,
        )

    down, up = key(layers[0]), key(layers[1])
    change = (down[:, :-1] != down[:, 1:]).any(axis=-1)
    back = (
        change & (up[:, :-1] == down[:, :-1]).all(axis=-1) & (up[:, 1:] == down[:, 1:]).all(axis=-1)
    )
    return hysteretic, int(both.sum()), int(change.sum()), int(back.sum())


ROW = re.compile(r"^\| \(ω, (f0|μkn|μcn)\) \| (clamp|allow) \| (.*) \|$")
PLANE = {"f0": "omega_f0", "μkn": "mu_kn", "μcn": "mu_cn"}


def rows_of(text: str, heading: str) -> list:
    block = text.split(heading, 1)[1].split("\n### ", 1)[0]
    return [(PLANE[m[1]], m[2], m[3].split(" | ")) for m in map(ROW.match, block.splitlines()) if m]


@pytest.mark.slow  # the report's section on two tiny planes (~7 s); the counting's own
# tests (regions, crossings on drawn examples) stay in the quick tier
def test_the_reports_hysteresis_counts_agree_with_the_raw_arrays(section):
    text, stores = section
    rows = rows_of(text, "### (a) Jumps")
    assert len(rows) == 6
    nonzero = 0
    for plane, law, cells in rows:
        name = f"{plane}_both" + ("" if law == "clamp" else "-allow")
        hysteretic, compared, _, _ = raw_counts(stores / f"{name}.zarr")
        assert cells[0].startswith(f"{hysteretic} of {compared} "), (plane, law, cells[0])
        nonzero += hysteretic > 0
    assert nonzero  # the check is not vacuous: some plane has hysteresis at this size


@pytest.mark.slow  # the report's section on two tiny planes (~7 s); the counting's own
# tests (regions, crossings on drawn examples) stay in the quick tier
def test_the_reports_crossings_and_census_agree_with_the_raw_arrays(section):
    text, stores = section
    for plane, law, cells in rows_of(text, "### (c) Irreversible"):
        if cells[0] != "down":
            continue
        name = f"{plane}_both" + ("" if law == "clamp" else "-allow")
        _, _, changes, back = raw_counts(stores / f"{name}.zarr")
        assert int(cells[1]) == changes and cells[2].startswith(f"{back} of {changes}")
    for plane, law, cells in rows_of(text, "Multistable cells of the census"):
        name = f"{plane}_census" + ("" if law == "clamp" else "-allow")
        n = xr.open_zarr(stores / f"{name}.zarr", mask_and_scale=False)["n_attractors"].values
        assert cells[1].startswith(f"{int((n >= 2).sum())} of {int((n >= 0).sum())}")


def test_regions_and_crossings_on_a_drawn_example():
    from campar.paper import structure_stats as st

    # a tongue: 1, 2, 4, 6, 8 cells wide from the bottom row up
    mask = np.zeros((5, 10), bool)
    for row, width in enumerate((1, 2, 4, 6, 8)):
        mask[row, :width] = True
    omega, second = np.linspace(6, 1, 10), np.linspace(0.7, 0.9, 5)
    (region,) = st.regions(mask, omega, second, min_cells=5)
    assert region.tongue and region.tip == pytest.approx(0.7) and region.widest == 8
    down = np.array([["1-1", "1-1", "2-2", "2-2"]])
    up = np.array([["1-1", "2-2", "2-2", "2-2"]])
    both = st.BothMap(
        np.array([4.0, 3.0, 2.0, 1.0]),
        np.array([0.8]),
        "mu_kn",
        down,
        up,
        np.zeros((1, 4), bool),
        np.ones((1, 4), bool),
    )
    c = st.irreversibility(both, "down")
    assert (c.total, c.same, c.near, c.far, c.never) == (1, 0, 1, 0, 0)


def test_label_regions_carry_the_types_of_their_boundary():
    from campar.paper import structure_stats as st

    down = np.array([["1-1", "2-2", "2-2", "2-1"]] * 3)
    both = st.BothMap(
        np.array([4.0, 3.0, 2.0, 1.0]),
        np.array([0.7, 0.8, 0.9]),
        "mu_kn",
        down,
        down.copy(),
        np.zeros((3, 4), bool),
        np.ones((3, 4), bool),
    )
    both.edges["down"] = [((i, 0), (i, 1), "PD") for i in range(3)]
    both.edges["down"] += [((i, 2), (i, 3), "G") for i in range(3)]
    regions = {r.label: r for r in st.label_regions(both, "down", min_cells=3)}
    assert set(regions) == {"2-2", "2-1"}
    assert regions["2-2"].types == {"PD": 3, "G": 3} and regions["2-2"].pd_and_g
    assert regions["2-1"].types == {"G": 3} and not regions["2-1"].pd_and_g
    assert not st.subharmonic("1-3") and st.subharmonic("12-8~") and not st.subharmonic("QP")
