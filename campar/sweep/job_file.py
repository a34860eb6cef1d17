"""A job file's YAML read strictly, and pydantic's findings said one line each."""

import typing

import yaml


class UniqueKeyLoader(yaml.SafeLoader):
    """YAML's safe loader, refusing a key given twice in one mapping (YAML requires keys to
    be unique; PyYAML would keep the last value silently)."""


def _unique_mapping(loader: UniqueKeyLoader, node: yaml.MappingNode, deep: bool = False):
    seen = {}
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        if isinstance(key, typing.Hashable) and key in seen:
            lines = f"lines {seen[key] + 1} and {key_node.start_mark.line + 1}"
            raise yaml.YAMLError(f"the key {key!r} is given twice ({lines})")
        seen[key] = key_node.start_mark.line
    return loader.construct_mapping(node, deep=deep)


UniqueKeyLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _unique_mapping)


def format_validation_error(exc, source: str, allowed_keys) -> str:
    """Every problem pydantic found, one line each: "SOURCE: key: problem". ``exc``: pydantic's
    ValidationError; ``allowed_keys(loc)``: the keys a job may have at ``loc``."""
    lines = []
    for err in exc.errors():
        where = ".".join(str(part) for part in err["loc"]) or "(top level)"
        message = err["msg"].removeprefix("Value error, ")
        if err["type"] == "extra_forbidden":
            message = f"unknown key; allowed here: {', '.join(allowed_keys(err['loc'][:-1]))}"
        elif err["type"] == "missing":
            message = "required key is missing"
        elif err["type"] in ("model_type", "dict_type"):
            message = "must be a mapping of keys (key: value, or {key: value})"
        got = err.get("input")
        detail = (
            ""
            if err["type"] in ("extra_forbidden", "missing") or isinstance(got, dict)
            else f", got {got!r}"
        )
        lines.append(f"{source}: {where}: {message}{detail}")
    return "\n".join(lines)
