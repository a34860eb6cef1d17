"""The bad-input matrix: input kind × command, every command run in this process.

Each cell is a bad input given to one command (``campar run``, ``point``, ``line``,
``continue``, ``curves``, ``plot``, ``status``, ``verify``, ``explore``) or Python entry
(``campar.simulate_point``, ``line``, ``Model.build``, ``cell``, ``open``). A command's cell
holds when it exits 2 (3 for a store made by another job: StoreMismatch), says the problem in
one line on stderr (argparse's usage block aside), prints no traceback and leaves the
directory as it was; an entry's cell when it raises a CamparError of one line, nothing else.
No cell computes: each is refused before work starts. The counts are printed on a line
starting ``BAD-INPUT`` (``-s``) and the number of cells is asserted, so the matrix cannot
silently shrink. Special files that could block or exhaust a reader (a FIFO, /dev/zero) are
given to a child process with a timeout in ``test_special_files_are_refused_by_every_reader``.

    pytest tests/test_bad_input_matrix.py -s | grep BAD-INPUT
"""

import os
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest
import yaml
from support.damage import synthetic_store
from test_store import JOB

import campar
from campar.cli import main
from campar.errors import CamparError, JobError, StoreError, StoreMismatch
from campar.sweep.job import Job

GRID = {
    "omega": {"from": 4.0, "to": 3.0, "points": 3},
    "mu_cn": {"from": 0.9, "to": 0.8, "points": 2},
}
HUGE = "1000000000"

# The kinds of bad value an option takes, and the option text each becomes.
VALUES = {"NaN": "nan", "+inf": "inf", "-inf": "-inf", "above range": "1e308", "type": "abc"}


def files(tmp: Path) -> dict[str, str]:
    """{kind: path} of files that are no job, no cam table and no store."""
    folder = tmp / "folder"
    folder.mkdir()
    big = tmp / "big.yaml"
    big.write_bytes(b"#" * (2 << 20))
    made = {"empty path": "", "directory": str(folder), "> 1 MiB": str(big)}
    for kind, text in [
        ("!!binary", "name: !!binary aGk=\n"),
        ("!!python/object", "name: !!python/object:os.system ls\n"),
        ("YAML parse error", "name: [x\n"),
        ("unknown key", "name: t\nbogus: 1\n"),
        ("wrong type", "name: t\nsweep: 3\n"),
    ]:
        path = tmp / (kind.strip("!").replace("/", "_").replace(" ", "_") + ".yaml")
        path.write_text(text)
        made[kind] = str(path)
    return made


def job_file(tmp: Path, name: str, **changes) -> str:
    data = {"name": name, "sweep": GRID, "store": str(tmp / f"{name}.zarr"), **changes}
    path = tmp / f"{name}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return str(path)


def command_cells(tmp: Path, store: str, foreign_job: str) -> list[tuple[str, str, list, int]]:
    """(command, kind, argv, exit code) of every command's cell."""
    bad_files = files(tmp)
    good = job_file(tmp, "good")
    cells = []

    def add(command, kind, argv, code=JobError.exit_code):
        cells.append((command, kind, [command, *argv], code))

    # run: the job file, --set and the options of a run
    for kind, path in bad_files.items():
        add("run", f"job: {kind}", [path])
        add("run", f"cam table: {kind}", [job_file(tmp, "cam", model={"cam": {"table": path}})])
    for kind, value in VALUES.items():
        add("run", f"--set {kind}", [good, "--set", f"sweep.omega.from={value}"])
    add("run", "--set below range", [good, "--set", "sweep.omega.from=-1"])
    add("run", "over-large points", [good, "--set", f"sweep.omega.points={HUGE}"])
    add("run", "--set unknown key", [good, "--set", "bogus=1"])
    add("run", "--set parse error", [good, "--set", "name=[unclosed"])
    add("run", "unknown flag", [good, "--bogus"])
    add("run", "--ranks without --dry-run", [good, "--ranks", "2"])
    add("run", "empty --store", [good, "--store", ""])
    add("run", "store of another job", [foreign_job], StoreMismatch.exit_code)

    # point, line, continue: the model's values, counts, --job and --set
    starts = {"point": ["--omega", "3"], "line": ["--omega", "3:4", "--points", "3"]}
    starts["continue"] = ["--omega", "3", "--second", "mu_cn:0.7:0.9"]
    for command, base in starts.items():
        for kind, value in VALUES.items():
            add(command, f"--f0 {kind}", [*base, "--f0", value])
        add(command, "--f0 below range", [*base, "--f0", "-1"])
        add(command, "--zeta above range", [*base, "--zeta", "1e9"])
        add(command, "unknown flag", [*base, "--bogus", "1"])
        add(command, "--set unknown key", [*base, "--set", "bogus=1"])
        add(command, "--set parse error", [*base, "--set", "name=[unclosed"])
        add(command, "--set NaN", [*base, "--set", "model.zeta=.nan"])
        for kind, path in bad_files.items():
            add(command, f"--job {kind}", [*base, "--job", path])
    for kind, value in VALUES.items():
        add("point", f"--omega {kind}", ["--omega", value])
        add("point", f"--y0 {kind}", ["--omega", "3", "--cycle", "1", "--y0", value])
    add("point", "--omega below range", ["--omega", "-3"])
    add("point", "over-large --cycle", ["--omega", "3", "--cycle", HUGE])
    add("point", "over-large --attractors", ["--omega", "3", "--attractors", HUGE])
    for kind, window in [("NaN", "nan:4"), ("inf", "3:inf"), ("empty", "4:4")]:
        add("line", f"range {kind}", ["--omega", window, "--points", "3"])
        add("continue", f"--second {kind}", ["--omega", "3", "--second", f"mu_cn:{window}"])
    add("line", "range above range", ["--omega", "3:1e308", "--points", "3"])
    add("line", "over-large --points", ["--omega", "3:4", "--points", HUGE])
    add("continue", "--second reversed", ["--omega", "3", "--second", "mu_cn:0.9:0.7"])
    add("continue", "--second unknown name", ["--omega", "3", "--second", "foo:1:2"])
    add("continue", "--second outside range", ["--omega", "3", "--second", "mu_kn:0.5:1e308"])
    add("continue", "--omega NaN", ["--omega", "nan", "--second", "mu_cn:0.7:0.9"])

    # the commands that read a store
    not_stores = {k: v for k, v in bad_files.items() if k in ("empty path", "directory", "> 1 MiB")}
    for command in ("curves", "plot", "status", "verify", "explore"):
        for kind, path in not_stores.items():  # a path that holds no store: a store problem
            add(command, f"store: {kind}", [path], StoreError.exit_code)
        add(command, "unknown flag", [store, "--bogus"])
    add("curves", "over-large --points", [store, "--points", HUGE])
    add("curves", "--types unknown", [store, "--types", "bogus"])
    add("curves", "empty --store", [store, "--store", ""])
    # (a reversed A:B of plot and line is the same interval: their pages say either order)
    for kind, window in [("NaN", "nan:4"), ("inf", "3:inf"), ("empty", "4:4")]:
        add("plot", f"--omega {kind}", [store, "--omega", window])
    add("plot", "--what unknown", [store, "--what", "bogus"])
    for kind, value in VALUES.items():
        add("explore", f"--cell-seconds {kind}", [store, "--cell-seconds", value])
    add("explore", "--port above range", [store, "--port", "70000"])
    add("explore", "over-large --zoom-ranks", [store, "--zoom-ranks", HUGE])
    return cells


def entry_cells(tmp: Path, store: str) -> list[tuple[str, str, object]]:
    """(entry, kind, call) of the Python entries' cells."""
    (tmp / "entries").mkdir()
    bad_files = files(tmp / "entries")
    cells = []
    for kind, value in VALUES.items():
        number = value if kind == "type" else float(value)
        cells.append(("simulate_point", kind, lambda v=number: campar.simulate_point(omega=v)))
        cells.append(("Model.build", kind, lambda v=number: campar.Model.build(f0=v)))
        cells.append(("line", kind, lambda v=number: campar.line((3.0, v), points=3)))
        cells.append(("cell", kind, lambda v=number: campar.cell(store, omega=v, zeta=0.2)))
    cells += [
        ("simulate_point", "unknown key", lambda: campar.simulate_point(omega=3, bogus=1)),
        ("simulate_point", "below range", lambda: campar.simulate_point(omega=-3)),
        ("Model.build", "unknown key", lambda: campar.Model.build(bogus=1)),
        ("Model.build", "below range", lambda: campar.Model.build(zeta=-1)),
        ("line", "empty range", lambda: campar.line((4.0, 4.0), points=3)),
        ("line", "over-large points", lambda: campar.line((3.0, 4.0), points=int(HUGE))),
        ("cell", "unknown coordinate", lambda: campar.cell(store, omega=3, bogus=1)),
    ]
    for kind, path in bad_files.items():
        if kind in ("empty path", "directory", "> 1 MiB"):
            cells.append(("open", kind, lambda p=path: campar.open(p)))
            cells.append(("cell", f"store: {kind}", lambda p=path: campar.cell(p, omega=3)))
    return cells


def snapshot(folder: Path) -> dict[str, tuple]:
    return {
        str(p): (p.is_dir(), p.stat().st_size, p.stat().st_mtime_ns)
        for p in sorted(folder.rglob("*"))
    }


def one_line(said: str) -> list[str]:
    """The lines of ``said`` that are not argparse's usage block (usage: and its indented
    continuation lines)."""
    lines = [line for line in said.splitlines() if line.strip()]
    return [line for line in lines if not line.startswith(("usage:", " "))]


@pytest.fixture
def stores(tmp_path):
    """(a store, a job file of another job naming that store)."""
    store = tmp_path / "store.zarr"
    synthetic_store(store, Job.from_dict(JOB))
    foreign = job_file(tmp_path, "foreign", store=str(store))
    return str(store), foreign


def test_every_bad_input_is_refused_in_one_line_by_every_command(
    tmp_path, stores, monkeypatch, capsys
):
    from campar.explore import server

    def never(*args, **kwargs):
        raise AssertionError("explore started a server on bad input")

    monkeypatch.setattr(server, "ExploreServer", never)
    monkeypatch.chdir(tmp_path)
    cells = command_cells(tmp_path, *stores)
    failed, counts = [], Counter()
    for command, kind, argv, code in cells:
        before = snapshot(tmp_path)
        capsys.readouterr()
        try:
            got = main(argv)
        except SystemExit as exc:
            got = exc.code
        except Exception as exc:  # a traceback: the cell fails, the matrix goes on
            got = f"{type(exc).__name__}: {exc}"
        printed, said = capsys.readouterr()
        lines = one_line(said)
        problems = []
        if got != code:
            problems.append(f"exit {got!r}, not {code}")
        if len(lines) != 1 or "Traceback" in said:
            problems.append(f"stderr {lines!r}")
        if snapshot(tmp_path) != before:
            problems.append("the directory changed")
        counts[command] += 1
        if problems:
            failed.append(f"{command} [{kind}] {argv[1:]}: {'; '.join(problems)}")
    with capsys.disabled():
        table = ", ".join(f"{c} {n}" for c, n in counts.items())
        print(f"\nBAD-INPUT commands: {len(cells)} cells ({table}), {len(failed)} failed")
        for line in failed:
            print("  " + line)
    assert not failed, "\n".join(failed)
    assert len(cells) == 145


def test_every_bad_input_is_refused_by_every_python_entry(tmp_path, stores, capsys):
    cells = entry_cells(tmp_path, stores[0])
    before = snapshot(tmp_path)
    failed, counts = [], Counter()
    for entry, kind, call in cells:
        counts[entry] += 1
        try:
            call()
        except CamparError as exc:
            if len(str(exc).strip().splitlines()) != 1:
                failed.append(f"{entry} [{kind}]: {str(exc)!r} is not one line")
            continue
        except Exception as exc:
            failed.append(f"{entry} [{kind}]: {type(exc).__name__}: {exc}")
            continue
        failed.append(f"{entry} [{kind}]: accepted")
    assert snapshot(tmp_path) == before
    with capsys.disabled():
        table = ", ".join(f"{c} {n}" for c, n in counts.items())
        print(f"\nBAD-INPUT entries: {len(cells)} cells ({table}), {len(failed)} failed")
        for line in failed:
            print("  " + line)
    assert not failed, "\n".join(failed)
    assert len(cells) == 33


# -- special files that could block or exhaust a reader: in a child, with a timeout ------


@pytest.mark.process
def test_special_files_are_refused_by_every_reader(tmp_path, stores, capsys):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    good = job_file(tmp_path, "good")
    cells = []
    for kind, path in [("FIFO", str(fifo)), ("/dev/zero", "/dev/zero")]:
        cam = job_file(tmp_path, f"cam_{len(cells)}", model={"cam": {"table": path}})
        cells += [
            (f"run job {kind}", ["run", path]),
            (f"run cam table {kind}", ["run", cam]),
            (f"run --set table {kind}", ["run", good, "--set", f"model.cam.table={path}"]),
            (f"point --job {kind}", ["point", "--omega", "3", "--job", path]),
            (f"line --job {kind}", ["line", "--omega", "3:4", "--points", "3", "--job", path]),
            (f"status {kind}", ["status", path]),
            (f"verify {kind}", ["verify", path]),
            (f"plot {kind}", ["plot", path]),
            (f"curves {kind}", ["curves", path]),
        ]
    # all in one child (one start-up), each cell with its own alarm as the timeout
    script = "\n".join(
        [
            "import io, json, signal, sys, contextlib",
            "from campar.cli import main",
            "out = []",
            "for argv in json.loads(sys.argv[1]):",
            "    err = io.StringIO()",
            "    signal.alarm(20)",
            "    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):",
            "        try: code = main(argv)",
            "        except SystemExit as e: code = e.code",
            "        except Exception as e: code = repr(e)",
            "    signal.alarm(0)",
            "    out.append([code, err.getvalue()])",
            "print(json.dumps(out))",
        ]
    )
    import json

    before = snapshot(tmp_path)
    done = subprocess.run(
        [sys.executable, "-c", script, json.dumps([argv for _, argv in cells])],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    results = json.loads(done.stdout.strip().splitlines()[-1])
    failed = []
    for (kind, _), (code, said) in zip(cells, results, strict=True):
        lines = one_line(said)
        if code != JobError.exit_code and code != 3 or len(lines) != 1 or "Traceback" in said:
            failed.append(f"{kind}: exit {code!r}, stderr {lines!r}")
    assert snapshot(tmp_path) == before
    with capsys.disabled():
        print(f"\nBAD-INPUT special files: {len(cells)} cells, {len(failed)} failed")
        for line in failed:
            print("  " + line)
    assert not failed, "\n".join(failed)
    assert len(cells) == 18
