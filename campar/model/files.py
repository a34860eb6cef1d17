"""Input files read whole (a job file, a cam table): checked for type and size first.

A path can name a FIFO (a read blocks until a writer comes, perhaps never), a device
(``/dev/zero`` never ends), a directory or a file far larger than any input: reading
first and checking the size after waits for ever or runs out of memory. So the file
is opened without blocking (``O_NONBLOCK``: a FIFO opens at once), refused unless it is
a regular file, its size checked before a byte is read, and at most ``limit + 1``
bytes read (a file that grows meanwhile is still refused).
"""

import os
import stat


def read_bounded(path, limit: int, what: str) -> bytes:
    """The bytes of the regular file at ``path``, at most ``limit``; ValueError with one
    line naming ``what`` and the reason otherwise (its type, its size, the system's)."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise ValueError(f"cannot read {what} {path}: {exc.strerror}") from None
    except ValueError as exc:  # a NUL byte in the path
        raise ValueError(f"cannot read {what} {str(path)!r}: {exc}") from None
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            raise ValueError(f"{what} {path} is {_kind(mode)}, not a regular file")
        size = os.fstat(fd).st_size
        if size > limit:
            raise ValueError(f"{what} {path}: {size} bytes; a {what} is at most {limit}")
        chunks, total = [], 0
        while total <= limit:
            chunk = os.read(fd, limit + 1 - total)
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
        if total > limit:
            raise ValueError(
                f"{what} {path}: more than {limit} bytes (it grew as it was read); a {what} is "
                f"at most {limit}"
            )
        return b"".join(chunks)
    except OSError as exc:
        raise ValueError(f"cannot read {what} {path}: {exc.strerror}") from None
    finally:
        os.close(fd)


def _kind(mode: int) -> str:
    for test, name in (
        (stat.S_ISDIR, "a directory"),
        (stat.S_ISFIFO, "a FIFO (named pipe)"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return name
    return "not a regular file"
