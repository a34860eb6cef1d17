"""One run per store: a lock file beside the store naming host, pid and start time.

The lock is a sidecar (``<store>.lock``) rather than a file inside the store so
that it can be taken before the store exists and held while ``--overwrite``
replaces it. It is created atomically (written aside, then hard-linked to its
name, which fails if the name exists), so it is never seen half written. A
lock left by a killed run is stale when it names this host and a process that
no longer exists (or a pid since reused by a younger process); it is then taken
over with a warning. A lock of another host cannot be checked and is refused,
and so is a lock file that names no run (empty or garbled: not written by
campar, which writes it whole). ``store`` is the store's real path (symbolic
links resolved), so every alias of a store finds the same lock.
"""

import json
import logging
import os
import socket
from datetime import UTC, datetime
from pathlib import Path

from ...errors import StoreIOError, StoreLocked, io_error

log = logging.getLogger("campar.sweep.store")


def lock_path(store: Path) -> Path:
    return store.with_name(store.name + ".lock")


def process_start(pid: int) -> int | None:
    """Start time of a process in clock ticks since boot (Linux), to tell reused pids apart."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    # Field 22; the command name (field 2) may hold spaces, so count from its ')'.
    return int(stat.rpartition(")")[2].split()[19])


def holder_alive(holder: dict) -> bool:
    pid = holder.get("pid")
    if not isinstance(pid, int) or pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True  # exists, owned by someone else
    if process_state(pid) in ("Z", "X"):
        return False  # killed, not yet reaped (a container's init may never reap it)
    started = holder.get("pid_start")
    return started is None or process_start(pid) in (None, started)


def process_state(pid: int) -> str | None:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()[0]
    except (OSError, IndexError):
        return None


class StoreLock:
    """The lock of one store, held by this process until ``release``."""

    def __init__(self, path: Path, holder: dict):
        self.path = path
        self.holder = holder

    @classmethod
    def acquire(cls, store: Path) -> "StoreLock":
        path = lock_path(store)
        try:
            blocking = next((p for p in path.parents if p.exists() or p.is_symlink()), None)
            if blocking is not None and not blocking.is_dir():  # mkdir would say "File exists"
                raise StoreIOError(
                    f"cannot create the store {store}: {blocking} is a file, not a folder"
                )
            path.parent.mkdir(parents=True, exist_ok=True)
            return cls._acquire(store, path)
        except OSError as exc:
            where = OSError(exc.errno, exc.strerror, str(path.parent))  # not our temporary name
            raise io_error(f"cannot take the lock of the store {store}", where) from None

    @classmethod
    def _acquire(cls, store: Path, path: Path) -> "StoreLock":
        me = {
            "host": socket.gethostname(),
            "pid": os.getpid(),
            "pid_start": process_start(os.getpid()),
            "start": datetime.now(UTC).isoformat(timespec="seconds"),
        }
        for _ in range(2):  # second pass after removing a stale lock
            if _create_exclusive(path, json.dumps(me)):
                return cls(path, me)
            holder = _read_holder(path)
            if holder is None:
                continue  # vanished meanwhile: try again
            if not holder.get("host") or not holder.get("pid"):
                raise StoreLocked(
                    f"{store} has a lock file {path} that names no run (empty or garbled; "
                    "campar writes it whole): delete it if no run uses the store"
                )
            if holder.get("host") != me["host"] or holder_alive(holder):
                raise StoreLocked(
                    f"{store} is in use by pid {holder.get('pid')} on host "
                    f"{holder.get('host')} (since {holder.get('start')}); wait for that run, "
                    f"or delete {path} if you are sure it is gone"
                )
            log.warning(
                "taking over the stale lock of %s: pid %s on %s (since %s) is gone",
                store,
                holder.get("pid"),
                holder.get("host"),
                holder.get("start"),
            )
            path.unlink(missing_ok=True)
        raise StoreLocked(f"could not take the lock {path}; another run is starting")

    def release(self) -> None:
        # Only remove the file if it is still ours (never another run's lock).
        if _read_holder(self.path) == self.holder:
            self.path.unlink(missing_ok=True)


def _create_exclusive(path: Path, text: str) -> bool:
    tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "w") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())  # never an empty lock after a power cut
        os.link(tmp, path)
        return True
    except FileExistsError:
        return False
    finally:
        tmp.unlink(missing_ok=True)


def _read_holder(path: Path) -> dict | None:
    try:
        holder = json.loads(path.read_text())
    except FileNotFoundError:
        return None
    except (OSError, ValueError):
        return {}  # not ours to judge (we never write it half): refused, names the file
    return holder if isinstance(holder, dict) else {}
