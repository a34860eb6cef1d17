"""The model layer (campar.model): one Model from each entry — a job's sections, a command's
flags, --set, Python keywords — and one message for one bad value whatever the entry."""

import math

import pytest
import yaml
from support.jobs import plane_job

import campar.cli
import campar.views.point
from campar.errors import JobError
from campar.model import FIELDS, Model
from campar.model.sections import PAPER_VALUES
from campar.sweep.job import MODEL_SECTIONS, Job, cell_job, load_job

# One non-default value of every key of the model, as a job file writes it (its flag takes
# the same text): each key is checked to reach the model from every entry.
VALUES = {
    "model.tensile": "allow",
    "model.duty_cycle": "force",
    "model.cam_velocity": "literal",
    "model.cam.rise": "cycloidal",
    "model.cam.fall": "modified-sine",
    "model.cam.phi1": 1.2,
    "model.cam.phi2": math.pi - 1.2,  # rise and far dwell still span π
    "model.cam.phi3": 1.0,
    "model.cam.phi4": math.pi - 1.0,
    "model.contact.law": "flores",
    "model.contact.n": 1.1,
    "model.contact.restitution": 0.7,
    "model.contact.impact_floor": 0.002,
    "initial.y": 0.25,
    "initial.v": -0.5,
    "integrator.method": "dp54",
    "integrator.rtol": 1e-8,
    "integrator.atol": 1e-11,
    "integrator.rk4_steps": 1200,
    "integrator.event_tol": 1e-11,
    "integrator.max_steps": 2_000_000,
    "transient.mode": "fixed",
    "transient.max_revolutions": 300,
    "transient.newton": False,
    "transient.jump_cap": 0.05,
    "transient.jump_residual": 1e-4,
    "transient.max_jumps": 10,
    "transient.jump_agree": 0.2,
    "transient.conv_tol": 1e-9,
    "transient.window_tol": 1e-7,
    "transient.extrapolate": 1,
    "transient.chaos_after": 50,
    "transient.chaos_lyapunov": 0.2,
    "transient.chaos_confidence": 0.95,
    "transient.chaos_clear": 32,
    "transient.chaos_sight": 0.1,
    "transient.quasiperiodic_after": 40,
    "classify.n_max": 16,
    "classify.chatter_p": 5,
    "classify.window_revolutions": 32,
    "classify.period_tol": 1e-7,
    "classify.lyap_tol": 0.02,
    "classify.sections": 20,
}
PARAMETERS = {"omega": 2.5, "f0": 0.4, "mu_kn": 0.91, "mu_cn": 0.75, "zeta": 0.1}
# Bad values and the message every entry gives for them.
BAD = [
    ("model.cam.rise", "bad", "model.cam.rise: Input should be 'cosine'"),
    ("integrator.rtol", 2.0, "integrator.rtol: Input should be less than 1"),
    ("classify.n_max", 10**9, "classify.n_max: Input should be less than or equal to 256"),
    ("transient.newton", 3, "transient.newton: Input should be a valid boolean"),
]


TABLE_KEYS = ("model.cam.table", "model.cam.table_joins")  # a cam table: its own test


def test_every_key_of_the_model_is_listed_here():
    assert set(VALUES) | set(TABLE_KEYS) == set(FIELDS)
    model_keys = {"omega", "f0", "mu_kn", "mu_cn", "zeta", *MODEL_SECTIONS}
    assert set(Model.model_fields) == model_keys


def nested(values: dict) -> dict:
    data: dict = {}
    for key, value in values.items():
        node = data
        *parents, last = key.split(".")
        for part in parents:
            node = node.setdefault(part, {})
        node[last] = value
    return data


@pytest.fixture(scope="module")
def job_file(tmp_path_factory):
    """A job file stating every key of the model (a basin: every parameter fixed)."""
    path = tmp_path_factory.mktemp("model") / "every_key.yaml"
    data = nested({k: v for k, v in VALUES.items() if not k.startswith("initial.")})
    data.update(
        name="every_key",
        sweep={
            "y0": {"from": -0.5, "to": 0.5, "points": 2},
            "ydot0": {"from": 0, "to": 1, "points": 2},
        },
        fixed=PARAMETERS,
    )
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def expected() -> Model:
    return Model.model_validate({**PARAMETERS, **nested(VALUES)})


def test_python_keywords_by_name_and_by_key_give_the_model():
    by_name = Model.build(**PARAMETERS, **{FIELDS[k].name: v for k, v in VALUES.items()})
    by_key = Model.build(**PARAMETERS, **VALUES)
    assert by_name == by_key == expected()
    for key, value in VALUES.items():  # each key reached, not left at its default
        assert by_name.value(key) == value != FIELDS[key].default


def test_a_job_file_gives_the_model(job_file):
    job = load_job(job_file)
    model = job.model_at(0.25, -0.5)  # the basin cell whose start is initial (y, v)
    assert model == expected()


def test_command_line_flags_give_the_model(monkeypatch):
    seen = {}
    monkeypatch.setattr(
        campar.views.point, "simulate_point", lambda m, **kw: seen.setdefault("m", m) and stop()
    )
    argv = ["point", *flags(PARAMETERS)]
    for key, value in VALUES.items():
        argv += [FIELDS[key].flag, yaml_text(value)]
    with pytest.raises(Stop):
        campar.cli.main(argv)
    assert seen["m"] == expected()


def test_set_and_job_give_the_model(monkeypatch, job_file):
    seen = {}
    monkeypatch.setattr(
        campar.views.point, "simulate_point", lambda m, **kw: seen.setdefault("m", m) and stop()
    )
    sets = [arg for key, value in VALUES.items() for arg in ("--set", f"{key}={yaml_text(value)}")]
    with pytest.raises(Stop):
        campar.cli.main(["point", *flags(PARAMETERS), *sets])
    assert seen.pop("m") == expected()
    start = ["--y0", "0.25", "--v0", "-0.5"]
    with pytest.raises(Stop):
        campar.cli.main(["point", "--omega", "2.5", "--job", str(job_file), *start])
    assert seen.pop("m") == expected()


@pytest.mark.parametrize("key, bad, message", BAD)
def test_one_message_for_a_bad_value_from_every_entry(key, bad, message, capsys, tmp_path):
    with pytest.raises(JobError) as python:
        Model.build(omega=3.0, **{FIELDS[key].name: bad})
    assert str(python.value).startswith(message)
    assert campar.cli.main(["point", "--omega", "3", FIELDS[key].flag, yaml_text(bad)]) == 2
    assert capsys.readouterr().err.strip() == f"campar point: {python.value}"
    assert campar.cli.main(["point", "--omega", "3", "--set", f"{key}={yaml_text(bad)}"]) == 2
    assert capsys.readouterr().err.strip() == f"campar point: {python.value}"
    path = tmp_path / "bad.yaml"
    data = nested({key: bad})
    data.update(
        name="bad",
        sweep={
            "omega": {"from": 3, "to": 2, "points": 2},
            "mu_cn": {"from": 0.8, "to": 0.7, "points": 2},
        },
    )
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    with pytest.raises(JobError) as job:
        load_job(path)
    assert f"job file {path}: {python.value}" == str(job.value)


@pytest.mark.parametrize(
    "argv, message",
    [
        (
            ["--cycle", "1", "--y0", "nan", "--omega", "3"],
            "initial.y: Input should be a finite number",
        ),
        (["--omega", "1e308"], "omega must be ≤ 100, got 1e+308"),
        (["--omega", "3", "--mu-kn", "nan"], "mu_kn: Input should be a finite number, got nan"),
        (["--omega", "3", "--cycle", "1000000000"], "--cycle must be an integer from 1 to 256"),
        (["--omega", "3", "--attractors", "1000000000"], "--attractors must be an integer from 2"),
        (
            ["--omega", "3", "--set", "sweep.omega.points=3"],
            "sweep.omega.points: not a key of the model",
        ),
    ],
)
def test_bad_input_is_one_line_exit_2_before_computing(argv, message, capsys, monkeypatch):
    monkeypatch.setattr(campar.views.point, "simulate_point", lambda *a, **k: stop())
    assert campar.cli.main(["point", *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_a_misspelled_word_names_the_one_meant_from_every_entry(capsys):
    with pytest.raises(JobError) as python:
        Model.build(omega=1.0, tensile="alow")
    assert str(python.value).endswith("got 'alow' (did you mean allow?)")
    for argv in (["--tensile", "alow"], ["--set", "model.tensile=alow"]):
        assert campar.cli.main(["point", "--omega", "1", *argv]) == 2
        assert capsys.readouterr().err == f"campar point: {python.value}\n"


def test_the_same_value_in_python_and_in_a_job_gives_the_same_error(tmp_path):
    with pytest.raises(JobError) as python:
        Model.build(omega=3.0, mu_kn=2.0)
    with pytest.raises(JobError) as job:
        Job.from_dict(
            {
                "name": "x",
                "sweep": {
                    "omega": {"from": 3, "to": 2, "points": 2},
                    "mu_cn": {"from": 0.8, "to": 0.7, "points": 2},
                },
                "fixed": {"mu_kn": 2.0},
            }
        )
    assert str(python.value) == "mu_kn must be in (0, 1), got 2.0"
    assert str(python.value) in str(job.value)


def test_a_cam_table_from_every_entry(tmp_path, monkeypatch):
    table = tmp_path / "cam.csv"
    theta = [2 * math.pi * i / 64 for i in range(64)]
    table.write_text("".join(f"{t!r}, {0.5 - 0.5 * math.cos(t)!r}\n" for t in theta))
    python = Model.build(omega=3.0, table=str(table), table_joins="smooth")
    assert python.model.cam.table == str(table) and len(python.model.cam.table_sha256) == 64
    seen = {}
    monkeypatch.setattr(
        campar.views.point, "simulate_point", lambda m, **kw: seen.setdefault("m", m) and stop()
    )
    with pytest.raises(Stop):
        campar.cli.main(["point", "--omega", "3", "--table", str(table), "--table-joins", "smooth"])
    assert seen.pop("m") == python
    with pytest.raises(Stop):
        campar.cli.main(["point", "--omega", "3", "--set", f"model.cam.table={table}"])
    assert seen.pop("m") == python
    with pytest.raises(JobError, match="model.cam: a cam is either a table or rise/fall laws"):
        python.replace(rise="cycloidal")


def test_replace_changes_one_key_and_validates():
    base = Model.build(omega=3.0, rise="cycloidal")
    assert base.replace(mu_kn=0.9).model == base.model
    assert base.replace(mu_kn=0.9).mu_kn == 0.9 and base.mu_kn == PAPER_VALUES["mu_kn"]
    with pytest.raises(JobError, match=r"model.cam: phi1 \(rise\) must be > 0, got -1$"):
        base.replace(phi1=-1.0)


def test_a_cell_job_holds_the_model_and_its_digest_is_that_of_a_job_file():
    model = Model.build(omega=2.0, mu_kn=0.9)
    job = cell_job(model)
    assert job.cell_model(0, 0) == model
    fixed = {"mu_kn": 0.9, "mu_cn": 0.8, "zeta": 0.2}
    same = Job.from_dict(plane_job("cell", (2.0, 2.0, 1), ("f0", 0.5, 0.5, 1), fixed=fixed))
    assert job.digest() == same.digest()


def test_every_model_key_is_a_flag_of_every_command_that_computes_a_cell(capsys):
    for command in ("point", "line", "continue"):
        with pytest.raises(SystemExit):
            campar.cli.main([command, "--help"])
        text = capsys.readouterr().out
        for field in FIELDS.values():
            assert field.flag in text, (command, field.flag)
        assert "--set" in text and "--job" in text


class Stop(Exception):
    pass


def stop():
    raise Stop


def flags(parameters: dict) -> list[str]:
    return [
        arg for name, v in parameters.items() for arg in (f"--{name.replace('_', '-')}", repr(v))
    ]


def yaml_text(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    return str(value)
