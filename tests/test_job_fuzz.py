"""Generated bad job files (hypothesis): each one refused in one line naming what is wrong,
exit 2, quickly, nothing written. A valid job of every section is spoiled in one place:
a value no field of its kind takes, a key unknown or missing, a key that is no name, bytes
that are not UTF-8, or a value repeated through aliases until it would expand past any job."""

import os
import tempfile
import time
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from campar.cli import main

# A job of every section, each leaf as the YAML text written in the file.
GOOD = {
    "name": "fuzz",
    "sweep": {
        "omega": {"from": "6.0", "to": "1.0", "points": "4"},
        "mu_cn": {"from": "0.9", "to": "0.6", "points": "3"},
    },
    "fixed": {"zeta": "0.2", "mu_kn": "0.8"},
    "model": {"tensile": "clamp"},
    "initial": {"y": "0.0", "v": "0.0"},
    "integrator": {"method": "dop853", "rtol": "1.0e-7", "atol": "1e-10", "max_steps": "500000"},
    "transient": {"mode": "converged", "max_revolutions": "200", "jump_cap": "0.02"},
    "classify": {"n_max": "8", "window_revolutions": "16", "period_tol": "1e-6"},
    "tiles": {"rows": "2"},
    "chains": {"start": "rest", "direction": "down"},
    "outputs": "[label, dc]",
    "store": "out.zarr",
}
TEXT_LEAVES = {"name", "tensile", "method", "mode", "start", "direction", "store"}


def leaves(node, path=()):
    for key, value in node.items():
        if isinstance(value, dict):
            yield from leaves(value, (*path, key))
        else:
            yield (*path, key)


def mappings(node, path=()):
    yield path
    for key, value in node.items():
        if isinstance(value, dict):
            yield from mappings(value, (*path, key))


NUMBER_LEAVES = [p for p in leaves(GOOD) if p[-1] not in TEXT_LEAVES and p[-1] != "outputs"]
STRING_LEAVES = [p for p in leaves(GOOD) if p[-1] in TEXT_LEAVES]
MAPPINGS = list(mappings(GOOD))
REQUIRED = [("name",), ("sweep",), ("sweep", "omega", "from"), ("sweep", "mu_cn", "points")]


def bomb(levels: int) -> str:
    """A flow sequence of nine-fold aliases ``levels`` deep: 9**levels values expanded."""
    parts = ["&b0 [x, x, x, x, x, x, x, x, x]"]
    parts += [f"&b{i} [" + ", ".join([f"*b{i - 1}"] * 9) + "]" for i in range(1, levels + 1)]
    return "[" + ", ".join(parts) + "]"


# Values no number of a job takes: text, truth values, non-finite, collections, too many
# digits, alias bombs.
NOT_NUMBERS = st.one_of(
    st.sampled_from(
        [
            "'4'",
            '"1e-3"',
            "abc",
            "true",
            "false",
            "yes",
            ".nan",
            ".inf",
            "-.inf",
            "[1, 2]",
            "{a: 1}",
            "''",
            "0x",
            "1.0.0",
        ]
    ),
    st.integers(31, 400).map(lambda digits: "7" * digits),
    st.integers(5, 9).map(bomb),
)
# Values none of the text settings takes, and those one of them does not.
NOT_TEXT = st.one_of(
    st.sampled_from(["''", '"a\\0b"', "[x]", "{a: b}", "7", "true", "1.5"]),
    st.integers(5, 9).map(bomb),
)
NOT_THIS_TEXT = {"name": ["a name/with slash", "ü"], "store": ["/", "..", ".", "a/.."]}


def render(node, indent="") -> str:
    lines = []
    for key, value in node.items():
        if isinstance(value, dict):
            lines.append(f"{indent}{key}:")
            lines.append(render(value, indent + "  "))
        else:
            lines.append(f"{indent}{key}: {value}")
    return "\n".join(line for line in lines if line)


def replaced(node, path, value):
    out = dict(node)
    if len(path) == 1:
        if value is None:
            del out[path[0]]
        else:
            out[path[0]] = value
        return out
    out[path[0]] = replaced(node[path[0]], path[1:], value)
    return out


def inside(node, path, key, value):
    out = dict(node)
    if not path:
        out[key] = value
        return out
    out[path[0]] = inside(node[path[0]], path[1:], key, value)
    return out


@st.composite
def bad_job_files(draw) -> bytes:
    how = draw(st.sampled_from(["number", "text", "unknown", "missing", "key", "bytes"]))
    job = GOOD
    if how == "number":
        job = replaced(job, draw(st.sampled_from(NUMBER_LEAVES)), draw(NOT_NUMBERS))
    elif how == "text":
        leaf = draw(st.sampled_from(STRING_LEAVES))
        own = NOT_THIS_TEXT.get(leaf[-1], ["no such"])  # a choice field: no such choice
        job = replaced(job, leaf, draw(st.one_of(NOT_TEXT, st.sampled_from(own))))
    elif how == "unknown":
        where = draw(st.sampled_from(MAPPINGS))
        job = inside(job, where, draw(st.sampled_from(["colour", "rtols", "From", "x_y"])), "1")
    elif how == "missing":
        job = replaced(job, draw(st.sampled_from(REQUIRED)), None)
    elif how == "key":
        where = draw(st.sampled_from(MAPPINGS))
        key = draw(st.sampled_from(["? [1, 2]\n", "? {a: 1}\n"]))
        text = render(job).encode()
        spoiled = render(inside(job, where, "SPOT", "1")).replace("SPOT: 1", key + ": 1")
        return spoiled.encode() if spoiled.encode() != text else text + b"\n? [1]\n: 2\n"
    text = (render(job) + "\n").encode()
    if how == "bytes":
        at = draw(st.integers(0, len(text)))
        bad = draw(st.sampled_from([b"\xe9", b"\xff\xfe", b"\xc3", b"\x80\x80"]))
        text = text[:at] + bad + text[at:]
    return text


@settings(
    max_examples=320,
    deadline=None,  # wall time depends on the machine's load: the CPU time is checked below
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
    database=None,
)
@given(data=bad_job_files())
def test_every_generated_bad_job_file_is_one_line_and_exit_2(data, capsys):
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        job = folder / "bad.yaml"
        job.write_bytes(data)
        cwd = os.getcwd()
        os.chdir(folder)  # store paths are relative: whatever a run wrote would land here
        try:
            start = time.process_time()  # CPU: a refusal computes nothing, however busy the machine
            code = main(["run", str(job)])
            seconds = time.process_time() - start
        finally:
            os.chdir(cwd)
        err = capsys.readouterr().err
        assert code == 2, (data[:300], err)
        assert err.startswith(f"campar run: job file {job}: ") and err.count("\n") == 1, err
        assert len(err) < 1000, err
        assert seconds < 2.0, (seconds, data[:300])
        assert [p.name for p in folder.iterdir()] == ["bad.yaml"]
