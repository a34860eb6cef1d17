"""The explorer's store reading in this process, against another revision's, paired.

    git show main:campar/explore/source.py > /tmp/source_base.py
    python benchmarks/explore_views.py --big /tmp/big.zarr --base /tmp/source_base.py

On a 4000 × 4000 synthetic store (``explore.make_big``, made when missing): a
``MapSource`` of this tree (A) and one of the module given with ``--base`` (B), in turn,
three times each: the scan (every tile verified and taken in), a view of 1/9 of the map
at 698 × 504 pixels (full resolution: its tiles read for the first time), the same view
again (the cache), and six pans of 40 pixels; wall and CPU seconds, medians.
"""

import argparse
import importlib.util
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from explore import make_big  # noqa: E402

WIDTH, HEIGHT = 698, 504  # the page's map, inside its axes


def timed(action) -> tuple[float, float]:
    cpu, wall = time.process_time(), time.perf_counter()
    action()
    return time.perf_counter() - wall, time.process_time() - cpu


def views(module, big: Path) -> dict:
    out = {}
    source = module.MapSource(big)
    out["scan"] = timed(source.scan)
    field = source.fields["label"]
    x0, x1 = source.x_edges[[0, -1]]
    y0, y1 = source.y_edges[[0, -1]]
    cx, cy, dx, dy = x0 + 0.4 * (x1 - x0), y0 + 0.55 * (y1 - y0), (x1 - x0) / 6, (y1 - y0) / 6
    box = [cx - dx, cx + dx, cy - dy, cy + dy]
    for name in ("view_first", "view_again"):
        out[name] = timed(lambda b=tuple(box): source.view(field, b, WIDTH, HEIGHT))
    pans = []
    for k in range(6):
        step = (40 if k % 2 else -40) / WIDTH * (box[1] - box[0])
        box = [box[0] + step, box[1] + step, box[2] + step / 2, box[3] + step / 2]
        pans.append(timed(lambda b=tuple(box): source.view(field, b, WIDTH, HEIGHT)))
    out["pan"] = tuple(statistics.median(p[i] for p in pans) for i in (0, 1))
    return out


def main() -> int:
    import campar.explore.source as mine

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--big", type=Path, required=True)
    parser.add_argument("--base", type=Path, required=True, help="another source.py")
    args = parser.parse_args()
    spec = importlib.util.spec_from_file_location("campar.explore._source_base", args.base)
    base = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = base
    spec.loader.exec_module(base)
    if not args.big.exists():
        make_big(args.big)
    runs = {"A (this tree)": [], "B (--base)": []}
    for _ in range(3):
        for name, module in zip(runs, (mine, base), strict=True):
            runs[name].append(views(module, args.big))
    for name, done in runs.items():
        medians = {
            k: [round(statistics.median(r[k][i] for r in done), 3) for i in (0, 1)] for k in done[0]
        }
        print(name, "(wall s, CPU s):", medians)
    return 0


if __name__ == "__main__":
    sys.exit(main())
