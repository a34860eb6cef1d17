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


class Interrupted(CamparError):
    """A run stopped on a signal; running the same command again resumes it."""

    exit_code = 75  # EX_TEMPFAIL: try again later
