"""Malformed job files: `campar run` names the key and what is allowed, exits 2, writes nothing."""

import pytest

from campar.cli import main
from campar.errors import JobError
from campar.sweep.job import load_job

GOOD_SWEEP = "sweep: {omega: {from: 6, to: 1, points: 4}, mu_cn: {from: 0.9, to: 0.5, points: 3}}"

# (case, file text, what the message must say)
CASES = [
    (
        "unknown key",
        f"name: x\n{GOOD_SWEEP}\nintegrater: {{rtol: 1.0e-9}}\n",
        ["integrater: unknown key; allowed here: name, sweep, fixed"],
    ),
    (
        "unknown nested key",
        f"name: x\n{GOOD_SWEEP}\nintegrator: {{rtols: 1.0e-9}}\n",
        ["integrator.rtols: unknown key; allowed here: method, rtol, atol"],
    ),
    (
        "unknown axis key",
        "name: x\nsweep: {omega: {from: 6, to: 1, step: 1}, "
        "mu_cn: {from: 0.9, to: 0.5, points: 3}}\n",
        ["sweep.omega.step: unknown key; allowed here: from, to, points"],
    ),
    (
        "wrong type",
        f"name: x\n{GOOD_SWEEP}\ntiles: {{rows: many}}\n",
        ["tiles.rows:", "integer", "'many'"],
    ),
    (
        "a section that is not a mapping",
        f"name: x\n{GOOD_SWEEP}\nintegrator: 5\n",
        ["integrator: must be a mapping of keys", "got 5"],
    ),
    (
        "out of range sweep end",
        "name: x\nsweep: {omega: {from: 6, to: 1, points: 4}, "
        "mu_cn: {from: 0.9, to: 1.5, points: 3}}\n",
        ["sweep: mu_cn.to: must be in (0, 1), got 1.5"],
    ),
    (
        "out of range setting",
        f"name: x\n{GOOD_SWEEP}\nintegrator: {{rtol: -1}}\n",
        ["integrator.rtol:", "greater than", "got -1"],
    ),
    (
        "no points",
        "name: x\nsweep: {omega: {from: 6, to: 1, points: 0}, "
        "mu_cn: {from: 0.9, to: 0.5, points: 3}}\n",
        ["sweep.omega.points:", "got 0"],
    ),
    (
        "not a choice",
        f"name: x\n{GOOD_SWEEP}\ntransient: {{mode: forever}}\n",
        ["transient.mode:", "'converged' or 'fixed'", "'forever'"],
    ),
    (
        "unknown output",
        f"name: x\n{GOOD_SWEEP}\noutputs: [label, colour]\n",
        ["outputs: unknown output 'colour'; allowed: label"],
    ),
    ("missing key", "name: x\n", ["sweep: required key is missing"]),
    (
        "omega not first",
        "name: x\nsweep: {mu_cn: {from: 0.9, to: 0.5, points: 3}, "
        "omega: {from: 6, to: 1, points: 4}}\n",
        ["sweep: must list omega", "first"],
    ),
    (
        "swept and fixed",
        f"name: x\n{GOOD_SWEEP}\nfixed: {{mu_cn: 0.5}}\n",
        ["mu_cn is both swept and fixed"],
    ),
    ("not YAML", "name: [x\n", ["not valid YAML", "line"]),
    ("not a mapping", "- name\n- x\n", ["a job is a mapping of keys", "got a list"]),
    ("empty file", "", ["a job is a mapping of keys", "got an empty file"]),
]


@pytest.mark.parametrize("text,expected", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_a_bad_job_file_exits_2_naming_the_key_and_creates_nothing(
    tmp_path, monkeypatch, capsys, text, expected
):
    monkeypatch.chdir(tmp_path)
    job = tmp_path / "bad.yaml"
    job.write_text(text + "store: results/bad.zarr\n" if text.startswith("name") else text)
    assert main(["run", str(job)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"campar run: job file {job}: ")
    for words in expected:
        assert words in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.yaml"]


def test_a_missing_job_file_exits_2(tmp_path, capsys):
    assert main(["run", str(tmp_path / "none.yaml")]) == 2
    assert "cannot read job file" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_a_job_without_a_store_needs_store_and_creates_nothing(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "job.yaml").write_text(f"name: x\n{GOOD_SWEEP}\n")
    assert main(["run", "job.yaml"]) == 2
    assert "--store" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["job.yaml"]


def test_load_job_raises_job_error_with_every_problem(tmp_path):
    path = tmp_path / "two.yaml"
    path.write_text(f"name: x\n{GOOD_SWEEP}\ntiles: {{rows: 0}}\nintegrater: 1\n")
    with pytest.raises(JobError) as err:
        load_job(path)
    assert "tiles.rows" in str(err.value) and "integrater" in str(err.value)
    assert err.value.exit_code == 2


def test_every_job_key_is_documented_in_jobs_readme():
    import typing
    from pathlib import Path

    from pydantic import BaseModel

    from campar.sweep.job import Job

    readme = (Path(__file__).parents[1] / "jobs" / "README.md").read_text()

    def keys(model, prefix=""):
        for name, field in model.model_fields.items():
            key = prefix + (field.alias or name)
            if isinstance(field.annotation, type) and issubclass(field.annotation, BaseModel):
                yield from keys(field.annotation, key + ".")
            elif typing.get_origin(field.annotation) is not dict:
                yield key

    missing = [k for k in keys(Job) if f"`{k}`" not in readme]
    assert not missing, f"jobs/README.md does not document {missing}"


def test_the_defaults_jobs_readme_states_are_the_job_models():
    """Each row `| \\`section.key\\` | default |` of jobs/README.md whose default is one
    number or word states the field's default (a stale row here misled a user before)."""
    import re
    from pathlib import Path

    from campar.sweep.job import Job

    readme = (Path(__file__).parents[1] / "jobs" / "README.md").read_text()
    rows = re.findall(r"^\| `([a-z_]+)\.([a-z_0-9]+)` \| `?([^|`,]+?)`? \|", readme, re.M)
    checked = 0
    for section, key, stated in rows:
        field = Job.model_fields.get(section)
        settings = getattr(field, "default", None) if field else None
        if settings is None or not hasattr(settings, key):
            continue
        value = getattr(settings, key)
        stated = stated.strip().replace(" ", "")
        if isinstance(value, bool):
            assert stated == str(value).lower(), (section, key, stated, value)
        elif isinstance(value, (int, float)):
            assert float(stated) == value, (section, key, stated, value)
        elif isinstance(value, str):
            assert stated == value, (section, key, stated, value)
        else:
            continue
        checked += 1
    assert checked >= 25, checked


# The job files an adversary tried (issue 31): each one line naming the key, exit 2, nothing
# written anywhere. (case, file bytes, words the line must hold)
ALIAS_BOMB = (
    "outputs: [&a0 [x,x,x,x,x,x,x,x,x], "
    + ", ".join(f"&a{i} [" + ",".join([f"*a{i - 1}"] * 9) + "]" for i in range(1, 9))
    + "]\n"
)
HOSTILE = [
    (
        "a billion rows a tile",
        f"name: x\n{GOOD_SWEEP}\ntiles: {{rows: 1000000000}}\n",
        ["tiles.rows:", "100000"],
    ),
    (
        "31-digit rows",
        f"name: x\n{GOOD_SWEEP}\ntiles: {{rows: {'1' * 31}}}\n",
        ["line 3", "31 digits"],
    ),
    (
        "5000-digit integer",
        f"name: x\n{GOOD_SWEEP}\nclassify: {{n_max: {'9' * 5000}}}\n",
        ["5000 digits"],
    ),
    (
        "max_steps beyond 64 bits",
        f"name: x\n{GOOD_SWEEP}\nintegrator: {{max_steps: 100000000000000000000}}\n",
        ["integrator.max_steps:"],
    ),
    ("store /", f"name: x\n{GOOD_SWEEP}\nstore: /\n", ["store:", "names a folder"]),
    ("store ''", f"name: x\n{GOOD_SWEEP}\nstore: ''\n", ["store: an empty path"]),
    ("store ..", f"name: x\n{GOOD_SWEEP}\nstore: ..\n", ["store:", "names a folder"]),
    ("store with NUL", f'name: x\n{GOOD_SWEEP}\nstore: "a\\0b.zarr"\n', ["store:", "NUL"]),
    ("complex key", f"name: x\n{GOOD_SWEEP}\n? [1, 2]\n: 3\n", ["line 3", "a key must be a name"]),
    ("alias bomb", f"name: x\n{GOOD_SWEEP}\n{ALIAS_BOMB}", ["aliases expand to over"]),
    (
        "alias bomb as name",
        "name: " + ALIAS_BOMB.removeprefix("outputs: ") + GOOD_SWEEP + "\n",
        ["aliases expand"],
    ),
    ("recursive alias", f"name: x\n{GOOD_SWEEP}\noutputs: &a [label, *a]\n", ["contains itself"]),
    (
        "basin from NaN",
        "name: x\nsweep: {y0: {from: .nan, to: 1, points: 3}, "
        "ydot0: {from: -1, to: 1, points: 2}}\nfixed: {omega: 3}\n",
        ["sweep.y0.from:", "finite"],
    ),
    (
        "basin to infinity",
        "name: x\nsweep: {y0: {from: 0, to: .inf, points: 3}, "
        "ydot0: {from: -1, to: 1, points: 2}}\nfixed: {omega: 3}\n",
        ["sweep.y0.to:", "finite"],
    ),
    (
        "basin out of range",
        "name: x\nsweep: {y0: {from: 0, to: 1, points: 3}, "
        "ydot0: {from: -1.0e300, to: 1.0e300, points: 2}}\nfixed: {omega: 3}\n",
        ["ydot0.from", "1000"],
    ),
    (
        "points as text",
        "name: x\nsweep: {omega: {from: 6, to: 1, points: '4'}, "
        "mu_cn: {from: 0.9, to: 0.5, points: 3}}\n",
        ["sweep.omega.points:", "not text"],
    ),
    (
        "rtol as text",
        f"name: x\n{GOOD_SWEEP}\nintegrator: {{rtol: '1e-9'}}\n",
        ["integrator.rtol:", "not text"],
    ),
    (
        "a fixed parameter as text",
        f"name: x\n{GOOD_SWEEP}\nfixed: {{zeta: '0.1'}}\n",
        ["fixed:", "not text"],
    ),
    (
        "an empty axis",
        "name: x\nsweep: {omega: {}, mu_cn: {from: 0.9, to: 0.5, points: 3}}\n",
        ["sweep.omega: required keys are missing: from, to, points"],
    ),
    ("YAML syntax", "name: x\nsweep: [\n", ["not valid YAML: line 4, column 1:"]),
    (
        "infinite setting",
        f"name: x\n{GOOD_SWEEP}\ntransient: {{jump_cap: .inf}}\n",
        ["transient.jump_cap:", "finite"],
    ),
]
HOSTILE_BYTES = [
    ("Latin-1", f"name: café\n{GOOD_SWEEP}\n".encode("latin-1"), ["not UTF-8", "0xe9"]),
    ("binary", bytes(range(256)) * 4, ["not UTF-8"]),
    ("NUL bytes", b"name: x\0\0\n", ["not valid YAML"]),
    ("huge", b"name: x\n#" + b"x" * (2 << 20) + b"\n", ["bytes; a job file is at most"]),
]


@pytest.mark.parametrize(
    "data,expected",
    [(c[1].encode(), c[2]) for c in HOSTILE] + [c[1:] for c in HOSTILE_BYTES],
    ids=[c[0] for c in HOSTILE + HOSTILE_BYTES],
)
def test_hostile_job_files_are_one_line_exit_2_and_write_nothing(
    tmp_path, monkeypatch, capsys, data, expected
):
    import time

    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)  # a store path of '' or . would land here
    job = tmp_path / "bad.yaml"
    job.write_bytes(
        data if b"store:" in data or not data.startswith(b"name") else data + b"store: out.zarr\n"
    )
    start = time.process_time()  # CPU: a refusal computes nothing, however busy the machine
    assert main(["run", str(job)]) == 2
    # a few kB parsed: milliseconds; an alias bomb expanded or a 5000-digit integer turned
    # into a number by a quadratic algorithm: minutes
    assert time.process_time() - start < 5
    err = capsys.readouterr().err
    assert err.startswith(f"campar run: job file {job}: ") and err.count("\n") == 1, err
    for words in expected:
        assert words in err, err
    assert list(work.iterdir()) == [] and sorted(p.name for p in tmp_path.iterdir()) == [
        "bad.yaml",
        "work",
    ]


def test_yaml_12_floats_are_numbers_and_quoted_numbers_are_not(tmp_path):
    path = tmp_path / "j.yaml"
    path.write_text(f"name: x\n{GOOD_SWEEP}\nintegrator: {{rtol: 1e-9, atol: 1E-12}}\n")
    job = load_job(path)
    assert job.integrator.rtol == 1e-9 and job.integrator.atol == 1e-12


def test_a_store_path_given_on_the_command_line_is_checked_too(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "job.yaml").write_text(f"name: x\n{GOOD_SWEEP}\nstore: x.zarr\n")
    for bad, words in (("", "an empty path"), ("/", "names a folder"), ("a\0b", "NUL")):
        assert main(["run", "job.yaml", "--store", bad]) == 2
        err = capsys.readouterr().err
        assert words in err and err.count("\n") == 1, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["job.yaml"]


def test_the_memory_estimate_counts_a_tile_chunk_past_the_grid(tmp_path, capsys):
    """rows far beyond the grid's rows: each chunk still spans them (zarr fills a whole
    chunk in memory), so the estimate refuses what would exhaust memory."""
    path = tmp_path / "j.yaml"
    path.write_text(
        f"name: x\n{GOOD_SWEEP}\ntiles: {{rows: 100000}}\n"
        "outputs: [label, sections]\nclassify: {n_max: 256}\n"
        f"store: {tmp_path / 'x.zarr'}\n"
    )
    assert main(["run", str(path), "--max-memory", "1G"]) == 2
    err = capsys.readouterr().err
    assert "each rank would need" in err and err.count("\n") == 1, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["j.yaml"]


@pytest.mark.parametrize("grace", ["nan", "-1", "inf", "soon"])
def test_a_grace_that_is_no_duration_is_refused(tmp_path, capsys, grace):
    (tmp_path / "job.yaml").write_text(f"name: x\n{GOOD_SWEEP}\nstore: {tmp_path / 'x.zarr'}\n")
    with pytest.raises(SystemExit) as exit_:
        main(["run", str(tmp_path / "job.yaml"), "--grace", grace])
    assert exit_.value.code == 2 and "argument --grace" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["job.yaml"]
