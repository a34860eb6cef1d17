"""``campar bench startup``: the fixed cost of a ``campar run``, and 1 against 2 ranks.

Two jobs, each launched as a whole command (``python -m campar.cli run``) one process
and under ``mpirun -n 2`` in turn (1, 2, 1, 2, …), so a machine whose speed drifts moves
both launches of a round alike:

- the **reference job**, one cell of the (ω, μcn) plane (ω = 2, μcn = 0.8, the paper's
  other values): its whole command is the fixed cost — process start to first cell,
  last cell to exit (the cell itself takes milliseconds, and its run part, store open
  to last tile, is printed apart);
- the **plane**, an N × N sub-plane of a plane job (default jobs/mu_cn.yaml at 100²): the
  speed-up of 2 ranks over one process, for the whole command and for the run part
  alone (the run log's seconds).

Per launch: the median wall seconds over the rounds, the median CPU seconds of the
command's processes (every rank, and mpirun: ``RUSAGE_CHILDREN``, which a shared machine
disturbs much less than wall time), and for the plane the median of each round's
speed-up. The machine's load is printed with them.

With ``--baseline DIR`` (another campar checkout, e.g. main's) each round launches
both, so the two are compared in the same run, paired. Every launch reads Python's
bytecode caches, as an installed campar does (``launch_environment``).

    campar bench startup                      # 5 rounds, the plane at 100²
    campar bench startup --baseline ../main --rounds 9 --size 60
"""

import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml

from ..sweep.store import read_store
from .common import machine_line
from .scaling import MPIRUN, write_job

REFERENCE = {
    "name": "startup_reference",
    "sweep": {
        "omega": {"from": 2.0, "to": 2.0, "points": 1},
        "mu_cn": {"from": 0.8, "to": 0.8, "points": 1},
    },
    "fixed": {"zeta": 0.2, "mu_kn": 0.8, "f0": 0.5},
    "model": {"tensile": "clamp"},
    "outputs": ["label", "dc", "eps", "pn"],
}
RANKS = (1, 2)
QUICK = {"size": 6, "rounds": 1}


def children_cpu() -> float:
    """CPU seconds (user + system) of every finished child of this process so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def timed_launch(job: Path, store: Path, ranks: int, tree: str | None) -> dict:
    """One whole command (campar from ``tree`` if given, else this one): its wall seconds,
    CPU seconds and the run part's seconds (store open to last tile, from its run log)."""
    launcher = [] if ranks == 1 else [str(MPIRUN), "-n", str(ranks)]
    command = [
        *launcher,
        sys.executable,
        "-P",  # the tree named, never a campar in the working directory
        "-m",
        "campar.cli",
        "run",
        str(job),
        "--store",
        str(store),
    ]
    env = launch_environment(store.parent)
    tree = tree or str(Path(__file__).resolve().parents[2])
    env["PYTHONPATH"] = os.pathsep.join([tree, *filter(None, [env.get("PYTHONPATH")])])
    cpu, start = children_cpu(), time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed ({done.returncode}):\n{done.stderr}")
    with read_store(store) as reader:
        entry = reader.attrs["runs"][-1]
    return {"wall": wall, "cpu": children_cpu() - cpu, "run": entry["seconds"]}


def launch_environment(tmp: Path) -> dict:
    """This process's environment for a launch, with Python's bytecode caches as an
    installed campar has them: where the environment says not to write them
    (``PYTHONDONTWRITEBYTECODE``), every launch would compile every module of campar from
    its source, a cost no installed campar pays; the launches then write and read them in
    a folder of the bench's own (``PYTHONPYCACHEPREFIX``), filled by the warm-up launch."""
    env = dict(os.environ)
    if env.pop("PYTHONDONTWRITEBYTECODE", None) is not None:
        env["PYTHONPYCACHEPREFIX"] = str(tmp / "pycache")
    return env


def rounds_of(job: Path, tmp: Path, name: str, rounds: int, trees: dict) -> dict:
    """(tree, ranks) → ``rounds`` launches, taking turns; each into a fresh store."""
    found = {(tree, ranks): [] for tree in trees for ranks in RANKS}
    for r in range(rounds):
        for tree, path in trees.items():
            for ranks in RANKS:
                store = tmp / f"{name}-{tree}-{ranks}-{r}.zarr"
                found[tree, ranks].append(timed_launch(job, store, ranks, path))
    return found


def median(runs: list[dict], key: str) -> float:
    return statistics.median(run[key] for run in runs)


def paired(a: list[dict], b: list[dict], key: str) -> float:
    """The median over rounds of each round's a / b."""
    return statistics.median(x[key] / y[key] for x, y in zip(a, b, strict=True))


def launch_name(tree: str, ranks: int) -> str:
    return f"{tree}: " + ("1 process" if ranks == 1 else f"mpirun -n {ranks}")


def run(args) -> int:
    if args.quick:
        for key, value in QUICK.items():
            setattr(args, key, value)
    print(machine_line())
    trees = {"this": None}
    if args.baseline:
        trees["baseline"] = str(Path(args.baseline).resolve())
    with tempfile.TemporaryDirectory(prefix="campar-bench-") as tmp:
        tmp = Path(tmp)
        reference = tmp / "reference.yaml"
        reference.write_text(yaml.safe_dump(REFERENCE, sort_keys=False))
        for tree, path in trees.items():  # compiles if a cache is cold
            timed_launch(reference, tmp / f"warm-{tree}.zarr", 1, path)
        (tmp / "plane").mkdir()
        plane = write_job(Path(args.job), tmp / "plane", args.size, None)
        fixed = rounds_of(reference, tmp, "reference", args.rounds, trees)
        maps = rounds_of(plane, tmp, "plane", args.rounds, trees)
    print(f"\nreference job: one cell (ω = 2, μcn = 0.8), {args.rounds} rounds, medians")
    print(f"{'launch':>22}  {'fixed s':>8}  {'CPU s':>6}  {'run part s':>10}")
    for key, runs in fixed.items():
        print(
            f"{launch_name(*key):>22}  {median(runs, 'wall'):8.3f}  "
            f"{median(runs, 'cpu'):6.2f}  {median(runs, 'run'):10.3f}"
        )
    if "baseline" in trees:
        for ranks in RANKS:
            a, b = fixed["this", ranks], fixed["baseline", ranks]
            print(
                f"this / baseline, {launch_name('', ranks)[2:]}: fixed "
                f"{paired(a, b, 'wall'):.2f}×, CPU {paired(a, b, 'cpu'):.2f}× (paired)"
            )
    print(f"\n{args.job} at {args.size}×{args.size}, {args.rounds} rounds, medians")
    print(
        f"{'launch':>22}  {'whole s':>8}  {'CPU s':>6}  {'run s':>6}  "
        f"{'whole 1/2':>9}  {'run 1/2':>7}"
    )
    for tree in trees:
        for ranks in RANKS:
            runs, one = maps[tree, ranks], maps[tree, 1]
            print(
                f"{launch_name(tree, ranks):>22}  {median(runs, 'wall'):8.2f}  "
                f"{median(runs, 'cpu'):6.2f}  {median(runs, 'run'):6.2f}  "
                f"{paired(one, runs, 'wall'):8.2f}×  {paired(one, runs, 'run'):6.2f}×"
            )
        ratios = [a["wall"] / b["wall"] for a, b in zip(maps[tree, 1], maps[tree, 2], strict=True)]
        print(f"  {tree}: whole-command 1/2 by round: " + " ".join(f"{x:.2f}×" for x in ratios))
    print(machine_line())
    return 0
