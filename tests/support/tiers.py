"""The test tiers, as a pytest plugin (conftest loads it).

Plain ``pytest`` runs the unit and integration tier: every test without a tier marker.
A tier marker says what a test does that costs more than a contributor's inner loop:

- ``process``: starts any child process (campar, a Python probe, mount, ...);
- ``mpi``: starts mpirun (implies ``process``);
- ``slurm``: starts a SLURM cluster or job (implies ``process``);
- ``browser``: starts a browser (implies ``process``);
- ``slow``: a cold numba compile, a large store or a long computation, in this process.

``--all-tiers`` runs every tier (the README's test command); ``-m EXPR`` selects by marker
as usual (``-m mpi``, ``-m "not slow"``), and a test named by its node id always runs.

``pytest`` without paths (the tier, or every tier) runs on every core under pytest-xdist
when it is installed, as ``-n auto`` would; ``-n N`` (``-n 0``: this process), ``-p
no:xdist``, ``--pdb`` and named files or tests keep their usual meaning, and a machine of
one core runs in this process.

The markers are applied by what a test does, not by memory: while a test runs (its
fixtures included), an audit hook records every program it starts, and a test that starts
one without ``process``, or mpirun without ``mpi`` (SLURM without ``slurm``, a browser
without ``browser``), fails with one line saying which marker it lacks. A fork is not a
program started: it copies this interpreter, imports nothing and costs no start-up (campar
forks a helper to split a cold compile, in whichever test compiles first).

Under pytest-xdist, a test marked ``mpi`` or ``slurm`` runs alone: it takes an exclusive
lock that every other test takes shared, so its ranks get the machine's cores instead of
sharing them with another worker's test (a pending exclusive request stops new shared
ones, so the MPI tests are not starved). Each worker runs its exclusive tests first, back
to back under one hold, then the modules with tests of other tiers, then the unit tests
(``run_order``): the machine is handed over once, and no long test starts last.

Every test has 120 s (pytest-timeout; longer where a test says why with
``@pytest.mark.timeout``). The timeout catches a hang, not a slow machine: on a machine
whose load average exceeds its cores the timer is stretched by load / cores (at most 10×),
measured as the test starts.

At the end, one line gives each tier's test count and summed test time.
"""

import _posixsubprocess
import contextlib
import fcntl
import os
import shlex
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

import pytest

TIERS = ("process", "mpi", "slurm", "browser", "slow")
IMPLY_PROCESS = ("mpi", "slurm", "browser")
# Tests that get the machine to themselves under xdist.
EXCLUSIVE = ("mpi", "slurm")

# What a started program needs besides ``process``, by the basename of any of its words.
PROGRAMS = {
    "mpi": {"mpirun", "mpiexec", "mpiexec.hydra", "hydra_pmi_proxy"},
    "slurm": {"srun", "sbatch", "salloc", "slurmctld", "slurmd", "scontrol", "sinfo"},
}
BROWSER_WORDS = ("chrome", "chromium", "headless_shell", "playwright", "firefox")
# Programs that libraries start on their own, once a machine, to find fonts or libraries
# (matplotlib's font cache, ctypes.util.find_library, platform.processor): not the test's.
LIBRARY_PROBES = {"fc-list", "uname", "ldconfig", "ldconfig.real"}

# Audit events of a program started (sys.audit). multiprocessing's spawn and forkserver
# start theirs with _posixsubprocess.fork_exec, which raises none: the plugin wraps it.
START_EVENTS = frozenset({"subprocess.Popen", "os.posix_spawn", "os.system", "os.spawn"})


class Watch:
    """The programs the running test has started, since the last ``take``."""

    def __init__(self) -> None:
        self.active = False
        self.starts: list[list[str]] = []

    def audit(self, event: str, args: tuple) -> None:
        if not self.active or event not in START_EVENTS:
            return
        if event == "subprocess.Popen":
            executable, argv = args[0], args[1]
            words = shlex.split(argv) if isinstance(argv, str) else [str(a) for a in argv]
            if executable is not None and not words:
                words = [str(executable)]
        elif event == "os.posix_spawn":
            words = [str(a) for a in args[1]]
        elif event == "os.system":
            words = shlex.split(str(args[0]))
        else:  # os.spawn
            words = [str(a) for a in args[2]]
        self.note(words)

    def note(self, words: list[str]) -> None:
        if not self.active or (words and Path(words[0]).name in LIBRARY_PROBES):
            return
        if not self.starts or self.starts[-1] != words:  # Popen's audit, then its fork_exec
            self.starts.append(words)

    def fork_exec(self, original):
        def fork_exec(args, *rest, **kwargs):
            self.note([os.fsdecode(a) for a in args or ()])
            return original(args, *rest, **kwargs)

        return fork_exec

    def take(self) -> list[list[str]]:
        starts, self.starts = self.starts, []
        return starts


WATCH = Watch()


def required_markers(words: list[str]) -> set[str]:
    """The markers a test that starts ``words`` needs."""
    names = {Path(word).name for word in words}
    needed = {"process"}
    needed |= {marker for marker, programs in PROGRAMS.items() if names & programs}
    if any(part in name.lower() for name in names for part in BROWSER_WORDS):
        needed.add("browser")
    return needed


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--all-tiers",
        action="store_true",
        help="run every tier: also the tests marked " + ", ".join(TIERS),
    )


def pytest_configure(config: pytest.Config) -> None:
    if not getattr(sys, "_campar_tiers_audit", False):
        # An audit hook cannot be removed: one a process, idle outside a test's run.
        sys.addaudithook(WATCH.audit)
        sys._campar_tiers_audit = True
        _posixsubprocess.fork_exec = WATCH.fork_exec(_posixsubprocess.fork_exec)


def default_workers(config: pytest.Config) -> int | None:
    """The xdist workers plain ``pytest`` runs with (None: as the command line says)."""
    if (
        not config.pluginmanager.has_plugin("xdist")
        or getattr(config, "workerinput", None) is not None
        or config.args_source is not pytest.Config.ArgsSource.TESTPATHS
        or config.getoption("numprocesses") is not None
        or config.getoption("dist") != "no"
        or config.getoption("tx")
        or config.getoption("usepdb")
        or config.getoption("collectonly")
    ):
        return None
    workers = config.hook.pytest_xdist_auto_num_workers(config=config)
    return workers if workers > 1 else None


# A wrapper, so that it runs before xdist's own turns -n into workers whichever plugin
# was registered first. A worker's start-up (campar imported, the compiled kernel loaded:
# a few CPU seconds) pays for itself over a tier, not for a file or a test named on the
# command line.
@pytest.hookimpl(wrapper=True)
def pytest_cmdline_main(config: pytest.Config):
    workers = default_workers(config)
    if workers is not None:
        config.option.numprocesses = workers
    return (yield)


def _selects_all(config: pytest.Config) -> bool:
    return (
        config.getoption("--all-tiers")
        or bool(config.getoption("markexpr"))
        or any("::" in arg for arg in config.args)
    )


def tier_of(markers) -> str:
    """A test's tier: the first of its tier markers (slurm, browser, mpi, process, slow)."""
    for tier in ("slurm", "browser", "mpi", "process", "slow"):
        if tier in markers:
            return tier
    return "unit"


def is_exclusive(item: pytest.Item) -> bool:
    """A test that gets the machine to itself under xdist (its marker says it starts ranks)."""
    return any(item.get_closest_marker(m) for m in EXCLUSIVE)


def run_order(items: list[pytest.Item]) -> list[pytest.Item]:
    """The order an xdist worker runs its tests in: the exclusive ones first, one after the
    other, then every module that holds a test of another tier, then the rest.

    Exclusive tests scattered through the run make the other worker stop at each, and the
    exclusive one wait for the other's test in flight (a slow one, often): together first,
    they run back to back on the worker that holds them (``SharedLock``, ``keep``) while
    the other waits once. The longer tests next and the unit tests last leave no long test
    starting alone at the end. Apart from the exclusive tests a module's tests stay
    together, in their order, so its module-scoped fixtures are set up once."""
    heavy = {
        item.path
        for item in items
        if not is_exclusive(item) and tier_of({m.name for m in item.iter_markers()}) != "unit"
    }
    return sorted(
        items, key=lambda item: 0 if is_exclusive(item) else 1 if item.path in heavy else 2
    )


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    for item in items:
        if any(item.get_closest_marker(m) for m in IMPLY_PROCESS):
            item.add_marker("process")
    if not _selects_all(config):
        kept, deselected = [], []
        for item in items:
            tiered = any(item.get_closest_marker(m) for m in TIERS)
            (deselected if tiered else kept).append(item)
        if deselected:
            config.hook.pytest_deselected(items=deselected)
            items[:] = kept
    if getattr(config, "workerinput", None) is not None:
        items[:] = run_order(items)  # every worker collects the same order, as xdist needs


class SharedLock:
    """A readers-writer lock between xdist workers on two files (flock): a turnstile that
    an exclusive request holds while it waits, so shared requests queue behind it.

    An exclusive hold may be kept for the worker's next test when that one is exclusive
    too: the other workers' tests then wait until the last of a run of exclusive tests,
    instead of one of theirs starting between each two (and the next exclusive test
    waiting for it to end)."""

    def __init__(self, folder: Path) -> None:
        self.turnstile = os.open(folder / "turnstile.lock", os.O_RDWR | os.O_CREAT)
        self.room = os.open(folder / "room.lock", os.O_RDWR | os.O_CREAT)
        self.kept = False  # the room is held exclusively, from the test before

    def _acquire(self, exclusive: bool) -> None:
        fcntl.flock(self.turnstile, fcntl.LOCK_EX)
        try:
            fcntl.flock(self.room, fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH)
        finally:
            fcntl.flock(self.turnstile, fcntl.LOCK_UN)

    @contextlib.contextmanager
    def hold(self, exclusive: bool, keep: bool = False):
        """The room, shared or exclusive, for one test; ``keep``: an exclusive hold stays
        after it, for the next test (which must then ask for it exclusively)."""
        if self.kept and not exclusive:
            self.release()
        if not self.kept:
            self._acquire(exclusive)
        self.kept = False
        try:
            yield
        finally:
            if exclusive and keep:
                self.kept = True
            else:
                self.release()

    def release(self) -> None:
        fcntl.flock(self.room, fcntl.LOCK_UN)
        self.kept = False


_LOCK: list[SharedLock] = []


def _worker_lock(config: pytest.Config) -> SharedLock | None:
    workerinput = getattr(config, "workerinput", None)
    if workerinput is None:
        return None  # one process runs the tests one at a time
    if not _LOCK:
        folder = Path(tempfile.gettempdir()) / f"campar-tiers-{workerinput['testrunuid']}"
        folder.mkdir(exist_ok=True)
        _LOCK.append(SharedLock(folder))
    return _LOCK[0]


# Outermost, so the wait for the lock is not counted in the test's timeout.
@pytest.hookimpl(hookwrapper=True, tryfirst=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem):
    lock = _worker_lock(item.config)
    exclusive = is_exclusive(item)
    keep = exclusive and nextitem is not None and is_exclusive(nextitem)
    with lock.hold(exclusive, keep) if lock else contextlib.nullcontext():
        WATCH.take()
        WATCH.active = True
        try:
            yield
        finally:
            WATCH.active = False
            WATCH.take()


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo):
    outcome = yield
    report = outcome.get_result()
    starts = WATCH.take()
    missing: dict[str, list[str]] = defaultdict(list)
    for words in starts:
        for marker in sorted(required_markers(words)):
            if not item.get_closest_marker(marker):
                missing[marker].append(" ".join(words)[:120])
    if not missing:
        return
    lines = [
        f"{item.nodeid} starts {commands[0]!r} ({len(commands)} such) in its {call.when}"
        f" without @pytest.mark.{marker} (tests/support/tiers.py)"
        for marker, commands in missing.items()
    ]
    message = "\n".join(lines)
    if report.failed:
        report.sections.append(("tier markers", message))
    else:
        report.outcome = "failed"
        report.longrepr = message


class TierTimes:
    """Each tier's test count and summed time (setup, call and teardown of each test, over
    every worker), for the terminal summary."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = defaultdict(float)
        self.tests: dict[str, set[str]] = defaultdict(set)
        self.start = time.monotonic()

    @pytest.hookimpl
    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        tier = tier_of(report.keywords)
        self.seconds[tier] += report.duration
        self.tests[tier].add(report.nodeid)

    @pytest.hookimpl
    def pytest_terminal_summary(self, terminalreporter) -> None:
        if not self.tests:
            return
        parts = [
            f"{tier} {len(self.tests[tier])} tests {self.seconds[tier]:.1f} s"
            for tier in ("unit", *TIERS)
            if tier in self.tests
        ]
        wall = time.monotonic() - self.start
        terminalreporter.write_sep("=", "time by tier (summed over workers)")
        terminalreporter.write_line(" | ".join(parts) + f" | wall {wall:.1f} s")


@pytest.hookimpl(trylast=True)
def pytest_sessionstart(session: pytest.Session) -> None:
    config = session.config
    if getattr(config, "workerinput", None) is None and config.pluginmanager.has_plugin(
        "terminalreporter"
    ):
        config.pluginmanager.register(TierTimes(), "campar-tier-times")


# A hang detector, not a speed check: what a test does in 120 s on free cores takes
# load / cores times as long when the cores are shared.
MAX_STRETCH = 10.0


def stretch() -> float:
    """How much longer than on free cores a test takes now: the 1-minute load average per
    core, between 1 and MAX_STRETCH."""
    return min(MAX_STRETCH, max(1.0, os.getloadavg()[0] / (os.cpu_count() or 1)))


@pytest.hookimpl(tryfirst=True)
def pytest_timeout_set_timer(item: pytest.Item, settings):
    timeout, factor = item.config.pluginmanager.get_plugin("timeout"), stretch()
    if timeout is None or factor == 1.0:
        return None  # pytest-timeout sets the timer as configured
    return timeout.pytest_timeout_set_timer(
        item, settings._replace(timeout=settings.timeout * factor)
    )
