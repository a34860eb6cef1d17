"""``campar bench``: benchmarks with numbers, one module per benchmark.

Every benchmark is registered here by name with one line of help, the module
that runs it and a function that adds its arguments. The module is imported
only when its benchmark runs, so building the ``campar`` parser stays cheap;
it defines ``run(args) -> int``, prints a table and states the machine load.

For developers — a new ``campar bench NAME``: write ``campar/bench/NAME.py``
with ``run(args)`` and register its arguments below (``needs``: packages beyond
campar's own dependencies, checked before the benchmark starts)::

    @benchmark("NAME", "one line of help", needs=("scipy",))
    def _name_arguments(p):
        p.add_argument("--size", type=int, default=20)
"""

import argparse
import importlib
from collections.abc import Callable
from typing import NamedTuple

from ..errors import CamparError

# The extra that installs what the benchmarks need besides campar (SciPy).
BENCH_EXTRA = "pip install -e '.[bench]'"


class MissingPackage(CamparError):
    """A benchmark needs a package that is not installed."""


class Benchmark(NamedTuple):
    name: str
    help: str
    module: str  # campar.bench.<module> defines run(args) -> int
    add_arguments: Callable[[argparse.ArgumentParser], None]
    needs: tuple[str, ...]  # importable packages it needs beyond campar's dependencies


# Registered benchmarks, in the order ``campar bench --help`` lists them.
BENCHMARKS: dict[str, Benchmark] = {}


def benchmark(name: str, help: str, module: str | None = None, needs: tuple[str, ...] = ()):
    """Register ``campar bench NAME``; decorates the function that adds its arguments."""

    def register(add_arguments):
        BENCHMARKS[name] = Benchmark(name, help, module or name, add_arguments, needs)
        return add_arguments

    return register


def add_parser(sub) -> None:
    """The ``bench`` parser with one sub-command per registered benchmark."""
    p = sub.add_parser("bench", help="benchmarks: precision, peers, output cost, stress, …")
    inner = p.add_subparsers(dest="benchmark", required=True, metavar="BENCHMARK")
    for bench in BENCHMARKS.values():
        q = inner.add_parser(bench.name, help=bench.help, description=bench.help)
        bench.add_arguments(q)
        q.set_defaults(handler=run_benchmark)


def run_benchmark(args) -> int:
    bench = BENCHMARKS[args.benchmark]
    check_packages(bench)
    module = importlib.import_module(f"{__name__}.{bench.module}")
    return int(module.run(args) or 0)


def check_packages(bench: Benchmark) -> None:
    """MissingPackage, naming the extra to install, if a package the benchmark needs is absent."""
    for package in bench.needs:
        try:
            importlib.import_module(package)
        except ImportError:
            raise MissingPackage(
                f"benchmark {bench.name} needs {package}, which is not installed: {BENCH_EXTRA}"
            ) from None


def floats(text: str) -> list[float]:
    """Comma-separated numbers: "1e-4,1e-6"."""
    return [float(x) for x in text.split(",") if x]


def ints(text: str) -> list[int]:
    return [int(x) for x in text.split(",") if x]


def names(text: str) -> list[str]:
    return [x for x in text.split(",") if x]


# -- the benchmarks ----------------------------------------------------------


@benchmark(
    "continuation",
    "periodic-orbit continuation: speed of a branch, PD and fold "
    "points against SciPy, the hysteresis bands' folds, a map's curves",
    needs=("scipy",),
)
def _continuation_arguments(p):
    p.add_argument("--points", type=int, default=1000, help="points of the speed branch (1000)")
    p.add_argument(
        "--hysteresis-job",
        default="jobs/mu_kn_both.yaml",
        help="a chains.direction: both job (jobs/mu_kn_both.yaml)",
    )
    p.add_argument("--store", help="a map store whose curves to compute and compare")
    p.add_argument("--quick", action="store_true", help="the speed branch only")


@benchmark(
    "precision", "wall time and steps against error: DP5(4) tolerances, RK4 steps", needs=("scipy",)
)
def _precision_arguments(p):
    p.add_argument("--cells", type=names, help="comma-separated cell names (default: all)")
    p.add_argument("--rtols", type=floats, help="DP5(4) rtols (default 1e-4 … 1e-12)")
    p.add_argument("--rk4-steps", type=ints, help="RK4 steps per revolution (default 60 … 7680)")
    p.add_argument("--reference-rtol", type=float, default=1e-13, help="SciPy reference (1e-13)")
    p.add_argument(
        "--scipy-rtols",
        type=floats,
        help="SciPy DOP853 peers on the figure (default 1e-6,1e-8,1e-10; '' for none)",
    )
    p.add_argument(
        "--min-seconds",
        type=float,
        default=0.3,
        help="repeat each timing this long at least; keep the fastest",
    )
    p.add_argument("--plot", metavar="FILE.png", help="log-log figure (default: none)")
    p.add_argument("--quick", action="store_true", help="a tiny configuration (seconds)")


@benchmark(
    "peers",
    "campar against SciPy DOP853 and the paper's RK4 recipe at equal agreement",
    needs=("scipy",),
)
def _peers_arguments(p):
    from ..sweep.job import DEFAULT_CLASSIFY, DEFAULT_INTEGRATOR, DEFAULT_TRANSIENT

    revolutions = DEFAULT_TRANSIENT.max_revolutions
    window = DEFAULT_CLASSIFY.window_revolutions
    rtol = DEFAULT_INTEGRATOR.rtol
    p.add_argument("--cells", type=names, help="comma-separated cell names (default: all)")
    p.add_argument(
        "--revolutions",
        type=int,
        default=revolutions,
        help=f"transient of the RK4 recipe and of SciPy ({revolutions})",
    )
    p.add_argument(
        "--window", type=int, default=window, help=f"read window, revolutions ({window})"
    )
    p.add_argument(
        "--scipy-cells",
        type=int,
        default=-1,
        help="run SciPy on the first N cells only (default: all)",
    )
    p.add_argument(
        "--scipy-rtol", type=float, default=rtol, help=f"SciPy rtol (campar's, {rtol:g}; atol /100)"
    )
    p.add_argument(
        "--min-seconds",
        type=float,
        default=0.3,
        help="repeat each campar timing at least this long",
    )
    p.add_argument(
        "--no-row",
        action="store_true",
        help="skip the map row (16 warm-started cells of the μcn plane, ~90 s)",
    )
    p.add_argument("--quick", action="store_true", help="a tiny configuration (seconds)")


@benchmark("outputs", "cost of a labels-only map against one with every output")
def _outputs_arguments(p):
    p.add_argument("--rows", type=int, default=20, help="μcn values (20)")
    p.add_argument("--omegas", type=int, default=40, help="ω values per chain (40)")
    p.add_argument("--repeat", type=int, default=4, help="alternating runs of each; fastest (4)")
    p.add_argument("--quick", action="store_true", help="a tiny configuration (seconds)")


@benchmark(
    "stress", "extreme parameters and states: no crash, no hang, valid or failed", needs=("scipy",)
)
def _stress_arguments(p):
    p.add_argument("--budget", type=int, default=1_000_000, help="step budget per cell (1e6)")
    p.add_argument(
        "--timeout", type=float, default=120.0, help="seconds before a cell counts as hung (120)"
    )
    p.add_argument(
        "--rtols",
        type=floats,
        default=[1e-8, 1e-10],
        help="labels compared between these (1e-8,1e-10)",
    )
    p.add_argument(
        "--check", type=int, default=40, help="label changes checked against SciPy, at most (40)"
    )
    p.add_argument("--quick", action="store_true", help="the fast subset of tests/test_stress.py")


@benchmark("scaling", "runner throughput: cells/s with 1, 2, 3 ranks, overhead, memory")
def _scaling_arguments(p):
    p.add_argument("--job", default="jobs/mu_cn.yaml", help="plane (jobs/mu_cn.yaml)")
    p.add_argument("--size", type=int, default=100, help="N of the N × N sub-plane (100)")
    p.add_argument("--rows", type=int, help="chains per tile (default: the job's)")
    p.add_argument("--ranks", type=ints, default=[1, 2, 3], help="launches (1,2,3)")
    p.add_argument("--suffix", default=".zarr", help="store type: .zarr (default) or .h5")
    p.add_argument(
        "--repeat",
        type=int,
        default=1,
        help="rounds, the launches taking turns: fastest kept, and paired (1)",
    )
    p.add_argument("--quick", action="store_true", help="a tiny configuration (seconds)")


@benchmark(
    "revolutions",
    "revolutions per cell of a map: distribution, non-periodic cells' share, against a baseline",
)
def _revolutions_arguments(p):
    p.add_argument("--job", default="jobs/mu_cn.yaml", help="map job (jobs/mu_cn.yaml)")
    p.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="change one key of the job, e.g. sweep.omega.points=100 (repeatable)",
    )
    p.add_argument("--baseline", metavar="DIR", help="another campar checkout, run in turn")
    p.add_argument(
        "--adjudicate",
        action="store_true",
        help="run the cells whose label differs from the baseline's for 3000 revolutions",
    )
    p.add_argument("--quick", action="store_true", help="a tiny configuration (seconds)")


@benchmark("startup", "fixed cost of a campar run, and 1 against 2 ranks, whole and run part")
def _startup_arguments(p):
    p.add_argument("--job", default="jobs/mu_cn.yaml", help="plane (jobs/mu_cn.yaml)")
    p.add_argument("--size", type=int, default=100, help="N of the N × N sub-plane (100)")
    p.add_argument("--rounds", type=int, default=5, help="rounds, the launches taking turns (5)")
    p.add_argument("--baseline", metavar="DIR", help="another campar checkout, launched in turn")
    p.add_argument("--quick", action="store_true", help="a tiny configuration (seconds)")


@benchmark("directions", "a map of both sweep directions against one direction (down, up)")
def _directions_arguments(p):
    p.add_argument("--job", default="jobs/mu_cn.yaml", help="plane (jobs/mu_cn.yaml)")
    p.add_argument("--size", type=int, default=60, help="N of the N × N sub-plane (60)")
    p.add_argument("--repeat", type=int, default=2, help="alternating runs of each; fastest (2)")
    p.add_argument("--quick", action="store_true", help="a tiny configuration (seconds)")


@benchmark("master", "the master's capacity: tiles/s, latency to disk, idle ranks, per writer")
def _master_arguments(p):
    p.add_argument(
        "--ranks",
        type=ints,
        default=[16, 64, 128],
        help="launches, oversubscribed beyond the cores (16,64,128)",
    )
    p.add_argument("--rows", type=int, default=400, help="values of the second parameter (400)")
    p.add_argument("--omegas", type=int, default=400, help="ω values per chain (400)")
    p.add_argument("--tile-rows", type=int, default=4, help="chains per tile (4)")
    p.add_argument(
        "--tile-seconds",
        type=float,
        default=0.15,
        help="stand-in tile time (0.15 s: 4 chains of the μcn plane)",
    )
    p.add_argument("--suffix", default=".zarr", help="store type: .zarr (default) or .h5")
    p.add_argument(
        "--writer",
        type=names,
        default=["workers", "master"],
        help="who writes the workers' tiles: workers (each its own; Zarr only), "
        "master (rank 0 writes every tile); default both, side by side",
    )
    p.add_argument("--tmp", help="directory for the stores (default: the system's)")
    p.add_argument("--keep-stores", action="store_true", help="keep the stores")
    p.add_argument("--quick", action="store_true", help="a tiny configuration (seconds)")


@benchmark(
    "map",
    "map agreement with a 500-revolution rtol 1e-11 reference against run time",
    module="maps",
)
def _map_arguments(p):
    p.add_argument(
        "--planes",
        type=names,
        default=["mu_cn", "mu_kn", "omega_f0"],
        help="planes, as jobs/NAME.yaml (mu_cn,mu_kn,omega_f0)",
    )
    p.add_argument("--size", type=int, default=100, help="N of the N × N sub-plane (100)")
    p.add_argument("--candidates", type=names, help="comma-separated (default: all)")
    p.add_argument(
        "--references",
        default="results/bench-map",
        help="reference stores and verdicts (results/bench-map)",
    )
    p.add_argument("--ranks", type=int, default=2, help="ranks computing a reference (2)")
    p.add_argument(
        "--no-adjudication", action="store_true", help="skip the long runs of disagreeing cells"
    )
    p.add_argument("--list", action="store_true", help="print the disagreeing cells")
    p.add_argument(
        "--audit", action="store_true", help="audit long runs that found twice campar's period"
    )
    p.add_argument("--quick", action="store_true", help="a tiny configuration (seconds)")


@benchmark("cells", "one cell against ω (cold, warm), warm-started rows, compile and start-up")
def _cells_arguments(p):
    p.add_argument("--rtol", type=float, default=1e-9, help="integrator rtol (1e-9)")
    p.add_argument(
        "--min-seconds",
        type=float,
        default=0.3,
        help="repeat each timing this long at least; keep the fastest",
    )
    p.add_argument("--quick", action="store_true", help="a tiny configuration (seconds)")
