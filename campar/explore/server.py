"""The explorer's HTTP server: the page, and a JSON route per question it asks.

Standard library only (``http.server``, one thread per request). It binds 127.0.0.1
unless told otherwise, answers only its own routes — the page's files by name
and the ``/api/`` routes, the stores by their index among those it was given, never a
path taken from a request — and refuses a request naming another host (a page of
another site reaching it through DNS rebinding). A bad request gets a 4xx with one
line of text; a computation that fails or runs over its time limit gets one line
too, and the server goes on.
"""

import base64
import contextlib
import json
import logging
import math
import subprocess
import threading
import time
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from pathlib import Path
from urllib.parse import parse_qs, urlsplit

import numpy as np

from ..errors import CamparError
from ..views.map_curves import curves_store_path
from . import render
from .lines import MAX_LINE_POINTS
from .source import MapSource
from .worker import WARM_UP_SECONDS, CellWorker

log = logging.getLogger("campar.explore")

STATIC = {  # served path → (file of campar/explore/static, content type)
    "/": ("index.html", "text/html; charset=utf-8"),
    "/explore.js": ("explore.js", "text/javascript; charset=utf-8"),
    "/plots.js": ("plots.js", "text/javascript; charset=utf-8"),
    "/exports.js": ("exports.js", "text/javascript; charset=utf-8"),
    "/overlays.js": ("overlays.js", "text/javascript; charset=utf-8"),
    "/lines.js": ("lines.js", "text/javascript; charset=utf-8"),
    "/explore.css": ("explore.css", "text/css; charset=utf-8"),
}
# The page runs only its own script (no inline or evaluated code); images are its maps.
CSP = "default-src 'self'; img-src 'self' data: blob:; style-src 'self' 'unsafe-inline'"
LOOPBACK_NAMES = frozenset({"127.0.0.1", "localhost", "::1"})
MAX_PIXELS = 4096  # a view's width or height
REFRESH_SECONDS = 0.5  # how often a store a run writes is looked at again
ZOOM_REFRESH_SECONDS = 0.1  # … a zoom's store, whose tiles commit a few a second
MAX_STARTS = 200  # starts of an attractor census from the page
MAX_CYCLE = 64  # period of a cycle by shooting from the page
LINES = ("row", "column", "segment")  # what a bifurcation line runs along
MAX_EDGE_CELLS = 400 * 400  # cells of a view whose edges are typed at a request
ZOOM_POINTS = 100  # a zoom's cells along each side
ZOOM_START_SECONDS = 60.0  # until a zoom's run has created its store
ZOOM_STOP_SECONDS = 30.0  # for a zoom's run to stop at a tile's end when the server stops


class BadRequest(Exception):
    """A request the server refuses: 400 with its one line."""


class Explorer:
    """The stores served, their scanners, and the cell worker."""

    def __init__(self, paths, cell_seconds: float | None = None):
        self.sources = [MapSource(p) for p in paths]
        self.worker = CellWorker(**({} if cell_seconds is None else {"seconds": cell_seconds}))
        self._stop = threading.Event()
        self._zoom_lock = threading.Lock()
        self._zooms = {}  # zoom store → its run's process
        self._ranges = {}  # (store, field, layer) → (tiles verified, (low, high))
        self.zoom_ranks = 2
        self.zoom_runner = None  # the warm process for small zooms (started by the warm-up)
        self._threads = [
            threading.Thread(target=self._watch, args=(s,), daemon=True) for s in self.sources
        ]

    def start(self, warm_up: bool = True) -> None:
        """Scan the stores; with ``warm_up``, start the cell worker and load its kernel."""
        for thread in self._threads:
            thread.start()
        if warm_up:
            threading.Thread(target=self._warm_up, daemon=True).start()

    def _warm_up(self) -> None:
        # after the scans: the first view is drawn before the worker's imports compete
        while not self._stop.is_set() and not all(s.scanned for s in self.sources):
            self._stop.wait(0.1)
        try:
            self.worker.run("warm_up", seconds=WARM_UP_SECONDS)
        except CamparError as exc:  # the first click says it again
            log.warning("warming the cell worker up: %s", exc)
        if not self._stop.is_set():  # after the worker's: its kernel is then in the cache
            self.start_zoom_runner()

    def start_zoom_runner(self) -> None:
        """Start the process kept warm for small zooms (the first store's kernel loaded)."""
        from .zoom import ZoomRunner

        runner = ZoomRunner()
        runner.start(self.sources[0].job)
        self.zoom_runner = runner

    def stop(self) -> None:
        self._stop.set()
        self.worker.stop()
        for store, process in self._zooms.items():
            if process.poll() is None:
                process.terminate()  # the run stops at a tile's end: resumable
                try:
                    process.wait(ZOOM_STOP_SECONDS)
                except subprocess.TimeoutExpired:
                    log.warning("the zoom's run into %s did not stop: killed", store)
                    process.kill()  # its committed tiles stay; a resume redoes the rest
                    process.wait()
        if self.zoom_runner is not None:
            self.zoom_runner.stop()

    def _watch(self, source: MapSource, seconds: float = REFRESH_SECONDS) -> None:
        """Scan the store, then look at it again every ``seconds`` while a tile is not
        shown (pending, or masked as damaged: a run may complete or repair it). A look
        that fails (a store being repaired or replaced) is said once and tried again."""
        while True:
            try:
                if not source.scanned:
                    source.scan()
                elif source.status()["verified"] < len(source.tiles):
                    source.refresh()
                source.problem = None
            except Exception as exc:  # the page shows the store as it was; the server goes on
                if source.problem is None:  # a campar error says itself in one line
                    trace = not isinstance(exc, CamparError)
                    log.warning("watching %s: %s", source.path, exc, exc_info=trace)
                source.problem = f"the store cannot be read now ({type(exc).__name__}: {exc})"
            if self._stop.wait(seconds):
                return

    # -- answers ---------------------------------------------------------------------------

    def stores(self) -> list[dict]:
        return [_describe(i, s) for i, s in enumerate(self.sources)]

    def map_view(self, q: dict) -> dict:
        source = self._source(q)
        field = _choice(q, "field", source.fields)
        layer = _integer(q, "layer", 0, source.layers - 1, default=0)
        box = tuple(_number(q, k) for k in ("x0", "x1", "y0", "y1"))
        if not (box[0] < box[1] and box[2] < box[3]):
            raise BadRequest("the view needs x0 < x1 and y0 < y1")
        w, h = (_integer(q, k, 1, MAX_PIXELS) for k in ("w", "h"))
        started, cpu = time.perf_counter(), time.process_time()
        values, inside = source.view(field, box, w, h, layer)
        answer = {"field": field.name, "status": source.status()}
        if "diff" in q:  # the other store's view of the same box: where they differ
            # the other of the two stores given (zooms added later are not compared)
            other = self.sources[1 if source is self.sources[0] else 0]
            other = None if other is source else other
            if other is None or field.name not in other.fields:
                raise BadRequest("a difference needs two stores with the field")
            theirs, inside2 = other.view(other.fields[field.name], box, w, h, layer)
            image, answer["legend"] = _difference(field, source, other, values, theirs)
            inside &= inside2
            image[~inside] = render.BACKGROUND
        elif field.categorical:
            names = tuple(source.categories[field.name])
            counts = tuple(source.legend(field, layer))
            sets = field.name == "attractor_set"
            answer["legend"], colours = render.category_legend(names, counts, sets)
            image = render.draw_categories(values, inside, names, colours)
        else:
            low, high = self._range(source, field, layer)
            answer["range"] = [low, high]
            image = render.draw_numbers(values, inside, low, high)
        answer["image"] = "data:image/png;base64," + base64.b64encode(render.png(image)).decode()
        answer["seconds"] = round(time.perf_counter() - started, 4)
        answer["cpu_seconds"] = round(time.process_time() - cpu, 4)  # the server process
        return answer

    def _range(self, source: MapSource, field, layer: int) -> tuple[float, float]:
        """A numeric field's range over the map, computed again only as the map grows."""
        key = (id(source), field.name, layer)
        verified = source.status()["verified"]
        cached = self._ranges.get(key)
        if cached is None or cached[0] != verified:
            cached = (verified, render.value_range(source.mosaic[field.name, layer]))
            self._ranges[key] = cached
        return cached[1]

    def cell(self, q: dict) -> dict:
        source = self._source(q)
        layer = _integer(q, "layer", 0, source.layers - 1, default=0)
        x, y = _number(q, "x"), _number(q, "y")
        rows, cols = source.pixel_cells((x - 1e-12, x + 1e-12, y - 1e-12, y + 1e-12), 1, 1)
        if rows[0] < 0 or cols[0] < 0:
            return {"outside": True}
        stored = source.cell(int(rows[0]), int(cols[0]), layer)
        arrays = stored.pop("arrays", None)
        if arrays is not None:
            stored.update(_cell_values(source, arrays))
        return stored

    def compute(self, q: dict, action: str) -> dict:
        source = self._source(q)
        if action == "line":
            return self.worker.run("line", str(source.path), *_line_arguments(q, source))
        row = _integer(q, "row", 0, source.rows - 1)
        col = _integer(q, "col", 0, source.cols - 1, default=0)
        args = [str(source.path), row, col]
        if action == "cell":
            args.append(_integer(q, "layer", 0, source.layers - 1, default=0))
        elif action == "branch":  # along the line's row or column
            args.append(_choice(q, "along", {"row": "row", "column": "column"}, "row"))
        elif action == "attractors":
            args.append(_integer(q, "k", 2, MAX_STARTS, default=16))
        else:
            args.append(_integer(q, "n", 1, MAX_CYCLE))
        return self.worker.run(action, *args)

    def edges(self, q: dict) -> dict:
        """The typed edges of the cells in a view (computed in the worker, bounded)."""
        source = self._source(q)
        box = tuple(_number(q, k) for k in ("x0", "x1", "y0", "y1"))
        rows, cols = source.pixel_cells(box, 2, 2)  # the view's corner cells
        cells = (abs(int(rows[1]) - int(rows[0])) + 1) * (abs(int(cols[1]) - int(cols[0])) + 1)
        if cells > MAX_EDGE_CELLS:
            raise BadRequest(
                f"zoom in to type the edges: the view holds ~{cells} cells, "
                f"more than {MAX_EDGE_CELLS}"
            )
        return self.worker.run("edges", str(source.path), box)

    def overlay(self, q: dict, action: str) -> dict:
        """The continued curves or the hysteresis cells of a store (in the worker)."""
        return self.worker.run(action, str(self._source(q).path))

    def zoom(self, q: dict) -> dict:
        """Start (or find) the zoom of a rectangle; its store is served once it exists."""
        from .zoom import WARM_CELLS, start_zoom, zoom_job, zoom_store

        source = self._source(q)
        box = tuple(_number(q, k) for k in ("x0", "x1", "y0", "y1"))
        points = _integer(q, "points", 2, 400, default=ZOOM_POINTS)
        job = zoom_job(source, box, points)
        store = zoom_store(source, job)
        with self._zoom_lock:
            for index, other in enumerate(self.sources):
                if other.path == store:
                    return {"store": index, "name": store.name, "running": self._running(store)}
            if not self._running(store):
                warm = self.zoom_runner
                small = job.shape[0] * job.shape[1] <= WARM_CELLS
                try:
                    if small and warm is not None and warm.free():
                        self._zooms[store] = warm.run(source, job)[1]
                    else:
                        self._zooms[store] = start_zoom(source, job, self.zoom_ranks)[1]
                except OSError as exc:
                    raise CamparError(
                        f"cannot start the zoom beside {source.path}: {exc}"
                    ) from None
            deadline = time.monotonic() + ZOOM_START_SECONDS
            while True:
                try:
                    added = MapSource(store)
                    break
                except CamparError:
                    if time.monotonic() > deadline or not self._running(store):
                        raise CamparError(
                            f"the zoom's run did not create its store (its log: "
                            f"{store.with_suffix('.log')})"
                        ) from None
                    time.sleep(0.1)
            self.sources.append(added)
            # its tiles come fast: looked at as often as a page redraws
            thread = threading.Thread(
                target=self._watch, args=(added, ZOOM_REFRESH_SECONDS), daemon=True
            )
            thread.start()
            return {"store": len(self.sources) - 1, "name": store.name, "running": True}

    def _running(self, store) -> bool:
        process = self._zooms.get(store)
        return process is not None and process.poll() is None

    def _source(self, q: dict) -> MapSource:
        return self.sources[_integer(q, "store", 0, len(self.sources) - 1, default=0)]


def _line_arguments(q: dict, source: MapSource) -> list:
    """(along, row, col, row2, col2, points) of a line: ``along`` row (default) needs
    ``row``, column needs ``col``, segment needs both cells and may give ``points``."""
    along = _choice(q, "along", {k: k for k in LINES}, "row")
    row = _integer(q, "row", 0, source.rows - 1, default=0 if along == "column" else None)
    col = _integer(q, "col", 0, source.cols - 1, default=0 if along == "row" else None)
    if along != "segment":
        return [along, row, col, None, None, None]
    row2 = _integer(q, "row2", 0, source.rows - 1)
    col2 = _integer(q, "col2", 0, source.cols - 1)
    points = None if "points" not in q else _integer(q, "points", 2, MAX_LINE_POINTS)
    return [along, row, col, row2, col2, points]


def _describe(index: int, s: MapSource) -> dict:
    job = s.job
    return {
        "store": index,
        "name": s.path.name,
        "job": job.name,
        "x": {
            "name": job.first,
            "edges": [float(s.x_edges[0]), float(s.x_edges[-1])],
            "values": job.first_values.tolist(),
        },
        "y": {
            "name": job.second,
            "edges": [float(s.y_edges[0]), float(s.y_edges[-1])],
            "values": job.second_values.tolist(),
        },
        "shape": [s.rows, s.cols],
        "layers": list(job.directions),
        "curves": Path(curves_store_path(s.path)).exists(),
        "fields": [
            {"name": f.name, "title": f.title, "categorical": f.categorical}
            for f in s.fields.values()
        ],
        "status": s.status(),
    }


def _cell_values(source: MapSource, arrays: dict) -> dict:
    from ..core.codes import KIND_NAMES, Flag, Kind, cell_label, status_message

    kind = int(arrays["kind"])
    out = {}
    if kind < 0:
        out["label"] = "not computed"
        return out
    out["label"] = cell_label(
        kind, int(arrays["n"]), int(arrays["p"]), source.job.classify.chatter_p
    )
    out["kind"] = KIND_NAMES.get(Kind(kind), str(kind)) if kind in set(Kind) else str(kind)
    out["status"] = status_message(int(arrays["status"]))
    out["flags"] = [f.name.lower() for f in Flag if f and int(arrays["flags"]) & f]
    for name in ("n", "p", "revolutions", "steps"):
        if name in arrays:
            out[name] = int(arrays[name])
    for name in ("dc", "eps_min", "eps_max", "pn_max", "lyapunov"):
        if name in arrays:
            out[name] = _json_number(arrays[name])
    if "multipliers" in arrays:
        out["multipliers"] = [[_json_number(a), _json_number(b)] for a, b in arrays["multipliers"]]
    out["state"] = [_json_number(a) for a in arrays["state"]]
    if "attractor_kind" in arrays:  # a census: the coexisting attractors, most frequent first
        out["attractors"] = [
            {
                "label": cell_label(int(k), int(n), int(p), source.job.classify.chatter_p),
                "fraction": _json_number(f),
            }
            for k, n, p, f in zip(
                arrays["attractor_kind"],
                arrays["attractor_n"],
                arrays["attractor_p"],
                arrays["attractor_fraction"],
                strict=True,
            )
            if k >= 0
        ]
    return out


def _difference(field, mine: MapSource, other: MapSource, a, b):
    """(image, legend) of where two views differ: categories same/different, numbers A − B."""
    if field.categorical:
        names_a, names_b = mine.categories[field.name], other.categories[field.name]
        ta = np.array([*names_a, ""])[a]  # -1 and -2 index the "" pad: no category
        tb = np.array([*names_b, ""])[b]
        same = ta == tb
        image = np.zeros((*a.shape, 4), np.uint8)
        image[same] = (224, 224, 224, 255)
        image[~same] = (202, 0, 32, 255)
        legend = [
            {"label": "same", "count": int(same.sum()), "colour": "#e0e0e0", "members": []},
            {"label": "different", "count": int((~same).sum()), "colour": "#ca0020"},
        ]
        return image, legend
    d = a.astype(np.float64) - b
    bound = float(np.nanmax(np.abs(d))) if np.isfinite(d).any() else 1.0
    image = render.draw_numbers(d, np.ones(d.shape, bool), -bound, bound)
    return image, [{"label": f"A − B in [{-bound:.4g}, {bound:.4g}]", "count": d.size}]


def _json_number(x):
    x = float(x)
    return x if math.isfinite(x) else None


def _one(q: dict, key: str) -> str | None:
    values = q.get(key)
    if values is None:
        return None
    if len(values) != 1:
        raise BadRequest(f"{key} given {len(values)} times")
    return values[0]


def _number(q: dict, key: str) -> float:
    text = _one(q, key)
    if text is None:
        raise BadRequest(f"missing {key}")
    try:
        value = float(text)
    except ValueError:
        raise BadRequest(f"{key} must be a number, got {text[:40]!r}") from None
    if not math.isfinite(value):
        raise BadRequest(f"{key} must be finite, got {text[:40]!r}")
    return value


def _integer(q: dict, key: str, low: int, high: int, default: int | None = None) -> int:
    text = _one(q, key)
    if text is None:
        if default is None:
            raise BadRequest(f"missing {key}")
        return default
    try:
        value = int(text)
    except ValueError:
        raise BadRequest(f"{key} must be an integer, got {text[:40]!r}") from None
    if not low <= value <= high:
        raise BadRequest(f"{key} must be in [{low}, {high}], got {value}")
    return value


def _choice(q: dict, key: str, choices, default: str | None = None):
    text = _one(q, key)
    if text is None:
        text = default
    if text not in choices:
        raise BadRequest(f"{key} must be one of {', '.join(choices)}, got {str(text)[:40]!r}")
    return choices[text]


class Handler(BaseHTTPRequestHandler):
    """One request; ``server.explorer`` answers it."""

    server_version = "campar-explore"
    protocol_version = "HTTP/1.1"

    def do_GET(self):  # noqa: N802 (http.server's name)
        self._answer("GET")

    def do_POST(self):  # noqa: N802 (what changes something: starts a zoom's run)
        self._answer("POST")

    def _answer(self, method: str) -> None:
        try:
            self._check_host()
            url = urlsplit(self.path)
            if method == "GET" and url.path in STATIC:
                name, kind = STATIC[url.path]
                body = resources.files(__package__).joinpath("static", name).read_bytes()
                return self._send(HTTPStatus.OK, body, kind)
            q = parse_qs(url.query, keep_blank_values=True, max_num_fields=32)
            explorer = self.server.explorer
            routes = {
                "/api/stores": lambda: explorer.stores(),
                "/api/map": lambda: explorer.map_view(q),
                "/api/cell": lambda: explorer.cell(q),
                "/api/compute": lambda: explorer.compute(q, "cell"),
                "/api/attractors": lambda: explorer.compute(q, "attractors"),
                "/api/cycle": lambda: explorer.compute(q, "cycle"),
                "/api/line": lambda: explorer.compute(q, "line"),
                "/api/branch": lambda: explorer.compute(q, "branch"),
                "/api/edges": lambda: explorer.edges(q),
                "/api/curves": lambda: explorer.overlay(q, "curves"),
                "/api/hysteresis": lambda: explorer.overlay(q, "hysteresis"),
            }
            if method == "POST":
                routes = {"/api/zoom": lambda: explorer.zoom(q)}
            if url.path not in routes:
                return self._line(HTTPStatus.NOT_FOUND, f"no such page: {url.path[:80]}")
            body = json.dumps(routes[url.path](), allow_nan=False).encode()
            return self._send(HTTPStatus.OK, body, "application/json")
        except BadRequest as exc:
            return self._line(HTTPStatus.BAD_REQUEST, str(exc))
        except CamparError as exc:  # a failed computation: the page shows it
            return self._line(HTTPStatus.UNPROCESSABLE_ENTITY, str(exc))
        except (ValueError, IndexError) as exc:
            return self._line(HTTPStatus.BAD_REQUEST, f"{type(exc).__name__}: {exc}")
        except Exception as exc:
            log.exception("request %s", self.path[:200])
            return self._line(HTTPStatus.INTERNAL_SERVER_ERROR, f"{type(exc).__name__}: {exc}")

    def _check_host(self) -> None:
        host = (self.headers.get("Host") or "").rsplit(":", 1)[0].strip("[]")
        allowed = self.server.allowed_hosts
        if allowed is not None and host not in allowed:
            raise BadRequest(f"requests name this server by its address, not {host[:60]!r}")

    def _line(self, status: HTTPStatus, text: str) -> None:
        line = " ".join(text.split())[:300]
        self._send(status, f"{status.value} {status.phrase}: {line}\n".encode(), "text/plain")

    def _send(self, status: HTTPStatus, body: bytes, kind: str) -> None:
        self.send_response(status)
        self.send_header("Content-Type", kind)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("Content-Security-Policy", CSP)
        self.end_headers()
        self.wfile.write(body)

    def send_error(self, code, message=None, explain=None):
        """http.server's own refusals (a malformed request line, …): one line too."""
        self.close_connection = True
        with contextlib.suppress(Exception):  # the client went away
            self._line(HTTPStatus(code), message or HTTPStatus(code).phrase)

    def log_message(self, format, *args):  # noqa: A002 (http.server's name)
        log.debug("%s %s", self.address_string(), format % args)


class ExploreServer(ThreadingHTTPServer):
    daemon_threads = True

    def __init__(self, explorer: Explorer, host: str = "127.0.0.1", port: int = 0):
        super().__init__((host, port), Handler)
        self.explorer = explorer
        # on the loopback interface only this machine's names reach it; on another
        # interface the user has chosen who may (the Host header is then not checked)
        self.allowed_hosts = LOOPBACK_NAMES if host in LOOPBACK_NAMES else None

    @property
    def url(self) -> str:
        host, port = self.server_address[:2]
        return f"http://{host}:{port}/"


def serve(paths, host: str = "127.0.0.1", port: int = 0, cell_seconds=None, warm_up=True):
    """An ExploreServer of the stores ``paths``, started on its own thread."""
    explorer = Explorer(paths, cell_seconds)
    server = ExploreServer(explorer, host, port)
    explorer.start(warm_up)
    # A short poll: ``shutdown`` waits for the loop's next turn.
    threading.Thread(target=server.serve_forever, args=(0.05,), daemon=True).start()
    return server


def shutdown(server: ExploreServer) -> None:
    server.shutdown()
    server.server_close()
    server.explorer.stop()
