"""A job changed key by key: ``campar run JOB --set sweep.omega.points=200``.

A dotted key names a place in the job's mapping (``sweep.omega.points``,
``model.tensile``, ``transient.max_revolutions``); its value replaces what the job
holds there. The changed mapping is validated by ``Job.from_dict`` exactly as a job
file is, so a misspelled key or an out-of-range value is refused with the same one
line, naming the key and what is allowed.
"""

import yaml

from ..errors import JobError
from .job import Job
from .job_file import UniqueKeyLoader, yaml_problem


def parse_assignment(text: str) -> tuple[str, object]:
    """``"sweep.omega.points=200"`` → ``("sweep.omega.points", 200)``: the value read as
    YAML reads it in a job file (numbers, true/false, lists ``[label, dc]``, text)."""
    key, sep, raw = text.partition("=")
    if not sep or not key.strip():
        raise JobError(f"--set expects KEY=VALUE (e.g. sweep.omega.points=200), got {text!r}")
    try:
        value = yaml.load(raw, Loader=UniqueKeyLoader)
    except yaml.YAMLError as exc:
        raise JobError(
            f"--set {key}: the value {raw!r} is not valid YAML: {yaml_problem(exc)}"
        ) from None
    return key.strip(), value


def with_settings(job: Job, settings: dict[str, object], source: str = "--set") -> Job:
    """``job`` with each dotted key of ``settings`` set to its value, validated like a job
    file; JobError (one line per problem, prefixed with ``source``) if the result is not a
    valid job."""
    if not settings:
        return job
    data = job.to_dict()
    for key, value in settings.items():
        assign(data, key, value)
    return Job.from_dict(data, source=source)


def assign(data: dict, key: str, value) -> None:
    """Set ``data[a][b][c] = value`` for the key ``a.b.c``, making the mappings between
    (an optional section the job leaves out, a parameter new to ``sweep`` or ``fixed``)."""
    parts = key.split(".")
    if not all(parts):
        raise JobError(f"--set {key}: a key is names joined by dots, e.g. sweep.omega.points")
    node = data
    for depth, part in enumerate(parts[:-1]):
        child = node.get(part)
        if child is None:
            child = node[part] = {}
        elif not isinstance(child, dict):
            where = ".".join(parts[: depth + 1])
            raise JobError(f"--set {key}: {where} is {child!r}, not a mapping of keys")
        node = child
    node[parts[-1]] = value
