"""A job file read with bounds (what ``load_job`` hands the schema), and its problems
said in one line.

PyYAML's safe loader would accept a file of any size and encoding, a key that is
a list, a key given twice (keeping the last), a 5000-digit integer (and then fail
converting it) and aliases whose expansion is exponential in the file's length
(nine levels of nine-fold aliases: 387 million values, minutes of validation and
gigabytes of memory for a 300-byte file). Here each of those is one line naming
the problem; the numbers are YAML 1.2's (``1e-8`` is a float, not text).
"""

import re
import typing
from pathlib import Path

import yaml

from ..errors import JobError
from ..model.settings import short_repr


def format_validation_error(exc, source: str, allowed_keys) -> str:
    """Every problem pydantic found, on one line: "SOURCE: key: problem; key: problem"
    (required keys missing from one mapping named together). ``exc``: pydantic's
    ValidationError; ``allowed_keys(loc)``: the keys a job may have at ``loc``."""
    problems, missing = [], {}
    for err in exc.errors():
        where = ".".join(str(part) for part in err["loc"]) or "(top level)"
        message = err["msg"].removeprefix("Value error, ")
        if err["type"] == "missing":
            parent = ".".join(str(part) for part in err["loc"][:-1])
            if parent not in missing:
                missing[parent] = []
                problems.append(("missing", parent))
            missing[parent].append(str(err["loc"][-1]))
            continue
        if err["type"] == "extra_forbidden":
            message = f"unknown key; allowed here: {', '.join(allowed_keys(err['loc'][:-1]))}"
        elif err["type"] in ("model_type", "dict_type"):
            message = "must be a mapping of keys (key: value, or {key: value})"
        got = err.get("input")
        detail = (
            ""
            if err["type"] == "extra_forbidden" or isinstance(got, dict)
            else f", got {short_repr(got)}"
        )
        problems.append(("", f"{where}: {message}{detail}"))
    lines = []
    for kind, text in problems:
        if kind == "missing":
            keys = missing[text]
            prefix = f"{text}." if text else ""
            lines.append(
                f"{prefix}{keys[0]}: required key is missing"
                if len(keys) == 1
                else f"{text or '(top level)'}: required keys are missing: {', '.join(keys)}"
            )
        else:
            lines.append(text)
    return f"{source}: " + "; ".join(lines)


def check_store_path(path) -> str:
    """``path`` as text if it can name a store; ValueError saying why not (empty, a NUL byte,
    a path that ends in no name: /, ., ..)."""
    text = str(path)
    if not text.strip():
        raise ValueError("an empty path; name the store, e.g. results/map.zarr")
    if "\0" in text:
        raise ValueError("the path holds a NUL byte, which no file name can")
    if Path(text).name in ("", ".", ".."):
        example = text.rstrip("/") + "/map.zarr"
        raise ValueError(f"names a folder, not a store; add the store's name, e.g. {example}")
    return text


class UniqueKeyLoader(yaml.SafeLoader):
    """YAML's safe loader, refusing a key given twice in one mapping (YAML requires keys to
    be unique; PyYAML would keep the last value silently), a key that is not a plain value
    (``? [1, 2]``), and integers of more than MAX_DIGITS digits; floats as YAML 1.2 reads
    them (``1e-8`` is a number, not the text YAML 1.1 makes of it)."""


MAX_JOB_BYTES = 1 << 20  # a job file of every key with comments is ~5 kB
MAX_DIGITS = 30  # digits of an integer: every bound of the schema has at most 13
# Nodes of the document once every alias is expanded. A job of every key and a census has
# ~150; a value repeated through aliases expands into the validator's work and messages
# (nine levels of nine-fold aliases are 387 million nodes: minutes and gigabytes).
MAX_NODES = 10_000

FLOAT_TAG = "tag:yaml.org,2002:float"
YAML12_FLOAT = re.compile(
    r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
    |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
    |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
    |[-+]?\.(?:inf|Inf|INF)
    |\.(?:nan|NaN|NAN))$""",
    re.X,
)
UniqueKeyLoader.yaml_implicit_resolvers = {
    first: [(tag, regexp) for tag, regexp in resolvers if tag != FLOAT_TAG]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
UniqueKeyLoader.add_implicit_resolver(FLOAT_TAG, YAML12_FLOAT, list("-+0123456789."))


def _unique_mapping(loader: UniqueKeyLoader, node: yaml.MappingNode, deep: bool = False):
    seen = {}
    for key_node, _ in node.value:
        if not isinstance(key_node, yaml.ScalarNode):
            line = key_node.start_mark.line + 1
            raise yaml.YAMLError(f"line {line}: a key must be a name, not a {key_node.id}")
        key = loader.construct_object(key_node, deep=deep)
        if isinstance(key, typing.Hashable) and key in seen:
            lines = f"lines {seen[key] + 1} and {key_node.start_mark.line + 1}"
            raise yaml.YAMLError(f"the key {key!r} is given twice ({lines})")
        seen[key] = key_node.start_mark.line
    return loader.construct_mapping(node, deep=deep)


def _bounded_int(loader: UniqueKeyLoader, node: yaml.ScalarNode):
    digits = sum(c.isdigit() for c in node.value)
    if digits > MAX_DIGITS:
        line = node.start_mark.line + 1
        raise yaml.YAMLError(
            f"line {line}: an integer of {digits} digits; no setting takes more than {MAX_DIGITS}"
        )
    return loader.construct_yaml_int(node)


def _refused_tag(loader: UniqueKeyLoader, node: yaml.Node):
    line = node.start_mark.line + 1
    raise yaml.YAMLError(
        f"line {line}: a {node.tag.replace('tag:yaml.org,2002:', '!!')} value is not allowed in "
        "a job (numbers, text, true/false, lists and mappings only; quote it to make it text)"
    )


# The safe loader's other types (bytes, dates, sets, ordered pairs) are no job's values.
for _tag in ("binary", "timestamp", "set", "omap", "pairs"):
    UniqueKeyLoader.add_constructor(f"tag:yaml.org,2002:{_tag}", _refused_tag)
UniqueKeyLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _unique_mapping)
UniqueKeyLoader.add_constructor("tag:yaml.org,2002:int", _bounded_int)


def expanded_nodes(node: yaml.Node, limit: int = MAX_NODES) -> int:
    """The nodes of a YAML document with every alias expanded; YAMLError once over ``limit``
    or if an alias contains itself. Each distinct node is counted once, in the time of the
    document as written."""
    sizes: dict[int, int] = {}
    open_nodes: set[int] = set()

    def size(n: yaml.Node) -> int:
        key = id(n)
        if key in sizes:
            return sizes[key]
        if key in open_nodes:
            raise yaml.YAMLError(f"line {n.start_mark.line + 1}: an alias that contains itself")
        open_nodes.add(key)
        if isinstance(n, yaml.SequenceNode):
            total = 1 + sum(size(child) for child in n.value)
        elif isinstance(n, yaml.MappingNode):
            total = 1 + sum(size(k) + size(v) for k, v in n.value)
        else:
            total = 1
        open_nodes.discard(key)
        if total > limit:
            raise yaml.YAMLError(
                f"line {n.start_mark.line + 1}: its aliases expand to over {limit} values; "
                "a job needs a few hundred: write the values out"
            )
        sizes[key] = total
        return total

    return size(node)


def parse_job_text(data: bytes, where: str):
    """The YAML document of a job file's bytes, as Python values; JobError (one line) for a
    file too large, not UTF-8 text, not valid YAML or bounded YAML (``UniqueKeyLoader``,
    ``expanded_nodes``)."""
    if len(data) > MAX_JOB_BYTES:
        raise JobError(f"{where}: {len(data)} bytes; a job file is at most {MAX_JOB_BYTES}")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise JobError(
            f"{where}: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start}); "
            "save the job file as UTF-8"
        ) from None
    loader = None
    try:
        loader = UniqueKeyLoader(text)  # its reader refuses control characters at once
        node = loader.get_single_node()
        if node is None:
            return None
        expanded_nodes(node)
        return loader.construct_document(node)
    except yaml.YAMLError as exc:
        raise JobError(f"{where}: not valid YAML: {yaml_problem(exc)}") from None
    except RecursionError:
        raise JobError(f"{where}: not valid YAML: nested too deeply") from None
    finally:
        if loader is not None:
            loader.dispose()


def yaml_problem(exc: yaml.YAMLError) -> str:
    """A YAML error in one line: where, and what ("line 3, column 1: expected …")."""
    if not isinstance(exc, yaml.MarkedYAMLError):
        return " ".join(str(exc).split())
    mark = exc.problem_mark or exc.context_mark
    where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark else ""
    what = "; ".join(" ".join(part.split()) for part in (exc.context, exc.problem) if part)
    return where + what
