"""The documentation is true: the site builds without a warning, every docstring example
of the API reference runs and prints what it shows, every `campar` command in README.md
and docs/ is one the CLI accepts, and the commands shown with their output print it."""

import contextlib
import doctest
import importlib
import os
import re
import shlex
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
from support.cli import call_campar

from campar.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PAGES = [
    ROOT / "README.md",
    ROOT / "jobs" / "README.md",
    ROOT / "slurm" / "README.md",
    ROOT / "benchmarks" / "RESULTS.md",
    *sorted(DOCS.rglob("*.md")),
]


def api_objects() -> list[str]:
    """Every object the API reference documents (docs/api.md's autodoc directives)."""
    text = (DOCS / "api.md").read_text()
    return re.findall(r"^\.\. auto(?:function|class):: (\S+)$", text, re.M)


def resolve(dotted: str):
    module, _, name = dotted.rpartition(".")
    return getattr(importlib.import_module(module), name)


@pytest.fixture(scope="module")
def example_dir(tmp_path_factory):
    """A working directory as the examples assume: the jobs, and the smoke map computed."""
    where = tmp_path_factory.mktemp("examples")
    (where / "jobs").symlink_to(ROOT / "jobs")
    with contextlib.chdir(where):
        run = call_campar(None, "run", "jobs/smoke.yaml")
    assert run.returncode == 0, run.stderr
    return where


@pytest.mark.parametrize("dotted", api_objects())
def test_every_api_example_runs_and_prints_what_it_shows(dotted, example_dir, monkeypatch):
    obj = resolve(dotted)
    assert re.search(r"\n\s*Examples\n\s*-{8}\n", obj.__doc__ or ""), f"{dotted}: no Examples"
    monkeypatch.chdir(example_dir)
    tests = doctest.DocTestFinder(recurse=False).find(obj, dotted, globs={})
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for test in tests:
        runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.attempted > 0 and result.failed == 0, f"{dotted}: {result}"


def code_blocks(page: Path):
    """Each code block of the page (fenced or indented): a list of (line number, text)."""
    blocks, block, fenced = [], [], False
    for number, line in enumerate(page.read_text().splitlines(), 1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
        elif fenced or line.startswith("    "):
            block.append((number, line.strip()))
            continue
        if block:
            blocks.append(block)
            block = []
    return [*blocks, block] if block else blocks


def shell_commands(block):
    """(line number, command) of a code block. Where the block shows a session (`$ `
    lines), only those are commands, and one shown refused (its output says error) is
    the error being shown, not a command to accept."""
    if not any(text.startswith("$ ") for _, text in block):
        return list(block)
    commands = []
    for i, (number, text) in enumerate(block):
        if not text.startswith("$ "):
            continue
        output = []
        for _, after in block[i + 1 :]:
            if after.startswith("$ "):
                break
            output.append(after)
        if not any("error" in line for line in output):
            commands.append((number, text[2:]))
    return commands


def campar_commands(page: Path):
    """(line number, argv after `campar`) of every campar command in the page's code."""
    for block in code_blocks(page):
        for number, line in shell_commands(block):
            line = re.sub(r"^(?:\.venv/bin/)?mpirun -n \d+ ", "", line)
            line = re.sub(r"^\S*/bin/", "", line)  # .venv/bin/campar
            if line.startswith("campar "):
                yield number, shlex.split(line, comments=True)[1:]


def all_commands():
    return [(page, number, argv) for page in PAGES for number, argv in campar_commands(page)]


@pytest.mark.parametrize(
    ("page", "number", "argv"),
    all_commands(),
    ids=lambda v: str(v.relative_to(ROOT)) if isinstance(v, Path) else None,
)
def test_every_campar_command_in_the_docs_is_one_the_cli_accepts(page, number, argv):
    parser = build_parser()
    try:
        parser.parse_args(argv)
    except SystemExit as exc:
        pytest.fail(f"{page.relative_to(ROOT)}:{number}: campar {shlex.join(argv)}: exit {exc}")
    for word in argv:  # the job files it names exist
        if word.startswith("jobs/") and word.endswith(".yaml"):
            assert (ROOT / word).is_file(), f"{page.relative_to(ROOT)}:{number}: no {word}"


def shown_outputs():
    """(page, command, output lines) of every `$ campar point …` shown with its output."""
    found = []
    for page in PAGES:
        lines = page.read_text().splitlines()
        for i, line in enumerate(lines):
            if line.startswith("$ campar point"):
                shown = []
                for after in lines[i + 1 :]:
                    if after.startswith(("$ ", "```")):
                        break
                    shown.append(after)
                if shown:
                    found.append((page, line[2:], shown))
    return found


@pytest.mark.parametrize(("page", "command", "shown"), shown_outputs(), ids=str)
def test_a_command_shown_with_its_output_prints_it(capsys, page, command, shown):
    out = call_campar(capsys, *shlex.split(command)[1:])
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines() == shown, page


def test_the_readme_is_short_and_its_links_hold():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 120
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if target.startswith("http"):
            continue
        path, _, anchor = target.partition("#")
        assert (ROOT / path).exists(), target
        if anchor:
            assert anchor in markdown_anchors(ROOT / path), target


def markdown_anchors(page: Path) -> set[str]:
    """The anchors GitHub and MyST give a page's headings."""
    anchors = set()
    for heading in re.findall(r"^#+ (.+)$", page.read_text(), re.M):
        slug = re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")
        anchors.add(slug)
    return anchors


def test_the_version_follows_the_changelog():
    import campar

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    released = re.findall(r"^## \[(\d+\.\d+\.\d+)\]", (ROOT / "CHANGELOG.md").read_text(), re.M)
    assert released and project["version"] == campar.__version__ == released[0]


@pytest.mark.slow
@pytest.mark.process
@pytest.mark.timeout(900)  # sphinx builds the whole site, every API page
def test_the_site_builds_without_a_warning(tmp_path):
    sphinx = Path(sys.executable).parent / "sphinx-build"
    run = subprocess.run(
        [str(sphinx), "-W", "--keep-going", "-q", "-b", "html", str(DOCS), str(tmp_path / "html")],
        text=True,
        capture_output=True,
        timeout=900,
        env={**os.environ, "PYTHONWARNINGS": "ignore"},
    )
    assert run.returncode == 0, run.stderr[-5000:]


@pytest.mark.process
def test_the_readme_tour_runs_as_shown(example_dir):
    """The tour after its first command (shown with its output above): the map exists (the
    fixture ran `campar run jobs/smoke.yaml` there), its plot is drawn, and the Python line
    prints what the README shows."""
    lines = (ROOT / "README.md").read_text().splitlines()
    start = lines.index("$ campar run jobs/smoke.yaml")
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    i = start + 1
    while lines[i] != "```":
        command, shown = lines[i].removeprefix("$ "), []
        i += 1
        while lines[i] != "```" and not lines[i].startswith("$ "):
            shown.append(lines[i])
            i += 1
        run = subprocess.run(
            command,
            shell=True,
            cwd=example_dir,
            env=env,
            text=True,
            capture_output=True,
            timeout=300,
        )
        assert run.returncode == 0, f"{command}: {run.stderr}"
        assert run.stdout.splitlines() == shown, command
    assert (example_dir / "smoke.png").stat().st_size > 0
