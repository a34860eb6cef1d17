"""Fault injection: writers killed at random moments, stores damaged at random places, disks
that fill up, signals at any moment of a run — every resume must end bitwise identical to
an uninterrupted run, every damage must be detected, nothing may crash.

Two tiers. The quick one (every CI run) kills writers of synthetic tiles and damages small
stores a few times per backend. The long one (``-m slow``) kills and signals real ``campar
run`` and ``mpirun -n 2 campar run`` processes in turn, damages stores dozens of times per
backend and fills small disks (tests/test_fault_campaign.py damages any file and checks every
reader); its counts are printed in lines starting ``FAULTS`` (run with ``-s``):

    pytest tests/test_faults.py -m slow -s | grep FAULTS

``CAMPAR_FAULT_ROUNDS`` scales the long tier (default 1; 4 gives ~4× as many faults).
"""

import os
import signal
import subprocess
import sys
import time
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest
import yaml
from support.damage import (
    DAMAGE,
    assert_synthetic,
    damage_file,
    finish,
    leftovers,
    small_disk,
    synthetic_store,
    zarr_chunks,
)
from support.jobs import SLOW, SMALL_JOB, assert_same_map, merge, reference_arrays
from support.processes import MPIRUN, kill_tree, subprocess_env, tree_env, wait_until_guarded
from test_store import make_job

from campar.cli import main
from campar.errors import StoreDamaged
from campar.sweep.plan import plan_tiles
from campar.sweep.store import _h5guard, read_store, verify_store
from campar.sweep.store import _hdf5 as h5

ROUNDS = int(os.environ.get("CAMPAR_FAULT_ROUNDS", "1"))
BACKENDS = [".zarr", ".h5"]
BAD_WORDS = ("Traceback", "Segmentation", "BAD TERMINATION", "Exception ignored", "HDF5-DIAG")


@pytest.fixture(autouse=True)
def short_watchdog(monkeypatch):
    """A rescue of a damaged HDF5 file that hangs is given up after 3 s, not 20."""
    monkeypatch.setattr(_h5guard, "WATCHDOG_SECONDS", 3.0)
    monkeypatch.setenv("CAMPAR_RESCUE_WATCHDOG", "3")


def report(**counts) -> None:
    print("FAULTS " + " ".join(f"{k}={v}" for k, v in counts.items()), flush=True)


# -- writers of synthetic tiles killed at random moments (quick) ---------------------------

WRITER = """
import os, signal, sys, threading, time
import campar.sweep.store._hdf5 as h5
h5.CHECKPOINT_TILES = 1  # every tile goes through a checkpoint: kills land inside them too
from support.damage import finish
from test_store import make_job
job = make_job(**{JOB!r})

def kill_after_creation(path, delay):
    # A store appears whole (it is built aside and renamed): from then on tiles are written
    while not os.path.exists(path):
        time.sleep(0.001)
    time.sleep(delay)
    os.kill(os.getpid(), signal.SIGKILL)

threading.Thread(target=kill_after_creation, args=(sys.argv[1], float(sys.argv[2]))).start()
finish(sys.argv[1], job)
time.sleep(60)  # finished before the kill: wait for it
"""
JOB = {"sweep__zeta__points": 24, "tiles__rows": 1, "sweep__omega__points": 40}


def kill_writers(path: Path, kills: int, seed: int, span: float = 0.4) -> int:
    """Start writers of ``path`` and SIGKILL each at a random moment within ``span`` seconds
    of the store's creation (the moment is timed from an event the child sees, not from its
    start, so a loaded machine's slow imports do not move it before the store exists)."""
    script = WRITER.replace("{JOB!r}", repr(JOB))
    rng = np.random.default_rng(seed)
    for _ in range(kills):
        done = subprocess.run(
            [sys.executable, "-c", script, str(path), str(rng.uniform(0.0, span))],
            env=tree_env(),
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert done.returncode == -signal.SIGKILL, done.stderr
    return kills


@pytest.mark.parametrize("suffix", BACKENDS)
@pytest.mark.process
def test_writers_killed_at_random_moments_lose_no_committed_tile(tmp_path, suffix):
    path = tmp_path / f"k{suffix}"
    kill_writers(path, 1, seed=len(suffix))
    job = make_job(**JOB)
    with read_store(path) as reader:
        assert verify_store(reader).clean  # whatever a kill left is whole, or pending
    finish(path, job)
    assert_synthetic(path, job)
    assert leftovers(tmp_path) == []


# -- stores damaged at random places (quick: a few per backend; slow: many) ---------------


# What a Zarr round damages, in turn: each kind of damage on each class of a tile's files (a
# cell array's chunk, its checksum, its done flag); which tile and which array are drawn at
# random. (An HDF5 store is one file: the place in it is drawn at random.)
ZARR_TURNS = [(how, files) for how in DAMAGE for files in ("cells", "checksum", "done")]


def damage_at_random(path: Path, job, rng: np.random.Generator, turn: int):
    """Damage one random committed tile's chunk (Zarr: as ``ZARR_TURNS[turn]`` says), or the
    file or a journal entry at a random place (HDF5). Returns (what was done or None if
    nothing changed, the tile hit)."""
    if path.suffix == ".zarr":
        how, where = ZARR_TURNS[turn % len(ZARR_TURNS)]
        index = int(rng.integers(len(plan_tiles(job))))
        *cells, checksum, done = zarr_chunks(path, job, index)
        files = {"cells": cells, "checksum": [checksum], "done": [done]}[where]
        return damage_file(files[int(rng.integers(len(files)))], how, rng), index
    how = str(rng.choice(DAMAGE))
    entries = list(h5.journal_entries(path).values())
    target = entries[int(rng.integers(len(entries)))] if entries and rng.random() < 0.3 else path
    if target == path and how == "delete":
        how = "truncate"  # a store file deleted is no store: nothing to detect
    return damage_file(target, how, rng), None


def damage_and_repair(path: Path, rounds: int, seed: int) -> dict:
    """Damage a finished store ``rounds`` times; each time verify must see it and a resume
    must restore every tile. Counts of what happened."""
    job = make_job()
    rng = np.random.default_rng(seed)
    counts = {"damaged": 0, "detected": 0, "repaired": 0, "refused": 0}
    # Zarr: every turn once in as many rounds, from a random one
    start = int(rng.integers(len(ZARR_TURNS))) if path.suffix == ".zarr" else 0
    for turn in range(start, start + rounds):
        if path.exists():
            finish(path, job)
        else:
            synthetic_store(path, job)
        what, tile = damage_at_random(path, job, rng, turn)
        if what is None:
            continue  # zeros written over zeros: no damage
        counts["damaged"] += 1
        try:
            with read_store(path) as reader:
                report = verify_store(reader)
            seen = not report.clean or not report.verified.all()
        except StoreDamaged:
            seen = True  # the store as a whole is named damaged
        assert seen, f"{what} went unnoticed"
        counts["detected"] += 1
        try:
            finish(path, job)
        except StoreDamaged as exc:  # e.g. an HDF5 superblock gone: refused, never deleted
            assert path.exists(), exc
            counts["refused"] += 1
            path.unlink()
            continue
        assert_synthetic(path, job)
        counts["repaired"] += 1
    return counts


# a damaged HDF5 file is read through campar's guard, a child process (_h5guard)
@pytest.mark.parametrize("suffix", [".zarr", pytest.param(".h5", marks=pytest.mark.process)])
def test_random_damage_is_detected_and_repaired(tmp_path, suffix):
    rounds = 4 if suffix == ".zarr" else 2  # an HDF5 rescue starts child processes
    counts = damage_and_repair(tmp_path / f"d{suffix}", rounds, seed=7 + len(suffix))
    assert counts["detected"] == counts["damaged"] == rounds
    report(kind="damage", backend=suffix, **counts)


@pytest.mark.slow
@pytest.mark.process  # HDF5: a damaged sealed file is rescued in the guard's child process
@pytest.mark.parametrize("suffix", BACKENDS)
def test_many_random_damages_are_detected_and_repaired(tmp_path, suffix):
    # Zarr: every kind of damage on every class of a tile's files once; HDF5: an HDF5 round
    # starts rescue processes (~1 s each): this count keeps the suite within its minutes.
    # CAMPAR_FAULT_ROUNDS scales both (benchmarks/RESULTS.md: the long runs)
    rounds = (len(ZARR_TURNS) if suffix == ".zarr" else 15) * ROUNDS
    counts = damage_and_repair(tmp_path / f"d{suffix}", rounds, seed=11 + len(suffix))
    assert counts["detected"] == counts["damaged"]
    assert counts["repaired"] >= 0.9 * counts["damaged"]  # HDF5 metadata damage may be refused
    report(kind="damage", backend=suffix, **counts)


# -- real runs killed and signalled at random moments (slow) -------------------------------

RUNNER = """
import sys
from campar.sweep.signals import guard_start
guard_start()  # as the campar program does in its first line
from campar.errors import CamparError
try:  # every tile through a checkpoint: kills land inside checkpoints too
    import campar.sweep.store._hdf5 as h5
    h5.CHECKPOINT_TILES = 1
    from campar.cli import main
except CamparError as exc:  # a signal during these imports: as main would report it
    sys.exit(print(f"campar run: {exc}", file=sys.stderr) or exc.exit_code)
code = main(sys.argv[1:])  # from Python: the caller's handlers are restored, then
from campar.sweep.signals import finished
finished()  # as the campar program does once its work is over
sys.exit(code)
"""


def start_run(job_file: Path, mpi: bool) -> subprocess.Popen:
    command = [sys.executable, "-c", RUNNER, "run", str(job_file)]
    if mpi:
        command = [str(MPIRUN), "-n", "2", *command]
    return subprocess.Popen(
        command,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=subprocess_env(),
        start_new_session=True,
    )


def timed_run(job_file: Path, mpi: bool) -> tuple[float, float]:
    """(seconds until campar's handlers are in place, seconds of the whole run) of one
    uninterrupted run, measured here: the windows of the interruptions scale with this
    machine's speed, whatever its load."""
    start = time.monotonic()
    proc = start_run(job_file, mpi)
    guarded_after = wait_until_guarded(proc, ranks=2 if mpi else 1)
    _, err = proc.communicate(timeout=600)
    assert proc.returncode == 0, err[-2000:]
    return guarded_after, time.monotonic() - start


@pytest.fixture(scope="session")
def run_timing(tmp_path_factory):
    """``run_timing(mpi)``: ``timed_run`` of the campaigns' job in one process or under
    ``mpirun -n 2``, measured once a session (each campaign's windows scale with it)."""
    measured = {}

    def timing(mpi: bool) -> dict:
        if mpi not in measured:
            folder = tmp_path_factory.mktemp("timed")
            data = merge(merge(SMALL_JOB, SLOW), {"name": "c", "store": str(folder / "t.zarr")})
            job_file = folder / "timed.yaml"
            job_file.write_text(yaml.safe_dump(data, sort_keys=False))
            guarded_after, whole = timed_run(job_file, mpi)
            measured[mpi] = {"guarded_after": guarded_after, "whole": whole}
        return measured[mpi]

    return timing


# How a run is interrupted: SIGKILL to every process, or SIGTERM/SIGINT/SIGUSR1 to the group
HOWS = ("kill", "signal")


def interrupt_at(proc: subprocess.Popen, how: str, moment: float, rng) -> tuple[str, str]:
    """Kill or signal a run ``moment`` seconds from now, unless it ends before; its output."""
    try:
        proc.wait(timeout=moment)  # a run that ends before its moment is not waited for
    except subprocess.TimeoutExpired:
        if how == "kill":
            kill_tree(proc.pid)
        else:
            sig = [signal.SIGTERM, signal.SIGINT, signal.SIGUSR1][int(rng.integers(3))]
            os.killpg(proc.pid, sig)
    return proc.communicate(timeout=300)


def interrupt_until_complete(
    job_file, job, mpi: bool, rng, first: int, timing: dict, most: int = 60
) -> Counter:
    """Run the job again and again, the runs killed and signalled in turn (the first as
    ``HOWS[first]``), each at a random moment, until one completes (after ``most`` runs
    interrupted, the next is left to complete). ``timing``: ``timed_run``'s measure of this
    job here; every moment is drawn within 1.2 times it, so each run has its chance to commit
    tiles on a slow machine as on a fast one (a first run that completes is a timed run: its
    time replaces the measure). Counts runs and interruptions of each kind."""
    counts = Counter()
    for attempt in range(60):
        how = HOWS[(first + attempt) % 2]
        start = time.monotonic()
        proc = start_run(job_file, mpi)
        if attempt == most:  # the last: left to complete
            out, err = proc.communicate(timeout=300)
        elif how == "kill":  # from the first instant
            out, err = interrupt_at(proc, how, rng.uniform(0.0, 1.2 * timing["whole"]), rng)
        else:  # from campar's first handler on: before it, Python's own start-up
            wait_until_guarded(proc, ranks=2 if mpi else 1)
            moment = rng.uniform(0.0, 1.2 * (timing["whole"] - timing["guarded_after"]))
            out, err = interrupt_at(proc, how, moment, rng)
        counts["runs"] += 1
        bad = [w for w in BAD_WORDS if w in out + err]  # mpirun reports on stdout
        assert not bad, (out + err)[-3000:]
        if proc.returncode == 0:
            if attempt == 0:
                timing["whole"] = time.monotonic() - start
            break
        counts[how] += 1
        allowed = (-signal.SIGKILL, 137, 1) if how == "kill" else (75, 130, 143)
        if how == "kill" and mpi:  # hydra's mpiexec exits 255 when its proxy is killed first
            allowed += (255,)
        assert proc.returncode in allowed, (how, proc.returncode, err[-2000:])
    else:
        pytest.fail("60 runs did not complete the map")
    return counts


# Serial: both backends. Under mpirun (the machine to itself) Zarr alone: its workers write
# their own tiles and the master commits them, the one writer path mpirun adds; into HDF5
# the master writes every tile with the serial run's writer (interrupted by the serial HDF5
# campaign), and the stop (tiles taken back, those in flight collected, exit 75) is the
# same for both backends. There a campaign interrupts two runs, one of each kind, and lets
# the third complete; a serial one interrupts four.
CAMPAIGNS = [
    pytest.param(".zarr", False, id="zarr-serial"),
    pytest.param(".h5", False, id="h5-serial"),
    pytest.param(".zarr", True, id="zarr-mpi", marks=pytest.mark.mpi),
]


@pytest.mark.slow
@pytest.mark.parametrize(("suffix", "mpi"), CAMPAIGNS)
@pytest.mark.process
@pytest.mark.timeout(1200)  # runs again and again until one completes (up to 60)
def test_runs_interrupted_at_random_moments_resume_bitwise_identical(
    write_job, tmp_path, run_timing, suffix, mpi
):
    if mpi and not MPIRUN.exists():
        pytest.skip(f"no mpirun at {MPIRUN}")
    rng = np.random.default_rng([len(suffix), mpi])
    timing = run_timing(mpi)
    # the serial reference, on a thread (the kernel releases the GIL) while the runs start
    # and wait: it takes no time of its own
    reference = ThreadPoolExecutor(1).submit(reference_arrays, write_job(name="c", slow=True)[1])
    total = Counter()
    # ROUNDS campaigns at least, and more until runs were both killed and signalled
    for campaign in range(4 * ROUNDS):
        if campaign >= ROUNDS and all(total[how] for how in HOWS):
            break
        store = tmp_path / f"c{campaign}{suffix}"
        job_file, job = write_job(name="c", slow=True, store=str(store))
        missing = [i for i, how in enumerate(HOWS) if not total[how]]
        first = missing[0] if len(missing) == 1 else campaign % 2  # the kind not yet seen
        most = 2 if mpi else 4
        total += interrupt_until_complete(job_file, job, mpi, rng, first, timing, most)
        total["campaigns"] += 1
        reference.result()
        with read_store(job.store) as reader:  # equal to the uninterrupted map, bit for bit
            assert_same_map(reader, job)
            assert verify_store(reader).clean
    assert all(total[how] for how in HOWS), f"{total}: runs neither killed nor signalled"
    report(backend=suffix, mpi=mpi, identical=total["campaigns"], **total)


# -- full disks (slow; root only) ------------------------------------------------------------

# tmpfs sizes (kB) where a run meets the full disk at different moments: creating the store,
# committing a tile or checkpointing, its resume opening the store still full
DISK_SIZES = (48, 160, 320, 96, 240)


def run_on_full_disk(job_file: Path, mpi: bool, capfd) -> tuple[int, str]:
    """(exit code, stderr) of ``campar run JOB``: under ``mpirun -n 2``, or in this process
    (a full disk is met by the writer and reported by the command: no process boundary)."""
    if mpi:
        proc = start_run(job_file, mpi=True)
        _, err = proc.communicate(timeout=300)
        return proc.returncode, err
    capfd.readouterr()
    code = main(["run", str(job_file)])
    return code, capfd.readouterr().err


@pytest.mark.slow
@pytest.mark.parametrize(
    ("suffix", "mpi"),
    # under mpirun a Zarr store's worker writes its own tiles: its full disk ends the run too
    # (one size: its run fails mid-way, then its resume at the opening, both under mpirun)
    [*((suffix, False) for suffix in BACKENDS), pytest.param(".zarr", True, marks=pytest.mark.mpi)],
)
@pytest.mark.process  # mount, and mpirun
def test_runs_on_a_full_disk_fail_in_one_line_and_resume_identical(
    write_job, tmp_path, monkeypatch, capfd, suffix, mpi
):
    monkeypatch.setattr(h5, "CHECKPOINT_TILES", 1)  # as RUNNER: every tile checkpointed
    disk = tmp_path / "disk"
    counts = {"full": 0, "identical": 0}
    sizes = DISK_SIZES[2 : 2 + ROUNDS] if mpi else DISK_SIZES[: 3 * ROUNDS]
    for size in sizes:
        with small_disk(disk, size) as resize:
            job_file, job = write_job(name=f"f{size}", store=str(disk / f"f{size}{suffix}"))
            for _ in range(2):  # the first run, then a resume on the still-full disk
                code, err = run_on_full_disk(job_file, mpi, capfd)
                assert not [w for w in BAD_WORDS if w in err], err[-3000:]
                if code == 0:
                    break
                assert code == 74, err[-2000:]
                assert "No space left on device" in err.splitlines()[-1]
                assert leftovers(disk) == [], leftovers(disk)
                counts["full"] += 1
            resize(16384)
            assert main(["run", str(job_file)]) == 0  # in this process: the resume
            with read_store(job.store) as reader:
                assert_same_map(reader, job)
            counts["identical"] += 1
    assert counts["full"] > 0, "no run met the full disk: the sizes no longer test anything"
    if mpi:
        assert counts["full"] == 2 * len(sizes), "under mpirun, a run and its resume are full"
    report(kind="full-disk", backend=suffix + (" mpirun -n 2" if mpi else ""), **counts)
