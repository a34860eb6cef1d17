"""campar explore's page in a real browser: Debian's headless Chromium driven by Playwright.

One server (the ``campar explore`` command, a child process) and one browser session for
every check, in order: the page loads nothing from outside the server; the drawn colour
of every cell is its stored label's colour in the maps' palette; hovering a cell reads
its stored values; a click computes the cell and its label is `campar point`'s; a row's
bifurcation line has the stored row's labels, a column's and a segment's are the chains
of campar.explore.lines; another variable is drawn with viridis
over its range; two stores side by side and their difference; the exports. Screenshots
go to $CAMPAR_SCREENSHOTS when it is set (docs/explore.md shows them).

Under CI=true a missing Chromium or Playwright fails these tests instead of skipping them.
"""

import contextlib
import io
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from support.jobs import EXPLORE_MAP

import campar
from campar.cli import main
from campar.explore.chromium import CHROMIUM, CHROMIUM_ARGS

pytestmark = [pytest.mark.browser, pytest.mark.process]

JOB = EXPLORE_MAP
TIMEOUT_MS = 240_000  # a cold numba cache compiles the kernel in the cell worker first


def _require(what: str) -> None:
    if os.environ.get("CI", "").lower() == "true":
        pytest.fail(f"{what} (CI must run the browser tests: .ci/run installs chromium)")
    pytest.skip(what)


@pytest.fixture(scope="module")
def stores(tmp_path_factory):
    folder = tmp_path_factory.mktemp("explore-browser")
    a, b = folder / "a.zarr", folder / "b.zarr"
    campar.run({**JOB, "name": "explore_a", "store": str(a)})
    campar.run({**JOB, "name": "explore_b", "fixed": {"mu_kn": 0.86}, "store": str(b)})
    return a, b


@pytest.fixture(scope="module")
def url(stores):
    command = [sys.executable, "-m", "campar.cli", "explore", "--no-browser", "--zoom-ranks", "1"]
    command += [str(s) for s in stores]
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        assert line.startswith("campar explore: serving ") and " at http://127.0.0.1:" in line
        yield line.rsplit(" at ", 1)[1].strip()
    finally:
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(60) == 0  # a stop signal ends the server cleanly


@pytest.fixture(scope="module")
def page(url):
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        _require("Playwright for Python is not installed (the test extra installs it)")
    if not Path(CHROMIUM).exists() and not shutil.which("chromium"):
        _require("Chromium is missing (apt-get install chromium)")
    executable = CHROMIUM if Path(CHROMIUM).exists() else shutil.which("chromium")
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=executable, args=list(CHROMIUM_ARGS))
        # the page forbids evaluated script (its Content-Security-Policy); the test's own
        # probes are evaluated script, so this context lets them run
        context = browser.new_context(
            viewport={"width": 1400, "height": 900}, bypass_csp=True, accept_downloads=True
        )
        page = context.new_page()
        page.requests = []
        page.errors = []
        page.on("request", lambda r: page.requests.append(r.url))
        page.on("pageerror", lambda e: page.errors.append(str(e)))
        page.set_default_timeout(TIMEOUT_MS)
        page.goto(url)
        page.wait_for_function("window.explore && window.explore.ready")
        yield page
        context.close()
        browser.close()


def screenshot(page, name: str) -> None:
    folder = os.environ.get("CAMPAR_SCREENSHOTS")
    if folder:
        Path(folder).mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(Path(folder) / f"{name}.png"), full_page=True)


@contextlib.contextmanager
def redrawn(page, view: int = 0):
    """Wait, after the block, until view ``view`` has drawn an image asked for in it."""
    before = page.evaluate(f"window.explore.views[{view}].drawn")
    yield
    page.wait_for_function(f"window.explore.views[{view}].drawn > {before}")


def pixels(page, cells, view: int = 0) -> np.ndarray:
    """RGBA drawn at the centre of each (ω, μcn) in ``cells`` on map ``view``."""
    script = """([view, cells]) => {
        const v = window.explore.views[view];
        const ctx = v.canvas.getContext("2d");
        return cells.map(([x, y]) => {
            const [px, py] = v.toPixel(x, y);
            return Array.from(ctx.getImageData(Math.floor(px), Math.floor(py), 1, 1).data);
        });
    }"""
    return np.array(page.evaluate(script, [view, [list(map(float, c)) for c in cells]]))


def cell_centres(ds):
    return [(ds.omega.values[j], ds.mu_cn.values[i]) for i in range(6) for j in range(12)]


def label_rgba(labels) -> np.ndarray:
    from campar.views.plot.labels import label_colour

    return np.array([np.round(np.array(label_colour(str(x))) * 255) for x in labels])


def test_the_page_loads_nothing_from_elsewhere(page, url):
    assert page.requests and all(r.startswith(url) for r in page.requests), page.requests
    assert not page.errors


def test_every_cell_is_drawn_in_its_labels_colour(page, stores):
    ds = campar.open(stores[0])
    drawn = pixels(page, cell_centres(ds))
    expected = label_rgba(ds.label.values.ravel())
    assert np.array_equal(drawn, expected)
    legend = page.locator("#legend .entry").all_inner_texts()
    values, counts = np.unique(ds.label.values, return_counts=True)
    shown = {t.split("\t")[0].split("\n")[0]: t for t in legend}
    assert set(shown) == set(values.tolist())
    for value, count in zip(values.tolist(), counts.tolist(), strict=True):
        assert shown[value].split()[-1] == str(count)
    screenshot(page, "map")


def _mouse_at(page, omega, mu, view: int = 0):
    px, py = page.evaluate(
        "([v, x, y]) => window.explore.views[v].toPixel(x, y)", [view, float(omega), float(mu)]
    )
    box = page.locator(f"#map{view}").bounding_box()
    return box["x"] + px, box["y"] + py


def test_hovering_a_cell_reads_its_stored_values(page, stores):
    ds = campar.open(stores[0])
    page.mouse.move(*_mouse_at(page, ds.omega.values[3], ds.mu_cn.values[2]))
    page.wait_for_function("window.explore.hovered && window.explore.hovered.row === 2")
    assert page.inner_text("#hover-label") == ds.label.values[2, 3]
    text = page.inner_text("#hover")
    assert f"duty cycle {float(ds.dc.values[2, 3]):.4f}" in text
    assert f"ε max {float(ds.eps_max.values[2, 3]):.4f}" in text


def test_a_click_computes_the_cell_as_campar_point_from(page, stores):
    ds = campar.open(stores[0])
    omega, mu = ds.omega.values[3], ds.mu_cn.values[2]
    page.mouse.click(*_mouse_at(page, omega, mu))
    page.wait_for_function("window.explore.cell && window.explore.cell.report")
    out = io.StringIO()
    args = ["point", "--from", str(stores[0]), "--omega", str(omega), "--mu-cn", str(mu)]
    with contextlib.redirect_stdout(out):
        assert main([*args, "--json"]) == 0
    point = json.loads(out.getvalue())
    assert page.inner_text("#cell-label") == point["label"] == ds.label.values[2, 3]
    drawn = page.evaluate(
        """() => { const c = document.getElementById("phase");
        const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
        let n = 0; for (let i = 3; i < d.length; i += 4) n += d[i] > 0; return n; }"""
    )
    assert drawn > 1000  # the phase portrait is drawn
    screenshot(page, "cell")


def test_a_failing_computation_is_shown_and_the_page_goes_on(page, stores):
    page.evaluate("computeCell(0, {row: 99, col: 0, omega: 1, mu_cn: 0.7})")
    page.wait_for_function("document.getElementById('cell-label').className === 'error'")
    assert page.inner_text("#cell-label").startswith("400 Bad Request: row must be in [0, 5]")
    ds = campar.open(stores[0])
    page.mouse.click(*_mouse_at(page, ds.omega.values[3], ds.mu_cn.values[2]))
    page.wait_for_function("window.explore.cell.report")
    assert page.inner_text("#cell-label") == ds.label.values[2, 3]


def test_without_chromium_under_ci_the_tests_fail(monkeypatch):
    monkeypatch.setenv("CI", "true")
    with pytest.raises(pytest.fail.Exception):
        _require("Chromium is missing")
    monkeypatch.setenv("CI", "false")
    with pytest.raises(pytest.skip.Exception):
        _require("Chromium is missing")


def test_a_row_gives_its_bifurcation_line(page, stores):
    ds = campar.open(stores[0])
    page.click("#line-mode")
    page.mouse.click(*_mouse_at(page, ds.omega.values[5], ds.mu_cn.values[4]))
    page.wait_for_function("window.explore.line && window.explore.line.data")
    line = page.evaluate("window.explore.line.data")
    assert line["row"] == 4
    assert line["labels"] == ds.label.values[4].tolist()  # the row's chain, run again
    assert len(line["points"]) >= 12
    # the branches through a periodic cell of the row: they pass through its stored cycle
    i = next(j for j in range(12) if ds.label.values[4, j] == "1-1")
    page.evaluate("window.explore.cell = null")
    page.mouse.click(*_mouse_at(page, ds.omega.values[i], ds.mu_cn.values[4]))
    page.wait_for_function("window.explore.cell && window.explore.cell.report")
    page.click("#branch")
    page.wait_for_function("window.explore.line.branch")
    branch = page.evaluate("window.explore.line.branch")
    y = float(ds.state.values[4, i, 0])
    at_cell = [p for b in branch["branches"] for p in b["points"] if p[0] == ds.omega.values[i]]
    assert any(abs(p[1] - y) < 1e-6 and p[2] for p in at_cell), (y, at_cell)
    screenshot(page, "line")
    page.evaluate("window.explore.line = null")  # its row's mark off the map's colours


def _drawn_pixels(page, canvas: str) -> int:
    return page.evaluate(
        f"""() => {{ const c = document.getElementById("{canvas}");
        const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
        let n = 0; for (let i = 3; i < d.length; i += 4) n += d[i] > 0; return n; }}"""
    )


def test_a_column_and_a_segment_give_their_bifurcation_lines(page, stores):
    """A column's line (along μcn at the clicked cell's ω) and a segment's (two clicks)
    are the chains campar.explore.lines computes (test_explore_lines checks those against
    independent chains); the column's branches pass through the clicked cell's cycle."""
    from campar.explore.lines import column_line, segment_line

    ds = campar.open(stores[0])
    page.select_option("#line-along", "column")
    page.click("#line-mode")
    page.mouse.click(*_mouse_at(page, ds.omega.values[3], ds.mu_cn.values[2]))
    page.wait_for_function("window.explore.line && window.explore.line.data")
    line = page.evaluate("window.explore.line.data")
    assert (line["along"], line["col"], line["x"]) == ("column", 3, "mu_cn")
    column = column_line(stores[0], 3)
    assert line["labels"] == column["labels"] and line["points"] == column["points"]
    assert page.inner_text("#line-head").startswith("the column ω = ")
    assert _drawn_pixels(page, "line-plot") > 1000
    # the branches along μcn through a periodic cell of the column
    i = next(r for r in range(6) if ds.label.values[r, 3] == "1-1")
    page.evaluate("window.explore.cell = null")
    page.mouse.click(*_mouse_at(page, ds.omega.values[3], ds.mu_cn.values[i]))
    page.wait_for_function("window.explore.cell && window.explore.cell.report")
    page.click("#branch")
    page.wait_for_function("window.explore.line.branch")
    branch = page.evaluate("window.explore.line.branch")
    y = float(ds.state.values[i, 3, 0])
    at_cell = [p for b in branch["branches"] for p in b["points"] if p[0] == ds.mu_cn.values[i]]
    assert any(abs(p[1] - y) < 1e-6 and p[2] for p in at_cell), (y, at_cell)
    screenshot(page, "column")

    page.select_option("#line-along", "segment")
    page.click("#line-mode")
    page.mouse.click(*_mouse_at(page, ds.omega.values[0], ds.mu_cn.values[0]))
    page.wait_for_function("window.explore.segmentStart")
    assert "click its other end" in page.inner_text("#line-head")
    page.mouse.click(*_mouse_at(page, ds.omega.values[11], ds.mu_cn.values[5]))
    page.wait_for_function("window.explore.line.along === 'segment' && window.explore.line.data")
    line = page.evaluate("window.explore.line.data")
    segment = segment_line(stores[0], (0, 0), (5, 11))
    assert line["labels"] == segment["labels"] and line["points"] == segment["points"]
    assert line["x"] == "omega" and len(line["labels"]) == 12
    screenshot(page, "segment")
    page.evaluate("window.explore.line = null")
    page.select_option("#line-along", "row")


def test_another_variable_is_drawn_over_its_range(page, stores):
    from matplotlib import colormaps

    ds = campar.open(stores[0])
    with redrawn(page):
        page.select_option("#field", "dc")
    dc = ds.dc.values.ravel()
    k = np.round((dc - dc.min()) / (dc.max() - dc.min()) * 255).astype(int)
    expected = np.round(colormaps["viridis"](np.linspace(0, 1, 256))[k] * 255)
    drawn = pixels(page, cell_centres(ds))
    assert np.abs(drawn - expected).max() <= 1
    with redrawn(page):
        page.select_option("#field", "label")


def test_two_stores_side_by_side_and_their_difference(page, stores):
    a, b = (campar.open(s) for s in stores)
    assert (a.label.values != b.label.values).any()  # the comparison shows something
    with redrawn(page, 1):
        page.select_option("#compare", "side")
    assert np.array_equal(pixels(page, cell_centres(b), 1), label_rgba(b.label.values.ravel()))
    screenshot(page, "side-by-side")
    with redrawn(page):
        page.select_option("#compare", "diff")
    differ = (a.label.values != b.label.values).ravel()
    drawn = pixels(page, cell_centres(a))
    assert np.array_equal(drawn[differ], np.tile([202, 0, 32, 255], (differ.sum(), 1)))
    assert np.array_equal(drawn[~differ], np.tile([224, 224, 224, 255], ((~differ).sum(), 1)))
    screenshot(page, "difference")
    with redrawn(page):
        page.select_option("#compare", "one")


def test_the_typed_edges_are_those_of_campar_plot(page, stores):
    from campar.views.boundaries import store_boundaries
    from campar.views.plot.curves import CURVE_STYLES

    page.check("#edges")
    page.wait_for_function("window.explore.edges && window.explore.edges.data")
    shown = page.evaluate("window.explore.edges.data.segments")
    typed = [s for s in store_boundaries(stores[0]).segments if s.type in CURVE_STYLES]
    assert sorted(shown) == sorted([*map(float, s.edge), s.type] for s in typed)
    assert typed  # the test map has edges to draw
    screenshot(page, "edges")
    page.uncheck("#edges")


def test_a_zoom_is_computed_and_drawn_over_the_map(page, stores):
    """A rectangle dragged in zoom mode is run again on a 4 × 4 grid of its own, beside
    the map, and drawn over it in its own labels' colours as its tiles commit."""
    page.fill("#zoom-points", "4")
    page.click("#zoom-mode")
    start, end = _mouse_at(page, 2.0, 0.85), _mouse_at(page, 4.0, 0.65)
    page.mouse.move(*start)
    page.mouse.down()
    page.mouse.move(*end, steps=4)
    page.mouse.up()
    page.wait_for_function("window.explore.zooms.length === 1")
    index = page.evaluate("window.explore.zooms[0].store")
    complete = f"""fetch('/api/stores').then(r => r.json()).then(s =>
        s[{index}].status.verified === s[{index}].status.tiles)"""
    for _ in range(2400):  # evaluate awaits the promise (wait_for_function would not)
        if page.evaluate(complete):
            break
        time.sleep(0.1)
    assert page.evaluate(complete)
    with redrawn(page):
        page.evaluate("setBox(window.explore.box)")  # drawn again now that every tile is in
    (zoom,) = (stores[0].parent / f"{stores[0].name}.zooms").glob("*.zarr")
    z = campar.open(zoom)
    centres = [(z.omega.values[j], z.mu_cn.values[i]) for i in range(4) for j in range(4)]
    assert np.array_equal(pixels(page, centres), label_rgba(z.label.values.ravel()))
    screenshot(page, "zoom")


def test_exports(page, tmp_path):
    with page.expect_download() as svg:
        page.click("#export-svg")
    text = Path(svg.value.path()).read_text()
    assert text.startswith("<svg") and "data:image/png;base64," in text
    assert "ω: cam speed" in text and "μcn: contact damping" in text
    with page.expect_download() as png:
        page.click("#export-png")
    assert Path(png.value.path()).read_bytes().startswith(b"\x89PNG")
    with page.expect_download() as cell:
        page.click("#export-json")
    data = json.loads(Path(cell.value.path()).read_text())
    assert data["report"]["label"] == data["stored"]
    assert not page.errors
