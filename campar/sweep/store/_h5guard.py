"""HDF5 files checked before the HDF5 library reads them, and rescued in a child process.

The HDF5 library trusts its file: a damaged one can make it raise, but also
loop for ever or crash (measured: 4 KiB of zeros in a 120 kB store made
h5py's attribute iteration spin). So campar never hands HDF5 a store file it
has not checked. Every file campar writes carries, in its HDF5 user block (512
bytes HDF5 itself skips; netCDF and h5py read the file as usual), its seal: the
BLAKE2b digest of the rest of the file and the hash of the job it holds, the
rest of the block zeros, so that every byte of the file is checked. The file is
only ever replaced whole (written aside, renamed), so the seal holds from one
write to the next. Before a store file is opened, ``file_state`` hashes it
(about 1 GB/s) and compares. The job hash names the store's job even when HDF5
cannot read the file at all (a truncated file keeps its first bytes): a resume
of that job keeps the file aside and starts again, never guessing.

A file that fails the check is read by ``rescue`` in a child process with a
watchdog: the child opens it, reports its attributes and every committed
tile's verdict (its checksum), and copies the tiles that verify into a new
file. A child that hangs (silent for ``WATCHDOG_SECONDS``) is killed, one that
crashes is reported; the parent is never at the HDF5 library's mercy. Files of
formats 1 and 2 (no user block) are read as before.

Nor does campar let HDF5 meet a full disk (measured: a checkpoint that ran out
of space printed thousands of lines of HDF5 errors and crashed the process):
a new file is built in memory and written by Python, and before HDF5 writes
into a copy, ``reserve`` allocates the disk blocks it may need (fallocate with
FALLOC_FL_KEEP_SIZE), so a full disk is one OSError before HDF5 starts.
"""

import ctypes
import errno
import hashlib
import json
import os
import subprocess
import sys
import threading
from dataclasses import dataclass, field
from pathlib import Path

from ._h5layout import USERBLOCK, build

SIGNATURE = b"\x89HDF\r\n\x1a\n"  # where an HDF5 file's superblock starts
MAGIC = b"campar-digest blake2b-16 "
JOB = b"job "  # the second line of the seal: the job hash of the store
DIGEST_BYTES = 16
BLOCK = 1 << 20  # hashing reads this much at a time
# A rescue child silent this long is hung in the HDF5 library (reading a tile takes
# milliseconds); the environment can shorten it (the fault-injection tests do).
WATCHDOG_SECONDS = float(os.environ.get("CAMPAR_RESCUE_WATCHDOG", "20"))
STARTUP_SECONDS = 300.0  # a child still loading Python and h5py after this is hung too

UNSEALED = "unsealed"  # an HDF5 file without campar's digest (formats 1 and 2)
FOREIGN = "not an HDF5 file"

_cache: dict[tuple, str | None] = {}  # (path, inode, size, mtime) → state
_rescued: dict[tuple, "Rescue"] = {}  # the same → what a rescue of the attributes read


def file_digest(path: Path, job_hash: str) -> str:
    """BLAKE2b digest (hex) of the job hash and the file after its user block."""
    with open(path, "rb") as fh:
        return _digest(fh, job_hash)


def _digest(fh, job_hash: str) -> str:
    h = hashlib.blake2b(job_hash.encode(), digest_size=DIGEST_BYTES)
    fh.seek(USERBLOCK)
    while chunk := fh.read(BLOCK):
        h.update(chunk)
    return h.hexdigest()


FALLOC_FL_KEEP_SIZE = 1  # linux/falloc.h: allocate blocks without changing the file's size


def reserve(fh, nbytes: int, path: Path) -> None:
    """Allocate ``nbytes`` of disk for the open file ``fh`` beyond its end; OSError(ENOSPC)
    if the disk has not that much. Filesystems without fallocate: nothing reserved (the
    caller's free-space check stands alone). ``release`` gives back what is left unused."""
    libc = ctypes.CDLL(None, use_errno=True)
    fallocate = getattr(libc, "fallocate", None)
    if fallocate is None:
        return
    fallocate.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_long, ctypes.c_long]
    if fallocate(fh.fileno(), FALLOC_FL_KEEP_SIZE, 0, nbytes) == 0:
        return
    code = ctypes.get_errno()
    if code in (errno.EOPNOTSUPP, errno.ENOSYS, errno.EINVAL):
        return
    raise OSError(code, f"{os.strerror(code)}: {nbytes / 1e6:.1f} MB needed", str(path.parent))


def release(path: Path) -> None:
    """Free the blocks ``reserve`` allocated past the end of the file that HDF5 did not use."""
    with open(path, "r+b") as fh:
        os.ftruncate(fh.fileno(), os.fstat(fh.fileno()).st_size)


def seal(path: Path, job_hash: str) -> None:
    """Write the digest of a file campar has just written into its user block, with the hash
    of the job it holds (``sealed_job``), and fsync it."""
    with open(path, "r+b") as fh:
        fh.write(_stamp(file_digest(path, job_hash), job_hash))
        fh.flush()
        os.fsync(fh.fileno())


def _stamp(digest: str, job_hash: str) -> bytes:
    """The whole user block: every byte of it is checked, so every byte of the file is."""
    return (MAGIC + f"{digest}\n".encode() + JOB + f"{job_hash}\n".encode()).ljust(USERBLOCK, b"\0")


def sealed_job(path: Path) -> str | None:
    """The job hash in a file's seal: which job a store holds even when HDF5 cannot read it
    (a truncated file keeps its first bytes); None if the seal is unreadable."""
    with open(path, "rb") as fh:
        head = fh.read(USERBLOCK)
    return _job_line(head) if head.startswith(MAGIC) else None


def _job_line(head: bytes) -> str | None:
    for line in head.split(b"\n"):
        if line.startswith(JOB) and len(line) == len(JOB) + 16:
            return line[len(JOB) :].decode("ascii", "replace")
    return None


def file_state(path: Path) -> tuple[str | None, int]:
    """(state, inode) of the file now at ``path``: state None if it is as campar sealed it,
    UNSEALED if it carries no seal (an HDF5 file of format 1 or 2, or rewritten by another
    tool), FOREIGN if it is no HDF5 file, else why it fails its check. Cached per version."""
    with open(path, "rb") as fh:
        st = os.fstat(fh.fileno())
        key = (str(path), st.st_ino, st.st_size, st.st_mtime_ns)
        if key not in _cache:
            _cache.clear()  # one file at a time: memory stays flat
            _cache[key] = _check(fh)
    return _cache[key], st.st_ino


def _check(fh) -> str | None:
    head = fh.read(USERBLOCK)
    if head and len(head) < len(MAGIC) and MAGIC.startswith(head):
        return f"it is cut short after {len(head)} bytes of campar's seal"
    if not head.startswith(MAGIC):
        if head.startswith(SIGNATURE):
            return UNSEALED
        fh.seek(USERBLOCK)
        if fh.read(len(SIGNATURE)) != SIGNATURE:
            return FOREIGN
        return "its user block, which holds campar's digest of the file, is damaged"
    stored = head[len(MAGIC) : len(MAGIC) + 2 * DIGEST_BYTES].decode("ascii", "replace")
    job_hash = _job_line(head) or ""
    if head != _stamp(stored, job_hash) or _digest(fh, job_hash) != stored:
        return "its bytes differ from those campar wrote (the digest in its user block disagrees)"
    return None


def zeroed_start(path: Path) -> bool:
    """The file begins with a block of zeros (where a damaged HDF5 file had its signature)."""
    with open(path, "rb") as fh:
        head = fh.read(2 * USERBLOCK)
    return len(head) == 2 * USERBLOCK and not head.strip(b"\0")


def open_checked(path: Path):
    """(h5py.File, state) of a file that passed its check (or is UNSEALED); (None, state)
    if it did not: never hand HDF5 a file it has not checked."""
    import h5py

    for _ in range(3):
        state, inode = file_state(path)
        if state not in (None, UNSEALED):
            return None, state
        f = h5py.File(path, "r")
        if os.fstat(f.id.get_vfd_handle()).st_ino == inode:
            return f, state
        f.close()  # a checkpoint replaced the file meanwhile: check the new one
    raise OSError(f"{path} is replaced faster than it can be checked")


# -- the rescue child --------------------------------------------------------------------


@dataclass
class Rescue:
    """What a rescue child read from a damaged file."""

    attrs: dict | None = None  # the store's attributes (decoded), if readable
    good: list[int] = field(default_factory=list)  # committed tiles that verified
    damaged: dict[int, str] = field(default_factory=dict)  # committed tiles that did not
    finished: bool = False  # the child got through every tile (and the copy, if asked)
    failure: str | None = None  # how the child ended, if it did not finish


def rescue_attrs(path: Path) -> Rescue:
    """``rescue`` of the attributes alone (cached per version of the file: a store is opened
    by ``read_attrs`` and then by its reader)."""
    st = os.stat(path)
    key = ("attrs", str(path), st.st_ino, st.st_size, st.st_mtime_ns)
    if key not in _rescued:
        _rescued.clear()
        _rescued[key] = rescue(path, attrs_only=True)
    return _rescued[key]


def rescue(path: Path, into: Path | None = None, attrs_only: bool = False) -> Rescue:
    """Read a damaged HDF5 store in a child process: its attributes, and (unless
    ``attrs_only``) every committed tile's verdict; build a new store of its job at ``into``
    (if given) holding the tiles that verify and the old attributes (trusted only if
    ``finished``)."""
    command = [sys.executable, "-m", "campar.sweep.store._h5guard", str(path)]
    command.append("--attrs" if attrs_only else str(into) if into is not None else "--tiles")
    child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    result, heard = Rescue(), threading.Event()

    def watchdog():
        heard.wait(STARTUP_SECONDS)  # Python and h5py loading: not yet the damaged file
        heard.clear()
        while child.poll() is None:
            if not heard.wait(WATCHDOG_SECONDS):
                child.kill()
                result.failure = (
                    f"reading it hangs the HDF5 library (silent for {WATCHDOG_SECONDS:.0f} s)"
                )
                return
            heard.clear()

    threading.Thread(target=watchdog, daemon=True).start()
    for line in child.stdout:
        heard.set()
        _take(result, json.loads(line))
    code = child.wait()
    heard.set()  # the watchdog sees the child gone and ends
    if not result.finished and result.failure is None:
        result.failure = f"reading it crashes the HDF5 library (exit {code})"
    return result


def _take(result: Rescue, message: dict) -> None:
    if "attrs" in message:
        result.attrs = message["attrs"]
    elif "tile" in message:
        if message["why"] is None:
            result.good.append(message["tile"])
        else:
            result.damaged[message["tile"]] = message["why"]
    elif "error" in message:
        result.failure = f"HDF5 cannot read it ({message['error']})"
    elif message.get("finished"):
        result.finished = True


ATTRS_ONLY = "--attrs"


def _child(source: Path, into: Path | str | None) -> None:
    """In the child: report attributes and tile verdicts line by line; copy the good tiles."""
    import h5py
    import numpy as np

    from ..job import Job
    from ..plan import plan_tiles
    from ._integrity import describe_exception, tile_checksum
    from ._schema import cell_arrays, decode_attrs

    def say(**message):
        print(json.dumps(message, default=str), flush=True)

    say(ready=True)  # loaded: from now on, silence means HDF5 is stuck on the file
    try:
        f = h5py.File(source, "r")
    except Exception as exc:
        say(error=describe_exception(exc))
        return
    with f:
        raw = dict(f.attrs.items())
        attrs = decode_attrs(raw)
        say(attrs=attrs)
        if into == ATTRS_ONLY:
            say(finished=True)
            return
        job = Job.from_dict(attrs["job"])
        names = [a.name for a in cell_arrays(job)]
        if into is not None:
            build(into, job)
        out = h5py.File(into, "r+") if into is not None else None
        try:
            if out is not None:
                for key, value in raw.items():
                    out.attrs[key] = value
            for tile in plan_tiles(job):
                try:
                    if int(f["done"][tile.index]) == 0:
                        continue
                    arrays = {name: f[name][tile.region] for name in names}
                    stored = int(f["checksum"][tile.index])
                    why = (
                        None
                        if stored and tile_checksum(arrays, names) == stored
                        else ("checksum mismatch: its arrays changed after the commit")
                    )
                except Exception as exc:  # whatever HDF5 raises on this tile's bytes
                    why, arrays = f"unreadable ({describe_exception(exc)})", None
                if why is None and out is not None:
                    for name, values in arrays.items():
                        out[name][tile.region] = values
                    out["checksum"][tile.index] = np.uint64(stored)
                    out["done"][tile.index] = 1
                say(tile=tile.index, why=why)
        finally:
            if out is not None:
                out.close()
    say(finished=True)


if __name__ == "__main__":
    try:
        target = {"--attrs": ATTRS_ONLY, "--tiles": None}.get(sys.argv[2], Path(sys.argv[2]))
        _child(Path(sys.argv[1]), target)
    except Exception as exc:  # an error of the HDF5 library on the damaged bytes
        from ._integrity import describe_exception

        print(json.dumps({"error": describe_exception(exc)}), flush=True)
