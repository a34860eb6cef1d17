"""The explorer's numbers in headless Chromium: page ready, pan and zoom on a large store
with the server's memory, a click on a periodic cell, a zoom computed by the runner.

    python benchmarks/explore.py --map results/mu_cn.zarr --big /tmp/big.zarr

``--map``: a computed 400 × 400 store of the (ω, μcn) plane (jobs/mu_cn.yaml); ``--big``: a
4000 × 4000 store of synthetic tiles (bands of labels and a smooth duty cycle, written
through the store's own commit path), made there when missing. The server is the
``campar explore`` command in a child process; its peak memory is its VmHWM. Needs
Playwright for Python and Debian's chromium (the test extra, .ci/run).
"""

import argparse
import json
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from campar.explore.chromium import CHROMIUM, CHROMIUM_ARGS

REPEATS = 10


def make_big(path: Path, points: int = 4000) -> None:
    from campar.sweep.arrays import array_names, array_spec
    from campar.sweep.job import Job
    from campar.sweep.plan import plan_tiles
    from campar.sweep.store import open_store

    job = Job.from_dict(
        {
            "name": "big",
            "sweep": {
                "omega": {"from": 6.0, "to": 0.02, "points": points},
                "mu_cn": {"from": 0.95, "to": 0.70, "points": points},
            },
            "outputs": ["label", "dc"],
            "tiles": {"rows": 8},
        }
    )
    omega = job.omega
    with open_store(path, job) as store:
        for tile in plan_tiles(job):
            rows = np.arange(tile.row_start, tile.row_stop)[:, None]
            band = ((omega[None, :] * 3 + rows / points * 5).astype(int)) % 6
            arrays = {}
            for name in array_names(job):
                dtype, tail = array_spec(job, name)
                arrays[name] = np.zeros((tile.n_rows, points, *tail), dtype)
            arrays["kind"][:] = np.where(band == 5, 2, 0)
            arrays["n"][:] = np.where(band == 5, 0, 1 + band % 3)
            arrays["p"][:] = np.where(band == 5, 3, band % 4)
            arrays["revolutions"][:] = 10
            arrays["steps"][:] = 200
            arrays["dc"][:] = 0.5 + 0.4 * np.sin(omega[None, :] + rows / points * 3)
            store.write_tile(tile, arrays)


class Server:
    def __init__(self, *stores):
        command = [sys.executable, "-m", "campar.cli", "explore", "--no-browser", *map(str, stores)]
        started = time.perf_counter()
        self.proc = subprocess.Popen(command, stdout=subprocess.PIPE, text=True)
        line = self.proc.stdout.readline()
        self.serving_seconds = time.perf_counter() - started
        self.url = line.rsplit(" at ", 1)[1].strip()

    def peak_mib(self) -> float:
        for line in Path(f"/proc/{self.proc.pid}/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
        return float("nan")

    def stop(self) -> None:
        self.proc.terminate()
        self.proc.wait(60)


def open_page(p, url):
    browser = p.chromium.launch(executable_path=CHROMIUM, args=list(CHROMIUM_ARGS))
    page = browser.new_context(viewport={"width": 1400, "height": 900}, bypass_csp=True).new_page()
    page.set_default_timeout(600_000)
    started = time.perf_counter()
    page.goto(url)
    page.wait_for_function("window.explore && window.explore.ready")
    return browser, page, time.perf_counter() - started


def wait_until(page, expression: str, poll: float = 0.05) -> None:
    """Wait until ``expression`` (a promise's value: evaluate awaits it) is true."""
    while not page.evaluate(expression):
        time.sleep(poll)


def scanned(page) -> None:
    """Wait until the server has verified every committed tile of its stores."""
    wait_until(
        page, "fetch('/api/stores').then(r => r.json()).then(s => s.every(x => x.status.scanned))"
    )


def timed_redraw(page, action, cpu: list) -> float:
    """Seconds from the action to the view redrawn; the server's CPU seconds go to ``cpu``."""
    before = page.evaluate("window.explore.views[0].drawn")
    started = time.perf_counter()
    action()
    page.wait_for_function(f"window.explore.views[0].drawn > {before}", polling="raf")
    cpu.append(page.evaluate("window.explore.views[0].answer.cpu_seconds"))
    return time.perf_counter() - started


def bench_map(p, store: Path) -> dict:
    import campar

    out = {}
    server = Server(store)
    out["serving_s"] = server.serving_seconds
    browser, page, ready = open_page(p, server.url)
    out["ready_s"] = ready  # while the server verifies the store's tiles
    scanned(page)
    browser.close()
    browser, page, ready = open_page(p, server.url)
    out["ready_again_s"] = ready  # its tiles verified: a second browser
    ds = campar.open(store)
    box = page.locator("#map0").bounding_box()
    periodic = np.argwhere(ds.label.values == "1-1")
    rng = np.random.default_rng(1)
    clicks = []
    for k, (i, j) in enumerate(periodic[rng.choice(len(periodic), REPEATS + 1, replace=False)]):
        px, py = page.evaluate(
            "([x, y]) => window.explore.views[0].toPixel(x, y)",
            [float(ds.omega[j]), float(ds.mu_cn[i])],
        )
        page.evaluate("window.explore.cell = null")
        started = time.perf_counter()
        page.mouse.click(box["x"] + px, box["y"] + py)
        page.wait_for_function("window.explore.cell && window.explore.cell.report", polling="raf")
        if k:  # the first click warms the worker
            clicks.append(time.perf_counter() - started)
    out["click_median_s"], out["click_max_s"] = statistics.median(clicks), max(clicks)
    shutil.rmtree(store.parent / f"{store.name}.zooms", ignore_errors=True)  # computed anew
    started = time.perf_counter()
    zoom = page.evaluate(
        """async () => {
        const r = await fetch('/api/zoom?' + new URLSearchParams(
            {store: 0, x0: 1, x1: 2, y0: 0.70, y1: 0.80}), {method: 'POST'});
        return r.json(); }"""
    )
    wait_until(
        page,
        f"""fetch('/api/stores').then(r => r.json()).then(s => s[{zoom["store"]}] &&
        s[{zoom["store"]}].status.verified === s[{zoom["store"]}].status.tiles)""",
    )
    out["zoom_100x100_s"] = time.perf_counter() - started
    out["zoom_store"] = page.evaluate("fetch('/api/stores').then(r => r.json())")[zoom["store"]]
    out["zoom_store"] = {k: out["zoom_store"][k] for k in ("name", "shape", "status")}
    out["server_peak_mib"] = server.peak_mib()
    browser.close()
    server.stop()
    return out


def bench_big(p, store: Path) -> dict:
    out = {}
    server = Server(store)
    browser, page, ready = open_page(p, server.url)
    started = time.perf_counter()
    scanned(page)
    out["scan_s"] = ready + time.perf_counter() - started
    box = page.locator("#map0").bounding_box()
    cx, cy = box["x"] + 380, box["y"] + 280
    page.mouse.move(cx, cy)
    times, cpu = {"zoom": [], "pan": []}, []
    for _ in range(REPEATS):  # zoom in 1.25× a step, to 1/9 of the map: full resolution
        times["zoom"].append(timed_redraw(page, lambda: page.mouse.wheel(0, -100), cpu))
    for k in range(REPEATS):
        step = 40 if k % 2 else -40

        def drag(step=step):
            page.mouse.move(cx, cy)
            page.mouse.down()
            page.mouse.move(cx + step, cy + step / 2, steps=3)
            page.mouse.up()

        times["pan"].append(timed_redraw(page, drag, cpu))
    for _ in range(REPEATS):
        times["zoom"].append(timed_redraw(page, lambda: page.mouse.wheel(0, 100), cpu))
    for name, values in times.items():
        out[f"{name}_median_s"], out[f"{name}_max_s"] = statistics.median(values), max(values)
    out["server_cpu_median_s"], out["server_cpu_max_s"] = statistics.median(cpu), max(cpu)
    out["server_peak_mib"] = server.peak_mib()
    browser.close()
    server.stop()
    return out


def main() -> int:
    from playwright.sync_api import sync_playwright

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--map", type=Path, required=True)
    parser.add_argument("--big", type=Path, required=True)
    args = parser.parse_args()
    if not args.big.exists():
        started = time.perf_counter()
        make_big(args.big)
        print(f"made {args.big} in {time.perf_counter() - started:.0f} s", flush=True)
    with sync_playwright() as p:
        results = {"map_400": bench_map(p, args.map), "map_4000": bench_big(p, args.big)}
    print(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
