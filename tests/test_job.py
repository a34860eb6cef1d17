"""Malformed job files: `campar run` names the key and what is allowed, exits 2, writes nothing."""

import pytest

from campar.cli import main
from campar.errors import JobError
from campar.sweep.job import load_job

GOOD_SWEEP = "sweep: {omega: {from: 6, to: 1, points: 4}, mu_cn: {from: 0.9, to: 0.5, points: 3}}"

# (case, file text, what the message must say)
CASES = [
    ("unknown key", f"name: x\n{GOOD_SWEEP}\nintegrater: {{rtol: 1.0e-9}}\n",
     ["integrater: unknown key; allowed here: name, sweep, fixed"]),
    ("unknown nested key", f"name: x\n{GOOD_SWEEP}\nintegrator: {{rtols: 1.0e-9}}\n",
     ["integrator.rtols: unknown key; allowed here: method, rtol, atol"]),
    ("unknown axis key", "name: x\nsweep: {omega: {from: 6, to: 1, step: 1}, "
     "mu_cn: {from: 0.9, to: 0.5, points: 3}}\n",
     ["sweep.omega.step: unknown key; allowed here: from, to, points"]),
    ("wrong type", f"name: x\n{GOOD_SWEEP}\ntiles: {{rows: many}}\n",
     ["tiles.rows:", "integer", "'many'"]),
    ("a section that is not a mapping", f"name: x\n{GOOD_SWEEP}\nintegrator: 5\n",
     ["integrator: must be a mapping of keys", "got 5"]),
    ("out of range sweep end",
     "name: x\nsweep: {omega: {from: 6, to: 1, points: 4}, "
     "mu_cn: {from: 0.9, to: 1.5, points: 3}}\n",
     ["sweep: mu_cn.to: must be in (0, 1), got 1.5"]),
    ("out of range setting", f"name: x\n{GOOD_SWEEP}\nintegrator: {{rtol: -1}}\n",
     ["integrator.rtol:", "greater than", "got -1"]),
    ("no points", "name: x\nsweep: {omega: {from: 6, to: 1, points: 0}, "
     "mu_cn: {from: 0.9, to: 0.5, points: 3}}\n", ["sweep.omega.points:", "got 0"]),
    ("not a choice", f"name: x\n{GOOD_SWEEP}\ntransient: {{mode: forever}}\n",
     ["transient.mode:", "'converged' or 'fixed'", "'forever'"]),
    ("unknown output", f"name: x\n{GOOD_SWEEP}\noutputs: [label, colour]\n",
     ["outputs: unknown output 'colour'; allowed: label"]),
    ("missing key", "name: x\n", ["sweep: required key is missing"]),
    ("omega not first",
     "name: x\nsweep: {mu_cn: {from: 0.9, to: 0.5, points: 3}, "
     "omega: {from: 6, to: 1, points: 4}}\n",
     ["sweep: must list omega", "first"]),
    ("swept and fixed", f"name: x\n{GOOD_SWEEP}\nfixed: {{mu_cn: 0.5}}\n",
     ["mu_cn is both swept and fixed"]),
    ("not YAML", "name: [x\n", ["not valid YAML", "line"]),
    ("not a mapping", "- name\n- x\n", ["a job is a mapping of keys", "got a list"]),
    ("empty file", "", ["a job is a mapping of keys", "got an empty file"]),
]  # fmt: skip


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
