"""One error hierarchy for campar; every message says what to change."""


class CamparError(Exception):
    """Base of every error campar raises on purpose."""

    exit_code = 1


class JobError(CamparError):
    """A job file or parameter set is invalid."""

    exit_code = 2


class StoreError(CamparError):
    """A result store cannot be used as asked."""

    exit_code = 3


class StoreMismatch(StoreError):
    """The store at the path was made by a different job."""


class StoreLocked(StoreError):
    """Another run holds the store's lock."""


class StoreDamaged(StoreError):
    """A store's committed tiles or metadata fail their checks (``campar verify``)."""

    exit_code = 65  # EX_DATAERR: the data is wrong


class StoreDamageWarning(UserWarning):
    """A store opened with damaged tiles: their cells read as not computed (``campar.open``)."""


class StoreIOError(StoreError):
    """The operating system refused a read or write of the store (full disk, permissions)."""

    exit_code = 74  # EX_IOERR


class OutputError(CamparError):
    """An output file cannot be written where or in the format asked."""

    exit_code = 73  # EX_CANTCREAT


class ContinuationError(CamparError):
    """A periodic orbit, a branch or a bifurcation curve could not be computed as asked
    (Newton did not converge, the integration failed); the message says where and why."""

    exit_code = 1


class Interrupted(CamparError):
    """A run stopped on a signal; running the same command again resumes it."""

    exit_code = 75  # EX_TEMPFAIL: try again later

    def __init__(self, message: str = "", exit_code: int | None = None):
        super().__init__(message)
        if exit_code is not None:
            self.exit_code = exit_code  # 130 for a Ctrl-C before the run started


def io_error(what: str, exc: OSError) -> StoreIOError:
    """A StoreIOError in one line: what failed, on which path, and the system's reason."""
    reason = exc.strerror or str(exc) or type(exc).__name__
    where = f" ({exc.filename})" if exc.filename and str(exc.filename) not in what else ""
    return StoreIOError(f"{what}: {reason}{where}")
