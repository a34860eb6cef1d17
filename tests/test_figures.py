"""Orbit views, bifurcation lines and the paper's composite figures: headless, marked right,
and the line's section points agreeing with single-point simulations."""

import io
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from campar.cli import main
from campar.paper import setups as paper
from campar.views.line import bifurcation_line, continued_state, describe_line, varied_parameters
from campar.views.plot import PlotError, plot_orbit
from campar.views.plot.bifurcation import plot_line, plot_lines
from campar.views.plot.figures import plot_force_row, plot_gap_family, plot_phase_grid
from campar.views.plot.orbit import plot_gap, plot_phase
from campar.views.point import simulate_point

PNG = b"\x89PNG\r\n\x1a\n"
# A chaotic cell of the (ω, f0) plane, from rest (found on its 48 × 48 grid).
CHAOS = dict(omega=5.745531914893617, f0=2.451914893617021)


def png_bytes(figure: Figure) -> bytes:
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=60)
    return buffer.getvalue()


def assert_headless_png(figure) -> None:
    assert isinstance(figure, Figure)
    assert isinstance(figure.canvas, FigureCanvasAgg)
    assert png_bytes(figure).startswith(PNG)


@pytest.fixture(scope="module")
def orbits():
    """2-2 with the clamp active, the same point with tensile force, 1-0, and chaos."""
    return {
        "2-2": simulate_point(3.0, mu_kn=0.91, trace=True),
        "allow": simulate_point(3.0, mu_kn=0.91, tensile="allow", trace=True),
        "1-0": simulate_point(0.3, trace=True),
        "chaos": simulate_point(CHAOS["omega"], f0=CHAOS["f0"], trace=True),
    }


@pytest.mark.parametrize("name", ["2-2", "allow", "1-0", "chaos"])
def test_plot_orbit_renders_headless(orbits, name):
    figure = plot_orbit(orbits[name])
    assert_headless_png(figure)
    assert orbits[name].label in figure.get_suptitle()


def test_phase_portrait_marks_every_section_and_detachment_point(orbits):
    r = orbits["2-2"]
    assert (r.n, r.p) == (2, 2)
    ax = plot_phase(r).axes[0]
    orbit, sections, detachments = ax.lines[:3]
    np.testing.assert_allclose(np.column_stack(sections.get_data()), r.sections)
    assert len(detachments.get_xdata()) == r.p
    np.testing.assert_allclose(
        np.column_stack(detachments.get_data()), r.trace.events_named("detachment")[:, 1:]
    )
    assert len(orbit.get_xdata()) == len(r.trace.t)


def test_force_panel_marks_impacts_and_detachments(orbits):
    r = orbits["2-2"]
    figure = plot_orbit(r)
    force = figure.axes[2]
    impacts = [line for line in force.lines if line.get_marker() == "o"][0]
    stars = [line for line in force.lines if line.get_marker() == "*"][0]
    np.testing.assert_allclose(impacts.get_xdata(), r.trace.events_named("impact")[:, 0])
    np.testing.assert_allclose(stars.get_xdata(), r.trace.events_named("detachment")[:, 0])
    assert len(stars.get_xdata()) == r.p
    # the cam input sits on a second y axis
    assert force.cam_axis.lines[0].get_ydata().max() == pytest.approx(1.0, abs=1e-6)


def test_gap_curve_repeats_a_periodic_orbit(orbits):
    r = orbits["allow"]  # 1-1
    ax = plot_gap(r, revolutions=2).axes[0]
    curve = [line for line in ax.lines if len(line.get_xdata()) > 10][0]
    assert curve.get_xdata()[-1] == pytest.approx(r.trace.t[-1] + r.trace.period)


def test_orbit_views_need_a_trace(orbits):
    r = simulate_point(3.0, mu_kn=0.91)
    with pytest.raises(PlotError, match="trace=True"):
        plot_orbit(r)


def test_composite_figures_render(orbits):
    panels = [
        {"kind": "phase", "result": orbits["2-2"], "heading": "$\\omega$ = 3\npaper 2-2"},
        {
            "kind": "section",
            "result": orbits["chaos"],
            "cloud": orbits["chaos"].sections,
            "heading": "chaos",
        },
    ]
    assert_headless_png(plot_phase_grid(panels, columns=2))
    rows = [("f0", (0.5, 1.5), [[orbits["2-2"], orbits["allow"]], [orbits["1-0"], orbits["1-0"]]])]
    assert_headless_png(plot_gap_family(rows))
    assert_headless_png(plot_force_row([orbits["2-2"], orbits["1-0"], orbits["chaos"]]))


@pytest.fixture(scope="module")
def line():
    return bifurcation_line((6.0, 0.2), 400, mu_kn=0.91)


def test_line_runs_omega_downwards_and_labels_cells(line):
    assert line.omega[0] == 6.0 and line.omega[-1] == pytest.approx(0.2)
    assert np.all(np.diff(line.omega) < 0)
    labels = set(line.labels)
    assert {"1-0", "1-1", "2-2", "1-2"} <= labels
    text = describe_line(line)
    assert "2-2" in text and "1-0" in text


def test_line_sections_agree_with_simulate_point(line):
    """Started from a cell's final state (a point of its cycle), simulate_point finds the
    same σn points; started from rest at a monostable ω, too."""
    labels = line.labels
    picks = [labels.index(label) for label in ("1-1", "2-2", "1-2", "1-0")]
    for i in picks:
        omega = float(line.omega[i])
        r = simulate_point(omega, mu_kn=0.91, y0=line.state[i, 0], v0=line.state[i, 1])
        assert r.label == labels[i]
        mine = line.sections[i][np.isfinite(line.sections[i, :, 0])]
        assert len(mine) == r.n
        for point in r.sections:
            assert np.min(np.abs(mine - point).max(axis=1)) < 1e-6
    i = labels.index("1-0")
    cold = simulate_point(float(line.omega[i]), mu_kn=0.91)
    np.testing.assert_allclose(cold.sections, line.sections[i, :1], atol=1e-6)


def test_continued_state_lands_on_the_lines_attractor(line):
    i = int(np.argmin(np.abs(line.omega - 3.0)))
    _, state = continued_state(float(line.omega[i]), mu_kn=0.91)
    r = simulate_point(float(line.omega[i]), mu_kn=0.91, y0=state[0], v0=state[1])
    assert r.label == line.labels[i]


def test_line_figures_render(line):
    assert_headless_png(plot_line(line))
    assert_headless_png(plot_lines([line, line], ["a", "b"]))


def test_only_one_line_parameter_may_vary():
    sets = varied_parameters({"f0": [0.5], "mu_kn": [0.9, 0.91]})
    assert sets == [{"f0": 0.5, "mu_kn": 0.9}, {"f0": 0.5, "mu_kn": 0.91}]
    with pytest.raises(Exception, match="only one parameter"):
        varied_parameters({"f0": [0.5, 1.0], "mu_kn": [0.9, 0.91]})


def test_line_command_draws_and_saves(tmp_path, capsys):
    out = tmp_path / "line.png"
    npz = tmp_path / "cells.npz"
    argv = [
        "line",
        "--omega",
        "3.3:2.9",
        "--points",
        "40",
        "--mu-kn",
        "0.91",
        "0.922",
        "-o",
        str(out),
        "--npz",
        str(npz),
    ]
    assert main(argv) == 0
    assert out.read_bytes().startswith(PNG)
    data = np.load(tmp_path / "cells-2.npz")
    assert data["omega"].shape == (40,) and float(data["mu_kn"]) == 0.922
    assert "80 cells in" in capsys.readouterr().out


@pytest.mark.process
def test_point_command_writes_a_png(tmp_path):
    out = tmp_path / "orbit.png"
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "campar.cli",
            "point",
            "--omega",
            "3",
            "--mu-kn",
            "0.91",
            "--plot",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert "2-2" in done.stdout
    assert out.read_bytes().startswith(PNG)


@pytest.mark.process
def test_importing_the_views_stays_light():
    code = (
        "import sys, campar.views.plot, campar.views.plot.orbit; "
        "print('matplotlib.pyplot' in sys.modules, 'campar.core.kernel' in sys.modules)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.stdout.split() == ["False", "False"], done.stderr


STEMS = (
    "fig2_omega_f0_labels",
    "fig2_omega_f0_dc",
    "fig2_omega_f0_lyapunov",
    "fig4_mu_kn_labels",
    "fig4_mu_kn_dc",
    "fig4_mu_kn_lyapunov",
    "fig7_mu_cn_labels",
    "fig7_mu_cn_dc",
    "fig7_mu_cn_lyapunov",
    "fig5_lines",
    "fig6_phase_portraits",
    "fig3_gap_preload",
    "fig8_gap_stiffness_damping",
    "fig9_force",
    "orbit_point",
)


@pytest.fixture(scope="module")
def gallery(tmp_path_factory):
    """A tiny gallery under both force laws (6 × 6 planes, 60-cell lines, 4-start
    censuses), with the title of every figure it saved."""
    from campar.paper import gallery
    from campar.paper.gallery import make_gallery
    from campar.views.plot import style

    out = tmp_path_factory.mktemp("gallery")
    titles = {}
    save = style.save_figure

    def saving(figure, path, **options):
        titles[Path(path).name] = figure.get_suptitle()
        return save(figure, path, **options)

    with pytest.MonkeyPatch.context() as mp:
        mp.setitem(paper.SIZES, "small", paper.Size(plane=6, line=60))
        mp.setattr(paper, "FIG6_STARTS", 4)
        # what these tests read (files, sidecars, titles, captions, axes) is the same at any
        # resolution; rasterising at the gallery's 200 dpi is a large part of its cost
        mp.setattr(gallery, "PNG_DPI", 40)
        # the attractor-structure figures have their own tests (test_attractor_figures.py)
        mp.setattr(gallery, "draw_structure", lambda g: None)
        mp.setattr(style, "save_figure", saving)
        pngs = make_gallery(out / "g", "small", stores=out / "stores", log=lambda _: None)
    return out / "g", pngs, titles


@pytest.mark.slow  # a tiny gallery under both force laws: minutes
def test_gallery_writes_every_figure_under_both_force_laws_with_its_job_file(gallery):
    from campar.sweep.job import load_job

    outdir, pngs, _ = gallery
    names = {p.name for p in pngs}
    for stem in STEMS:
        assert f"{stem}.png" in names and f"{stem}-allow.png" in names
    for path in pngs:
        assert path.read_bytes().startswith(PNG)
        assert path.with_suffix(".yaml").exists()
    for job in ("omega_f0", "mu_kn", "mu_cn"):  # the plane jobs, runnable with campar run
        for law, name in (("clamp", job), ("allow", f"{job}-allow")):
            plane = load_job(outdir / f"{name}.yaml")
            assert plane.shape == (6, 6) and plane.model.tensile == law
            assert "lyapunov" in plane.outputs
    index = (outdir / "index.md").read_text()
    assert "fig9_force.png" in index and "fig9_force-allow.png" in index
    assert "--tensile both" in index


UNITS = re.compile(r"\([^()]*(units of|dimensionless)")


@pytest.mark.slow  # a tiny gallery under both force laws: minutes
def test_every_figure_states_force_law_start_direction_and_units(gallery):
    from campar.paper.gallery import DIRECTION_TEXT, LAW_TEXT, START_TEXT

    outdir, pngs, titles = gallery
    index = (outdir / "index.md").read_text()
    for path in pngs:
        meta = yaml.safe_load(path.with_suffix(".yaml").read_text())
        law = "allow" if path.stem.endswith("-allow") else "clamp"
        assert meta["tensile"] == law, path.name
        assert meta["start"] in START_TEXT and meta["direction"] in DIRECTION_TEXT
        for text in (LAW_TEXT[law], START_TEXT[meta["start"]], DIRECTION_TEXT[meta["direction"]]):
            assert text in meta["caption"], (path.name, text)
        assert meta["caption"] in index
        title = titles[path.name]
        assert f"tensile: {law}" in title and f"start: {meta['start']}" in title, title
        assert "sweep: " in title
        # every labelled axis carries its units (or says it is dimensionless) …
        assert meta["axes"], path.name
        for axis in meta["axes"]:
            for text in axis.values():
                assert UNITS.search(text), (path.name, text)
        # … and each figure labels some x and some y axis
        assert any("x" in a for a in meta["axes"]) and any("y" in a for a in meta["axes"])
    for stem in ("fig2_omega_f0_labels", "fig4_mu_kn_dc", "fig7_mu_cn_lyapunov"):
        meta = yaml.safe_load((outdir / f"{stem}.yaml").read_text())
        assert (meta["start"], meta["direction"]) == ("continue", "down")  # the jobs' chains
    for stem in ("fig3_gap_preload", "fig9_force", "orbit_point"):
        assert yaml.safe_load((outdir / f"{stem}.yaml").read_text())["direction"] == "none"


@pytest.mark.slow  # a tiny gallery under both force laws: minutes
def test_label_maps_palettes_are_pairwise_distinct(gallery):
    from campar.views.plot.colour import pairwise_delta_e00
    from campar.views.plot.labels import GAP_STYLE, MIN_DELTA_E00

    outdir, pngs, _ = gallery
    maps = [p for p in pngs if "_labels" in p.stem]
    assert len(maps) == 6
    for path in maps:
        palette = yaml.safe_load(path.with_suffix(".yaml").read_text())["palette"]
        solid = {k: v for k, v in palette.items() if k not in GAP_STYLE}
        colours = list(solid.values()) + (["#ffffff"] if set(palette) & set(GAP_STYLE) else [])
        d = pairwise_delta_e00(colours)
        np.fill_diagonal(d, np.inf)
        assert d.min() >= MIN_DELTA_E00, (path.name, palette)


@pytest.mark.slow  # a tiny gallery under both force laws: minutes
def test_fig6_follows_the_planes_path_and_fig9_shades_the_clamp(gallery):
    outdir, _, _ = gallery
    for law, suffix in (("clamp", ""), ("allow", "-allow")):
        fig6 = yaml.safe_load((outdir / f"fig6_phase_portraits{suffix}.yaml").read_text())
        assert [cell["omega"] for cell in fig6["cells"]] == [w for w, _ in paper.FIG6_CLAIMS]
        for cell in fig6["cells"]:
            job = cell["path_job"]
            assert job["chains"]["start"] == "continue" and job["chains"]["direction"] == "down"
            assert job["model"]["tensile"] == law
            assert job["sweep"]["omega"]["from"] == 6.0
            assert job["sweep"]["omega"]["to"] == cell["omega"]
            assert (job["sweep"]["mu_kn"]["from"], job["sweep"]["mu_kn"]["to"]) == (0.95, 0.91)
            attractors = cell["attractors"]
            assert attractors[0]["on_path"] and not any(a["on_path"] for a in attractors[1:])
            assert cell["census_starts"] == 4
        fig9 = yaml.safe_load((outdir / f"fig9_force{suffix}.yaml").read_text())
        clamped = fig9["clamped_fraction_of_revolution"]
        if law == "clamp":
            assert max(clamped.values()) > 0 and "shaded orange" in fig9["caption"]
        else:
            assert max(clamped.values()) == 0
