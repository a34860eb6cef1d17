"""A zoom's time in the explorer, warm runner against a run of its own: paired runs.

    python benchmarks/explore_zoom.py --map results/mu_cn.zarr --repeats 3

The explorer's server in this process (no browser), the store given; each repeat asks
the 100 × 100 zoom over ω 1–2, μcn 0.70–0.80 twice, in turn: (A) run by the process kept
warm for zooms (the serial runner, the map's kernel loaded), (B) run by ``mpirun -n 2
campar run`` started for it (the path of a zoom too large for the warm runner, and the
only one before it). Each is timed from the request to every tile of the zoom's store
verified by the server (what the page then draws), with the CPU seconds of the process
that ran it (A: the warm process's, read from /proc; B: mpirun's and its ranks') and the
runner's own time as its log says it (first tile to last commit): the rest is start-up
and the server's part. The zoom's store is deleted before each request, so each
computes every cell.
"""

import argparse
import json
import re
import resource
import shutil
import statistics
import sys
import time
from pathlib import Path

BOX = {"x0": 1.0, "x1": 2.0, "y0": 0.70, "y1": 0.80}


def cpu_of(pid: int) -> float:
    """User + system CPU seconds of a live process (its own, not its children's)."""
    import os

    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def one_zoom(server, warm: bool) -> tuple[float, float, float]:
    """(seconds to every tile verified, CPU seconds of the run, the runner's own seconds
    from its first tile handed out to its last committed, as its log says) of one zoom."""
    explorer = server.explorer
    runner = explorer.zoom_runner
    explorer.zoom_runner = runner if warm else None
    try:
        source = explorer.sources[0]
        shutil.rmtree(source.path.parent / f"{source.path.name}.zooms", ignore_errors=True)
        explorer.sources[1:] = []  # the last repeat's zoom store: asked again, not found
        before = cpu_of(runner._process.pid) if warm else children_cpu()
        started = time.perf_counter()
        answer = explorer.zoom({k: [str(v)] for k, v in {**BOX, "store": 0}.items()})
        added = explorer.sources[answer["store"]]
        while added.status()["verified"] < len(added.tiles):
            time.sleep(0.01)
        seconds = time.perf_counter() - started
        process = explorer._zooms[added.path]
        process.wait(120)
        cpu = (cpu_of(runner._process.pid) if warm else children_cpu()) - before
        explorer._zooms.pop(added.path)
        log = added.path.with_suffix(".log").read_text()
        (said,) = re.findall(r"complete, .* in ([0-9.]+) s", log)
        return seconds, cpu, float(said)
    finally:
        explorer.zoom_runner = runner


def main() -> int:
    from campar.explore.server import serve, shutdown

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--map", type=Path, required=True)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    server = serve([args.map], warm_up=False)
    try:
        while not server.explorer.sources[0].scanned:
            time.sleep(0.05)
        server.explorer.start_zoom_runner()
        while not server.explorer.zoom_runner.free():
            time.sleep(0.05)
        one_zoom(server, warm=True)  # not counted: the first zoom's own first-call costs
        runs = {"warm": [], "own_process": []}
        for _ in range(args.repeats):
            for name in runs:
                runs[name].append(one_zoom(server, warm=name == "warm"))
    finally:
        shutdown(server)
    out = {}
    for name, values in runs.items():
        seconds, cpu, runner = zip(*values, strict=True)
        out[name] = {
            "seconds": [round(s, 2) for s in seconds],
            "median_s": round(statistics.median(seconds), 2),
            "cpu_s": [round(c, 2) for c in cpu],
            "median_cpu_s": round(statistics.median(cpu), 2),
            "runner_s": [round(r, 2) for r in runner],
            "median_runner_s": round(statistics.median(runner), 2),
        }
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
