"""A store's file replaced whole: written aside, then renamed into place.

Every file a Zarr store's writer makes — its metadata documents, its chunks, its root
record — is written as ``<path>.<32 hex>.partial`` and renamed onto ``path``, as zarr's
``LocalStore`` writes: a reader sees the old file or the new one, never part of one, and
a killed writer leaves whole files plus stray ``.partial`` ones, which
``_zarr.clean_leftovers`` deletes.
"""

import contextlib
import os
import uuid
from pathlib import Path


def write_file(path: Path | str, body: bytes) -> None:
    """Write ``body`` aside as ``<path>.<32 hex>.partial``, then rename it onto ``path``; a
    failed write leaves no ``.partial`` file."""
    aside = f"{path}.{uuid.uuid4().hex}.partial"
    try:
        with open(aside, "wb") as file:
            file.write(body)
        os.replace(aside, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(aside)
        raise
