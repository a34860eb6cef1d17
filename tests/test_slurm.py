"""SLURM support, tested against a real single-node SLURM on this machine.

slurm/local-cluster.sh installs (if needed) and starts munged, slurmctld and
slurmd; the smoke job then goes through slurm/campar.sbatch on 2 MPI ranks
(`srun --mpi=pmi2`), is interrupted once the way a time limit does it
(`scancel --signal=USR1 --batch`: the batch shell forwards USR1, campar exits
75, the script requeues the job) and once the way an admin or preemption does
it (`scontrol requeue`: SIGTERM, exit 75, SLURM requeues), and must end with
a store bitwise equal to a serial `campar run` of the same job.

Skipped only where the cluster cannot run at all (not Linux, not root, no
SLURM and no apt-get to install it); under CI=true that is a failure.
"""

import contextlib
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from support.cli import call_campar

# Installs and starts SLURM (apt-get, as root) and runs the smoke job through it: ~30 s,
# and the install alone may take minutes.
pytestmark = [pytest.mark.slurm, pytest.mark.slow, pytest.mark.timeout(1200)]

REPO = Path(__file__).resolve().parents[1]
CLUSTER = REPO / "slurm" / "local-cluster.sh"
SBATCH = REPO / "slurm" / "campar.sbatch"
DAEMON_LOGS = [Path("/var/log/slurm/slurmctld.log"), Path("/var/log/slurm/slurmd.log")]

POLL = 0.1  # seconds between scontrol/store polls: a signal lands within a tile or two
# Applied to jobs/smoke.yaml for the interrupted run (and its serial reference).
JOB_OVERRIDES = {"transient": {"mode": "fixed", "max_revolutions": 150}, "tiles": {"rows": 1}}
# Job states in which the job is not finished (it may still run, or run again).
UNFINISHED = {
    "PENDING",
    "CONFIGURING",
    "RUNNING",
    "COMPLETING",
    "REQUEUED",
    "REQUEUE_FED",
    "RESIZING",
    "SUSPENDED",
    "STOPPED",
}


# -- helpers -----------------------------------------------------------------


def _why_no_cluster():
    """Why a local SLURM cluster cannot run on this machine, or None."""
    if not sys.platform.startswith("linux"):
        return f"not Linux ({sys.platform})"
    if os.geteuid() != 0:
        return "not root: local-cluster.sh installs packages and starts daemons"
    if shutil.which("slurmctld") is None and shutil.which("apt-get") is None:
        return "SLURM is not installed and there is no apt-get to install it"
    return None


def _venv():
    """The virtualenv that holds `campar` (the one running the tests, else ./.venv)."""
    for prefix in (Path(sys.prefix), REPO / ".venv"):
        if (prefix / "bin" / "campar").exists():
            return prefix
    pytest.fail(f"no bin/campar in {sys.prefix} nor in {REPO / '.venv'}")


def _run(cmd, timeout=60, **kw):
    return subprocess.run(
        [str(c) for c in cmd], capture_output=True, text=True, timeout=timeout, **kw
    )


def _tail(path, n=60):
    try:
        lines = Path(path).read_text(errors="replace").splitlines()
    except OSError as exc:
        return f"({exc})"
    return "\n".join(lines[-n:])


def _dump_diagnostics(*files):
    """Print what helps most when a SLURM test fails: the job's output, the daemon logs."""
    for f in files:
        print(f"\n----- {f} -----\n{_tail(f, 200)}", file=sys.stderr)
    for cmd in (["sinfo", "-N", "-l"], ["squeue", "-l"], ["scontrol", "show", "jobs"]):
        with contextlib.suppress(Exception):
            r = _run(cmd, timeout=10)
            print(f"\n----- {' '.join(cmd)} -----\n{r.stdout}{r.stderr}", file=sys.stderr)
    for log in DAEMON_LOGS:
        print(f"\n----- last lines of {log} -----\n{_tail(log)}", file=sys.stderr)


def job_info(jobid):
    """`scontrol show job` as a dict ({} once SLURM has forgotten the job)."""
    r = _run(["scontrol", "show", "job", "-o", jobid], timeout=20)
    if r.returncode != 0:
        return {}
    return dict(re.findall(r"(\w+)=(\S*)", r.stdout))


def wait_for(what, predicate, timeout):
    """Poll predicate() until it returns something truthy; fail after timeout seconds."""
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        time.sleep(POLL)


def tiles_done(store):
    """(tiles done, tiles in all) from the store's commit flags, or None if not readable yet."""
    from campar.sweep.store import read_store

    try:
        with read_store(store) as s:
            done = np.asarray(s.done)
    except Exception:  # not created yet: try again
        return None
    return int(np.count_nonzero(done)), int(done.size)


def read_all(store):
    from campar.sweep.store import read_store

    with read_store(store) as s:
        return {name: np.asarray(s.read(name)) for name in s.names}


def assert_stores_equal(got_path, want_path):
    got, want = read_all(got_path), read_all(want_path)
    assert sorted(got) == sorted(want)
    for name in want:
        a, b = got[name], want[name]
        assert a.dtype == b.dtype and a.shape == b.shape, name
        if a.dtype.kind in "biufcmMSV":  # bitwise, NaNs included
            assert a.tobytes() == b.tobytes(), f"{name} differs from the serial run"
        else:
            np.testing.assert_array_equal(a, b, err_msg=name)


# -- the cluster ---------------------------------------------------------------


@pytest.fixture(scope="module")
def slurm_cluster():
    why = _why_no_cluster()
    if why:
        msg = f"no local SLURM cluster: {why}"
        print(msg, file=sys.stderr)
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(f"{msg} (CI must run the slurm tests)")
        pytest.skip(msg)
    was_up = _run(["bash", CLUSTER, "status"]).returncode == 0
    r = _run(["bash", CLUSTER, "start"], timeout=900)
    if r.returncode != 0:
        _dump_diagnostics()
        pytest.fail(f"slurm/local-cluster.sh failed ({r.returncode}):\n{r.stdout}{r.stderr}")
    yield
    if not was_up:  # leave the machine as we found it
        _run(["bash", CLUSTER, "stop"], timeout=120)


DAEMON_PIDS = [Path("/run/munge/munged.pid"), Path("/run/slurmctld.pid"), Path("/run/slurmd.pid")]


def daemons() -> list[str]:
    """The three daemons' process ids, from their pid files."""
    return [path.read_text().strip() if path.exists() else "" for path in DAEMON_PIDS]


def test_local_cluster_is_idempotent(slurm_cluster):
    before = daemons()
    r = _run(["bash", CLUSTER, "start"], timeout=120)
    assert r.returncode == 0, r.stderr
    # nothing changed, so nothing restarted: the same three processes, whatever the time
    assert "restarting" not in r.stderr
    assert all(before) and daemons() == before, (before, daemons())
    node = _run(["hostname", "-s"]).stdout.strip()
    assert _run(["sinfo", "-h", "-n", node, "-o", "%T"]).stdout.split()[0] in {"idle", "mixed"}


def test_srun_pmi2_gives_one_mpi_world(slurm_cluster):
    code = "from mpi4py import MPI; c = MPI.COMM_WORLD; print(c.Get_rank(), c.Get_size())"
    r = _run(
        ["srun", "--mpi=pmi2", "-n", "2", "--time=2", _venv() / "bin" / "python", "-c", code],
        timeout=120,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    assert sorted(r.stdout.split("\n")[:2]) == ["0 2", "1 2"], r.stdout


def test_smoke_job_interrupted_twice_resumes_bitwise(
    slurm_cluster, warm_numba_cache, tmp_path, capsys
):
    venv = _venv()
    campar = venv / "bin" / "campar"
    job = yaml.safe_load((REPO / "jobs" / "smoke.yaml").read_text())
    # The smoke grid, made long enough to be interrupted twice: a fixed transient
    # gives every cell the same cost (a few seconds for one process), one chain per
    # tile gives 24 tiles, so progress is seen tile by tile.
    job.update(JOB_OVERRIDES)

    def job_copy(name):
        path = tmp_path / f"{name}.yaml"
        path.write_text(
            yaml.safe_dump({**job, "store": str(tmp_path / f"{name}.zarr")}, sort_keys=False)
        )
        return path, tmp_path / f"{name}.zarr"

    serial_job, serial_store = job_copy("serial")
    slurm_job, slurm_store = job_copy("slurm")
    out = tmp_path / "slurm-job.out"
    jobid = None
    t_start = time.monotonic()
    # Every campar here, SLURM's ranks too (sbatch passes the environment on), imports the
    # tree under test, whichever checkout the venv's campar was installed from
    tree = os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH", "")]))
    env = dict(os.environ, PYTHONPATH=tree, CAMPAR_VENV=str(venv))
    serial = None
    try:
        r = _run(
            [
                "sbatch",
                "--parsable",
                "--ntasks=2",
                "--job-name=campar-test",
                f"--output={out}",
                SBATCH,
                slurm_job,
            ],
            cwd=tmp_path,
            env=env,
        )
        assert r.returncode == 0, r.stderr
        jobid = r.stdout.strip().split(";")[0]

        def running_with_progress(restarts, more_than):
            info = job_info(jobid)
            state = info.get("JobState")
            if state not in UNFINISHED:
                raise AssertionError(f"job ended ({state}) before it could be interrupted")
            if state != "RUNNING" or info.get("Restarts") != str(restarts):
                return None
            p = tiles_done(slurm_store)
            return p if p and more_than < p[0] < p[1] else None

        def requeued(restarts):
            # PENDING again: the attempt before has exited, and a requeued job waits
            # cred_expire (5 s) before it may start, so the store is still meanwhile.
            info = job_info(jobid)
            ok = info.get("Restarts") == str(restarts) and info.get("JobState") == "PENDING"
            return info if ok else None

        # 1. As at a time limit: USR1 to the batch shell only, which forwards it;
        #    campar flushes and exits 75; the script requeues the job.
        done1, total = wait_for(
            "the first attempt's first tiles", lambda: running_with_progress(0, 0), 180
        )
        r = _run(["scancel", "--signal=USR1", "--batch", jobid])
        assert r.returncode == 0, r.stderr
        wait_for("the job to requeue itself after USR1", lambda: requeued(1), 90)
        assert "job step ended with exit code 75" in out.read_text(), (
            "campar run did not exit 75 on SIGUSR1"
        )
        # The reference: one process, no SLURM, computed while the job waits to start
        # again with the cores idle (the kernel is in the session's warm cache).
        serial = subprocess.Popen(
            [str(campar), "run", str(serial_job)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=tmp_path,
            env=env,
        )

        # 2. As an admin or preemption does it: SIGTERM to everything, SLURM requeues.
        # Signal the second attempt only once it has committed a tile of its own:
        # before that, campar may not have installed its signal handlers yet.
        resumed_at, _ = tiles_done(slurm_store)
        assert done1 <= resumed_at < total, (done1, resumed_at, total)
        done2, _ = wait_for(
            "the second attempt to make progress",
            lambda: running_with_progress(1, resumed_at),
            120,
        )
        r = _run(["scontrol", "requeue", jobid])
        assert r.returncode == 0, r.stderr
        wait_for("the requeue by scontrol", lambda: requeued(2), 90)

        # 3. The third attempt resumes and finishes.
        def finished():
            info = job_info(jobid)
            return info if info.get("JobState") not in UNFINISHED else None

        final = wait_for("the job to finish", finished, 180)
        log = out.read_text()
        assert final.get("JobState") == "COMPLETED", f"{final.get('JobState')}:\n{log}"
        assert final.get("ExitCode") == "0:0"
        assert final.get("Restarts") == "2"
        steps = re.findall(r"job step ended with exit code (\d+)", log)
        assert steps == ["75", "75", "0"], steps
        assert tiles_done(slurm_store) == (total, total)
        r = call_campar(capsys, "status", slurm_store)  # what slurm/README.md points users to
        assert r.returncode == 0 and f"{total}/{total}" in r.stdout, r.stdout + r.stderr

        stdout, stderr = serial.communicate(timeout=600)
        assert serial.returncode == 0, f"serial campar run failed:\n{stdout}{stderr}"
        assert_stores_equal(slurm_store, serial_store)
        print(
            f"tiles done when signalled: {done1} and {done2} "
            f"of {total} (first attempt left {resumed_at}); "
            f"whole test {time.monotonic() - t_start:.1f} s",
            file=sys.stderr,
        )
    except BaseException:
        _dump_diagnostics(out)
        raise
    finally:
        if jobid and job_info(jobid).get("JobState") in UNFINISHED:
            _run(["scancel", jobid])
        if serial is not None and serial.poll() is None:
            serial.kill()
            serial.communicate()
