"""campar explore's server without a browser: what it serves, what it refuses, how it reads
stores (verified, damaged tiles masked as campar.open masks them), and its computations
bounded in time. The page in a real browser: test_explore_browser.py."""

import json
import shutil
import socket
import threading

import numpy as np
import pytest
from support.http import get, refused
from support.jobs import EXPLORE_MAP, computed_store

import campar
from campar.cli import main
from campar.errors import StoreDamaged
from campar.explore.server import serve, shutdown
from campar.explore.source import PENDING_CELL, MapSource

JOB = EXPLORE_MAP


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    return computed_store(tmp_path_factory, JOB)[0]


def _serving(store):
    server = serve([store], warm_up=False)
    server.explorer._threads and _scanned(server)
    yield server
    shutdown(server)


@pytest.fixture(scope="module")
def server(store):
    """One server for the tests that only read from it (nothing they ask changes it)."""
    yield from _serving(store)


@pytest.fixture
def own_server(store):
    """A server of the test's own, for a test that changes its worker or its stores."""
    yield from _serving(store)


def _scanned(server) -> None:
    for source in server.explorer.sources:
        for _ in range(200):
            if source.status()["scanned"]:
                break
            threading.Event().wait(0.05)


def whole_map(source, w=12, h=6) -> str:
    x0, x1 = source.x_edges[[0, -1]]
    y0, y1 = source.y_edges[[0, -1]]
    return f"x0={x0}&x1={x1}&y0={y0}&y1={y1}&w={w}&h={h}"


def test_binds_the_loopback_interface(server):
    assert server.server_address[0] == "127.0.0.1"
    assert server.socket.getsockname()[0] == "127.0.0.1"
    assert server.url.startswith("http://127.0.0.1:")
    # not reachable on another address of this machine
    others = {a[4][0] for a in socket.getaddrinfo(socket.gethostname(), None, socket.AF_INET)}
    for address in others - {"127.0.0.1"}:
        with pytest.raises(OSError):
            socket.create_connection((address, server.server_address[1]), timeout=2).close()


@pytest.mark.parametrize(
    "path",
    [
        "/../pyproject.toml",
        "/../../../../etc/passwd",
        "/%2e%2e/%2e%2e/%2e%2e/etc/passwd",
        "/%2E%2E%2F%2E%2E%2Fetc%2Fpasswd",
        "/..%2f..%2f..%2fetc%2fpasswd",
        "/explore.js/../../../etc/passwd",
        "/static/explore.js",
        "/static/../__init__.py",
        "//etc/passwd",
        "/%252e%252e/etc/passwd",
        "/..\\..\\etc\\passwd",
        "/api/map/../../../etc/passwd",
        "/explore.zarr/zarr.json",
    ],
)
def test_serves_nothing_but_its_routes(server, path):
    body = refused(server, path, 404, "404 Not Found: ")
    assert body.startswith("404 Not Found: ")
    assert "root:" not in body and "zarr_format" not in body


def test_the_stores_are_named_by_index_only(server, store):
    status, body = get(server, "/api/stores")
    assert status == 200
    (described,) = json.loads(body)
    assert described["name"] == store.name and described["shape"] == [6, 12]
    for bad in ("store=1", "store=-1", "store=../explore.zarr", f"store={store}"):
        refused(server, f"/api/cell?{bad}&x=3&y=0.8", 400, "400 Bad Request: ")


@pytest.mark.parametrize(
    "query",
    [
        "/api/map",
        "/api/map?field=label",
        "/api/map?field=nothing&x0=0&x1=1&y0=0&y1=1&w=10&h=10",
        "/api/map?field=label&x0=nan&x1=1&y0=0&y1=1&w=10&h=10",
        "/api/map?field=label&x0=1&x1=0&y0=0&y1=1&w=10&h=10",
        "/api/map?field=label&x0=0&x1=1&y0=0&y1=1&w=100000&h=10",
        "/api/map?field=label&x0=0&x1=1&y0=0&y1=1&w=10&h=10&w=20",
        "/api/map?field=label&x0=0&x1=1e999&y0=0&y1=1&w=10&h=10",
        "/api/cell?x=abc&y=1",
        "/api/compute?row=99&col=0",
        "/api/compute?row=x",
        "/api/cycle?row=0&col=0&n=0",
    ],
)
def test_a_malformed_request_gets_one_line(server, query):
    assert refused(server, query, 400, "400 Bad Request: ").startswith("400 Bad Request: ")


def test_a_malformed_request_line_gets_one_line(server):
    h, port = server.server_address[:2]
    with socket.create_connection((h, port), timeout=30) as sock:
        sock.sendall(b"NONSENSE\r\n\r\n")
        answer = _read_all(sock)
    # no request version: answered as HTTP/0.9 answers, the body alone
    assert answer == "400 Bad Request: Bad request syntax ('NONSENSE')\n"
    with socket.create_connection((h, port), timeout=30) as sock:
        sock.sendall(b"GET / HTTP/1.1\r\n" + b"X: " + b"y" * 70000 + b"\r\n\r\n")
        answer = _read_all(sock)
    assert answer.startswith("HTTP/1.1 431 ") and answer.endswith("Line too long\n")
    assert get(server, "/api/stores")[0] == 200  # and the server goes on


def _read_all(sock) -> str:
    chunks = []
    while chunk := sock.recv(65536):
        chunks.append(chunk)
    return b"".join(chunks).decode()


def test_another_host_name_is_refused(server):
    status, body = get(server, "/api/stores", host="attacker.example:80")
    assert status == 400 and "address" in body
    assert get(server, "/", method="POST")[0] == 404  # the page is read, not posted to


def test_the_map_draws_the_stored_labels_in_the_maps_palette(server, store):
    from campar.views.plot.labels import label_colour

    source = server.explorer.sources[0]
    status, body = get(server, f"/api/map?field=label&{whole_map(source)}")
    assert status == 200
    answer = json.loads(body)
    labels = campar.open(store).label.values  # (mu_cn, omega) as stored
    image = _decode_png(answer["image"])
    # one pixel a cell: pixel (i, j) is row i (μcn decreasing down the rows, as the page
    # draws it: up), column 11 - j (ω decreasing along the stored rows, drawn increasing)
    for i in range(6):
        for j in range(12):
            label = labels[i, 11 - j]
            expected = np.round(np.array(label_colour(label)) * 255)
            assert np.array_equal(image[i, j], expected), (i, j, label)
    legend = {e["label"]: e["count"] for e in answer["legend"]}
    values, counts = np.unique(labels, return_counts=True)
    assert legend == dict(zip(values.tolist(), counts.tolist(), strict=True))


def _decode_png(data_url: str) -> np.ndarray:
    import base64
    import io

    from matplotlib.image import imread

    raw = base64.b64decode(data_url.split(",", 1)[1])
    return np.round(imread(io.BytesIO(raw), format="png") * 255)


def test_hovering_reads_the_stored_cell(server, store):
    ds = campar.open(store)
    omega, mu = float(ds.omega[3]), float(ds.mu_cn[2])
    status, body = get(server, f"/api/cell?x={omega}&y={mu}")
    cell = json.loads(body)
    assert (cell["row"], cell["col"]) == (2, 3)
    assert cell["label"] == ds.label.values[2, 3]
    assert cell["dc"] == pytest.approx(float(ds.dc.values[2, 3]), abs=0)
    assert get(server, "/api/cell?x=100&y=0.8")[1] == '{"outside": true}'


def test_a_damaged_tile_is_masked_as_campar_open_masks_it(server, store, tmp_path):
    damaged = tmp_path / "damaged.zarr"
    shutil.copytree(store, damaged)
    (chunk,) = (damaged / "dc").glob("c.1.*")
    chunk.write_bytes(chunk.read_bytes()[:-3] + b"xyz")
    source = MapSource(damaged)
    source.scan()
    assert set(source.damage) == {1}  # tile 1: rows 2 and 3
    with pytest.warns(campar.errors.StoreDamageWarning):
        opened = campar.open(damaged)
    assert (opened.label.values[2:4] == "").all()  # campar.open: not computed
    field = source.fields["label"]
    x0, x1 = source.x_edges[[0, -1]]
    y0, y1 = source.y_edges[[0, -1]]
    values, inside = source.view(field, (x0, x1, y0, y1), 12, 6)
    assert inside.all()
    names = source.categories[field.name]
    drawn = np.array([[names[v] if v >= 0 else "" for v in row] for row in values])
    assert (drawn[:, ::-1] == opened.label.values).all()
    assert source.cell(2, 0)["stored"] == "damaged"


def test_a_store_with_a_damaged_variable_is_refused(store, tmp_path, capsys):
    damaged = tmp_path / "damaged.zarr"
    shutil.copytree(store, damaged)
    meta = damaged / "omega" / "zarr.json"
    text = json.loads(meta.read_text())
    text["attributes"]["units"] = "furlongs"
    meta.write_text(json.dumps(text))
    with pytest.raises(StoreDamaged):
        campar.open(damaged)
    with pytest.raises(StoreDamaged):
        MapSource(damaged)
    assert main(["explore", "--no-browser", str(damaged)]) == 65
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "variable omega" in err


def test_bad_arguments_get_one_line(store, capsys):
    assert main(["explore", "--no-browser", str(store), str(store), str(store)]) == 2
    assert main(["explore", "--no-browser", "--port", "70000", str(store)]) == 2
    assert main(["explore", "--no-browser", "/nonexistent.zarr"]) == 3
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 3 and all(line.startswith("campar explore: ") for line in err)


@pytest.mark.process
def test_a_cell_is_computed_bounded_in_time_and_failures_shown(own_server, store):
    """A cell computed in the worker as `campar point --from` computes it; a computation over its
    limit ends with one line and the next one runs; two clients at once."""
    server = own_server
    ds = campar.open(store)
    args = ["point", "--from", str(store), "--omega", str(float(ds.omega[3]))]
    args += ["--mu-cn", str(float(ds.mu_cn[2])), "--json"]
    worker = server.explorer.worker
    worker.seconds = 0.01  # the worker's spawn alone takes longer
    refused(server, "/api/compute?row=2&col=3", 422, "limit of 0.01 s")
    worker.seconds = 300
    answers = {}

    def ask(name, path):
        answers[name] = get(server, path)

    threads = [
        threading.Thread(target=ask, args=("cell", "/api/compute?row=2&col=3")),
        threading.Thread(
            target=ask, args=("map", f"/api/map?field=dc&{whole_map(ds_source(server))}")
        ),
        threading.Thread(target=ask, args=("cell2", "/api/compute?row=4&col=7")),
    ]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert {k: v[0] for k, v in answers.items()} == {"cell": 200, "map": 200, "cell2": 200}
    report = json.loads(answers["cell"][1])
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(args) == 0
    point = json.loads(out.getvalue())
    assert report["label"] == point["label"] == ds.label.values[2, 3]
    assert report["dc"] == point["dc"] == float(ds.dc.values[2, 3])  # the stored cell, bit for bit
    assert len(report["trace"]["t"]) > 10 and report["multipliers"]


def ds_source(server):
    return server.explorer.sources[0]


@pytest.mark.process
def test_a_zoom_is_computed_by_the_runner_beside_the_map(own_server, store):
    import time

    import yaml

    server = own_server
    server.explorer.zoom_ranks = 1  # the serial runner: no mpirun for a 4 × 4 grid
    query = "/api/zoom?store=0&x0=2&x1=4&y0=0.65&y1=0.85&points=4"
    assert get(server, query)[0] == 404  # a zoom changes something: POST only
    status, body = get(server, query, method="POST")
    assert status == 200, body
    zoom = json.loads(body)
    path = store.parent / f"{store.name}.zooms" / zoom["name"]
    assert zoom["store"] == 1 and path.is_dir()
    for _ in range(1200):
        stores = json.loads(get(server, "/api/stores")[1])
        if stores[1]["status"]["verified"] == stores[1]["status"]["tiles"]:
            break
        time.sleep(0.1)
    assert stores[1]["status"]["verified"] == stores[1]["status"]["tiles"]
    assert stores[1]["x"]["edges"][0] < 2 < 4 < stores[1]["x"]["edges"][1]
    assert get(server, query, method="POST")[1] == body.replace("true", "false")  # found again
    job = yaml.safe_load(path.with_suffix(".yaml").read_text())
    mine = json.loads(json.dumps(campar.open(store).attrs["job"]))
    mine = json.loads(mine) if isinstance(mine, str) else mine
    assert job["sweep"]["omega"] == {"from": 4.0, "to": 2.0, "points": 4}
    assert job["sweep"]["mu_cn"] == {"from": 0.85, "to": 0.65, "points": 4}
    same = ("model", "integrator", "transient", "classify", "outputs", "fixed", "chains")
    assert {k: job[k] for k in same} == {k: mine[k] for k in same}
    assert main(["verify", str(path)]) == 0
    assert (campar.open(path).label.values != "").all()


def test_a_large_map_is_kept_at_a_stride_and_read_whole_where_zoomed_in(store, monkeypatch):
    """With room for 18 cells a field the 6 × 12 map is kept at stride 2: a view of the
    whole map at one pixel a cell draws every other cell; zoomed in, the tiles under the
    view are read whole and every cell is drawn."""
    import campar.explore.source as source_module

    monkeypatch.setattr(source_module, "MOSAIC_CELLS", 18)
    source = MapSource(store)
    source.scan()
    assert source.stride == 2
    labels = campar.open(store).label.values[:, ::-1]  # ω increasing, as drawn
    field = source.fields["label"]
    names = source.categories["label"]

    def drawn(box, w, h):
        values, inside = source.view(field, box, w, h)
        assert inside.all()
        return np.array([[names[v] for v in row] for row in values])

    x0, x1 = source.x_edges[[0, -1]]
    y0, y1 = source.y_edges[[0, -1]]
    coarse = drawn((x0, x1, y0, y1), 6, 3)  # 2 cells a pixel: the mosaic
    # pixel centres lie on stored rows 1, 3, 5 and columns 10, 8, …, 0 (ω drawn
    # increasing); the mosaic holds the even rows and columns: rows 0, 2, 4
    assert (coarse == campar.open(store).label.values[0::2, 10::-2]).all()
    fine = drawn((x0, x1, y0, y1), 24, 12)  # 2 pixels a cell: the tiles, whole
    assert (fine[::2, ::2] == labels).all() and (fine[1::2, 1::2] == labels).all()


@pytest.mark.process  # the explorer's server starts multiprocessing's resource tracker
def test_a_store_a_run_is_writing_is_drawn_as_its_tiles_commit(store, tmp_path):
    """Tiles not committed are pending (drawn as not computed, a cell there cannot be
    computed: one line, the server goes on); a tile committed later is verified and
    drawn by the next refresh."""
    from campar.sweep.job import Job
    from campar.sweep.plan import plan_tiles
    from campar.sweep.store import open_store, read_store

    with read_store(store) as reader:
        job = reader.job
        tiles = plan_tiles(job)
        stored = [{n: reader.read_tile(n, t) for n in reader.names} for t in tiles]
    path = tmp_path / "running.zarr"
    job = Job.from_dict({**job.to_dict(), "store": str(path)})
    with open_store(path, job) as writer:
        writer.write_tile(tiles[0], stored[0])
    server = serve([path], warm_up=False)
    try:
        _scanned(server)
        source = server.explorer.sources[0]
        assert source.status()["verified"] == 1
        assert source.cell(2, 3)["stored"] == "pending"
        refused(server, "/api/compute?row=2&col=3", 422, "not computed yet")
        field = source.fields["label"]
        box = (*source.x_edges[[0, -1]], *source.y_edges[[0, -1]])
        values, _ = source.view(field, box, 12, 6)
        assert (values[2:] == PENDING_CELL).all()
        with open_store(path, job) as writer:  # the run goes on: tile 1 commits
            writer.write_tile(tiles[1], stored[1])
        assert source.refresh() == 1
        values, _ = source.view(field, box, 12, 6)
        names = source.categories["label"]
        drawn = np.array([[names[v] for v in row] for row in values[2:4]])
        assert (drawn[:, ::-1] == campar.open(store).label.values[2:4]).all()
        assert (values[4:] == PENDING_CELL).all()
    finally:
        shutdown(server)


@pytest.mark.process
def test_hysteresis_and_a_census_as_campar_open_gives_them(tmp_path):
    """A both-directions store with a census: the layer selector's second direction, the
    hysteresis cells and a hovered cell's attractors are campar.open's."""
    path = tmp_path / "both.zarr"
    campar.run(
        {
            **JOB,
            "name": "both",
            "sweep": {
                "omega": {"from": 3.4, "to": 2.9, "points": 8},
                "mu_kn": {"from": 0.93, "to": 0.89, "points": 3},
            },
            "chains": {"direction": "both"},
            "attractors": {"starts": 3},
            "store": str(path),
        }
    )
    ds = campar.open(path)
    server = serve([path], warm_up=False)
    try:
        _scanned(server)
        (described,) = json.loads(get(server, "/api/stores")[1])
        assert described["layers"] == ["down", "up"] and not described["curves"]
        status, body = get(server, "/api/hysteresis?store=0")
        assert status == 200, body
        cells = json.loads(body)["cells"]
        assert sorted(cells) == sorted(np.argwhere(ds.hysteresis.values).tolist())
        for layer in (0, 1):
            x, y = float(ds.omega[5]), float(ds.mu_kn[1])
            cell = json.loads(get(server, f"/api/cell?x={x}&y={y}&layer={layer}")[1])
            assert cell["label"] == ds.label.values[layer, 1, 5]
            shown = [a["label"] for a in cell["attractors"]]
            stored = [a for a in ds.attractor_label.values[layer, 1, 5] if a]
            assert shown == stored and shown
        # the sets of coexisting attractors, one pixel a cell, as campar plot names them
        from campar.sweep.attractor_sets import attractor_sets

        source = server.explorer.sources[0]
        box = (*source.x_edges[[0, -1]], *source.y_edges[[0, -1]])
        for layer in (0, 1):
            values, _ = source.view(source.fields["attractor_set"], box, 8, 3, layer)
            names = source.categories["attractor_set"]
            drawn = np.array([[names[v] for v in row] for row in values])[:, ::-1]
            codes, expected = attractor_sets(
                *(ds[f"attractor_{k}"].values[layer] for k in ("kind", "n", "p")),
                ds.n_attractors.values[layer],
            )
            assert (drawn == np.array([e or "none settled" for e in expected])[codes]).all()
    finally:
        shutdown(server)


@pytest.mark.process
def test_the_continued_curves_are_those_campar_curves_stored(store, tmp_path):
    from campar.views.map_curves import read_curves

    path = tmp_path / "map.zarr"
    shutil.copytree(store, path)
    assert main(["curves", str(path), "--points", "20"]) == 0  # how many: not what is checked
    expected = read_curves(path)
    assert expected  # the map has a PD edge to seed from
    server = serve([path], warm_up=False)
    try:
        (described,) = json.loads(get(server, "/api/stores")[1])
        assert described["curves"]
        status, body = get(server, "/api/curves?store=0")
        assert status == 200, body
        shown = json.loads(body)["curves"]
        assert [(c["type"], c["n"]) for c in shown] == [(c.type, c.n) for c in expected]
        for c, e in zip(shown, expected, strict=True):
            assert np.array_equal(np.array(c["points"], float), e.values)
    finally:
        shutdown(server)
