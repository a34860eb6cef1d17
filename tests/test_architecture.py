"""The dependency rules of DESIGN.md / STYLE.md, checked on the import graph."""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "campar"
LEAVES = {"status", "hermite", "jit", "errors"}  # constants and tiny shared helpers


def campar_imports(path: Path) -> set[str]:
    """campar modules (top-level names) and third-party roots a module imports."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:  # relative: from . import x / from .x import y
                if node.module:
                    found.add("campar." + node.module.split(".")[0])
                else:
                    found.update("campar." + a.name for a in node.names)
            elif node.module:
                found.add(node.module.split(".")[0])
        elif isinstance(node, ast.Import):
            found.update(a.name.split(".")[0] for a in node.names)
    return found


def modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE).with_suffix("")
        yield ".".join(rel.parts), path


MODULES = dict(modules())


@pytest.mark.parametrize("name", ["model", "integrator", "analysis", "hermite", "status", "jit"])
def test_numerical_core_imports_only_leaves(name):
    inside = {m.removeprefix("campar.") for m in campar_imports(MODULES[name]) if "campar." in m}
    assert inside <= LEAVES, f"{name} imports {inside - LEAVES}"


def test_integrator_knows_no_cam():
    text = MODULES["integrator"].read_text()
    assert "cam" not in campar_imports(MODULES["integrator"])
    for word in ("omega", "yc", "PHASE"):
        assert word not in text


def test_only_the_runner_imports_mpi4py():
    users = {name for name, path in MODULES.items() if "mpi4py" in campar_imports(path)}
    assert users <= {"runner"}, users


def test_plotting_never_imports_the_integrator():
    for name, path in MODULES.items():
        if name.startswith("plot"):
            imports = campar_imports(path)
            assert not imports & {"campar.integrator", "campar.kernel"}, name


def test_store_knows_nothing_of_integration():
    for name, path in MODULES.items():
        if name.startswith("store"):
            imports = campar_imports(path)
            assert not imports & {"campar.integrator", "campar.kernel", "campar.model"}, name


def test_modules_stay_small():
    for name, path in MODULES.items():
        assert len(path.read_text().splitlines()) <= 600, f"{name} has grown past 600 lines"
