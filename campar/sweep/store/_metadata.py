"""The store's variables under checksums: their metadata and the coordinates' values.

A tile's checksum (``_integrity``) vouches for its cells, but not for how they
decode: an attribute ``scale_factor`` added to ``dc`` doubles every value xarray
reads, a ``_FillValue`` changed hides cells, an edited ``omega`` moves the
whole map, a deleted ``dc/zarr.json`` leaves other Zarr readers without the
array. So a store records, when it is built, one checksum per variable
(attribute ``metadata_checksums``, JSON: name → BLAKE2b hex, 8 bytes) over
everything that says how its bytes read: its metadata document as the backend
stores it — dtype, shape, chunks, fill value, codecs or filters, dimension names
and every attribute (``scale_factor``, ``add_offset``, ``_FillValue``, ``units``,
…) — and, for a coordinate, its values. A Zarr store holds each document twice,
the array's own ``zarr.json`` and the copy consolidated into the store's
``zarr.json`` (the one campar and xarray read): both must match.

``variable_problems`` checks a store's variables against their checksums and
names what changed against a store built afresh from the stored job (whose own
hash vouches for it), e.g. "attribute scale_factor added (2.0)". A store
written before these checksums is checked against that fresh store directly, on
the parts that change how values decode (``DECODING``), and gets its checksums at
its next run. Whatever is found, ``campar run`` rewrites the variable from the
job (metadata and coordinates are functions of the job alone) and records the
checksums again: nothing of a variable is computed.
"""

import hashlib
import json
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

CHECKSUMS_ATTR = "metadata_checksums"
DIGEST_BYTES = 8
# The store's own attributes are one more "variable": those that say what the store holds
# (the job, the model's settings, the format), not those a run appends to or that say when
# and by which versions it was made.
GLOBAL = "(global attributes)"
# The root record (``_root``) of an HDF5 store is an attribute too: it vouches for the rest.
VOLATILE_ATTRS = (
    "runs",
    "history",
    "date_created",
    "campar_version",
    "versions",
    CHECKSUMS_ATTR,
    "campar_root",
)


def global_document(attrs: dict) -> dict:
    """The store's attributes under its checksum (``VOLATILE_ATTRS`` left out)."""
    return {key: value for key, value in attrs.items() if key not in VOLATILE_ATTRS}


# What changes how a variable's bytes decode: checked against the job where a store has no
# checksums. Zarr document keys, HDF5 description keys, and CF attributes.
DECODING = {
    "shape",
    "data_type",
    "chunk_grid",
    "chunk_key_encoding",
    "fill_value",
    "codecs",
    "dimension_names",
    "dtype",
    "chunks",
    "fillvalue",
    "compression",
    "scaleoffset",
}
DECODING_ATTRS = {
    "scale_factor",
    "add_offset",
    "_FillValue",
    "missing_value",
    "valid_min",
    "valid_max",
    "valid_range",
    "units",
    "calendar",
    "_Unsigned",
    "dtype",
    "coordinates",
    "flag_values",
    "flag_masks",
}


@dataclass
class Variable:
    """One variable as a store holds it: each copy of its metadata document, by where it
    is, and its values if it is a coordinate (None for a per-cell or per-tile array)."""

    documents: dict[str, dict] = field(default_factory=dict)
    values: np.ndarray | None = None


def variable_digest(document: dict, values: np.ndarray | None) -> str:
    """The checksum of one copy of a variable's metadata and its values (hex)."""
    h = hashlib.blake2b(digest_size=DIGEST_BYTES)
    h.update(json.dumps(document, sort_keys=True, default=repr).encode())
    if values is not None:
        h.update(b"values;")
        h.update(json.dumps(value_list(values)).encode())
    return h.hexdigest()


def value_list(values: np.ndarray) -> list:
    """Values as JSON numbers or text, the same from every backend (text may come as bytes)."""
    out = np.asarray(values).tolist()
    flat = out if isinstance(out, list) else [out]
    return [v.decode() if isinstance(v, bytes) else v for v in flat]


def digests(found: dict[str, "Variable | str"]) -> dict[str, str]:
    """The checksums to record for a store's variables (its first copy of each document)."""
    out = {}
    for name, variable in found.items():
        if isinstance(variable, str):
            raise ValueError(f"variable {name} cannot be read: {variable}")
        document = next(iter(variable.documents.values()))
        out[name] = variable_digest(document, variable.values)
    return out


def variable_problems(
    found: dict[str, "Variable | str"],
    stored: dict | None,
    expected: Callable[[], dict[str, Variable]],
) -> dict[str, str]:
    """{variable: what is wrong with it} for the variables ``found`` in a store (a str: why
    it cannot be read), checked against ``stored`` checksums, or where there are none
    against ``expected()``, the variables of a store built afresh from the job."""
    problems: dict[str, str] = {}
    fresh: dict[str, Variable] = {}

    def reference(name: str) -> Variable | None:
        if not fresh:
            fresh.update(expected())
        return fresh.get(name)

    for name, variable in found.items():
        if isinstance(variable, str):
            problems[name] = variable
            continue
        copies = list(variable.documents.values())
        alike = all(_text(document) == _text(copies[0]) for document in copies)
        recorded = stored is not None and name in stored  # else: checked against the job
        for where, document in variable.documents.items():
            place = "" if alike else f"{where}: "  # which copy, where the copies differ
            if recorded:
                if variable_digest(document, variable.values) == stored[name]:
                    continue
                what = changes(document, variable.values, reference(name), everything=True)
                problems[name] = f"{place}{what or 'changed'} (its checksum differs)"
                break
            what = changes(document, variable.values, reference(name), everything=False)
            if what:
                problems[name] = f"{place}{what}"
                break
    return problems


def changes(document: dict, values, reference: Variable | None, everything: bool) -> str:
    """What differs between a variable and its ``reference`` (as its job makes it), in a few
    words: every key of its document (``everything``) or only the ``DECODING`` ones."""
    if reference is None:
        return "not part of the stored job's store" if everything else ""
    want = next(iter(reference.documents.values()))
    said = []
    for key in sorted(set(document) | set(want)):
        if key == "attributes" or key == "attrs":
            said += attribute_changes(document.get(key, {}), want.get(key, {}), everything)
        elif (everything or key in DECODING) and _text(document.get(key)) != _text(want.get(key)):
            said.append(f"{key} {_short(document.get(key))}, the job's {_short(want.get(key))}")
    if reference.values is not None and values is not None:
        got, wanted = value_list(values), value_list(reference.values)
        if got != wanted:
            at = next((i for i, (a, b) in enumerate(zip(got, wanted, strict=False)) if a != b), 0)
            said.append(
                f"values differ from the job's (first at index {at}: "
                f"{_short(got[at] if at < len(got) else None)}, "
                f"the job's {_short(wanted[at] if at < len(wanted) else None)})"
            )
    return "; ".join(said)


def attribute_changes(got: dict, want: dict, everything: bool) -> list[str]:
    said = []
    for key in sorted(set(got) | set(want)):
        if not everything and key not in DECODING_ATTRS:
            continue
        if key not in want:
            said.append(f"attribute {key} added ({_short(got[key])})")
        elif key not in got:
            said.append(f"attribute {key} removed")
        elif key == "flag_masks" and not everything and _fewer_flags(got[key], want[key]):
            continue  # written by a campar of fewer flags: its values decode alike
        elif _text(got[key]) != _text(want[key]):
            said.append(f"attribute {key} is {_short(got[key])}, the job's {_short(want[key])}")
    return said


def _fewer_flags(got, want) -> bool:
    """Whether the flag masks ``got`` are some of ``want``'s: a cell's flags decode the same
    under both, as the masks a campar added later are bits no cell of the store has set."""
    try:
        return set(np.ravel(got).tolist()) <= set(np.ravel(want).tolist())
    except TypeError:
        return False


def _text(value) -> str:
    return json.dumps(value, sort_keys=True, default=repr)


def _short(value, chars: int = 40) -> str:
    text = _text(value)
    return text if len(text) <= chars else text[: chars - 1] + "…"
