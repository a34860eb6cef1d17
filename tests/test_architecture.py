"""The layering of campar (its subpackages' docstrings, docs/architecture.md) and its import
graph: no cycle, no registration at import, modules of at most 600 lines."""

import ast
import importlib
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "campar"

# Each layer may import the layers listed for it (and itself); nothing else of campar.
LAYERS = {
    "errors": set(),
    "core": {"errors"},
    "model": {"core", "errors"},
    "sweep": {"core", "model", "errors"},
    "continuation": {"core", "model", "sweep", "errors"},
    "views": {"core", "model", "sweep", "continuation", "errors"},
    "paper": {"core", "model", "sweep", "continuation", "views", "errors"},
    "bench": {"core", "model", "sweep", "continuation", "views", "errors"},
    "api": {"core", "model", "sweep", "continuation", "views", "errors"},
    "explore": {"core", "model", "sweep", "continuation", "views", "errors"},
    "cli": {
        "core",
        "model",
        "sweep",
        "continuation",
        "views",
        "paper",
        "bench",
        "api",
        "explore",
        "errors",
        "__init__",
    },
}


def imports_of(path: Path) -> set[str]:
    """Absolute dotted names a module imports (relative imports resolved)."""
    rel = path.relative_to(PACKAGE.parent).with_suffix("")
    package = list(rel.parts[:-1])
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - (node.level - 1)]
                if node.module:
                    found.add(".".join([*base, node.module]))
                else:
                    found.update(".".join([*base, a.name]) for a in node.names)
            elif node.module:
                found.add(node.module)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
    return found


def modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE.parent).with_suffix("")
        yield ".".join(rel.parts).removesuffix(".__init__"), path


MODULES = dict(modules())


def layer(module: str) -> str:
    """campar.core.kernel -> core; campar.cli -> cli; campar -> __init__."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] != "__version__" else "__init__"


def campar_layers(path: Path) -> set[str]:
    return {layer(m) for m in imports_of(path) if m == "campar" or m.startswith("campar.")}


def test_every_module_belongs_to_a_layer():
    assert {layer(m) for m in MODULES} <= {*LAYERS, "__init__"}


def test_imports_point_down_the_layers():
    offending = []
    for name, path in MODULES.items():
        own = layer(name)
        # __init__ (campar's lazy exports) imports by name only; every layer may import
        # campar.__version__ from it
        allowed = {"__init__"} if own == "__init__" else LAYERS[own] | {own, "__init__"}
        if not campar_layers(path) <= allowed:
            offending.append(f"{name} imports {sorted(campar_layers(path) - allowed)}")
    assert not offending, "\n".join(offending)


def test_every_subpackage_says_what_it_holds_and_may_import():
    for sub in (
        "core",
        "model",
        "sweep",
        "continuation",
        "views",
        "paper",
        "bench",
        "explore",
        "cli",
    ):
        doc = ast.get_docstring(ast.parse((PACKAGE / sub / "__init__.py").read_text()))
        assert doc and "import" in doc, sub


def test_the_integrator_knows_no_cam():
    path = MODULES["campar.core.integrator"]
    assert "campar.core.model" not in imports_of(path)
    code = "".join(
        ast.unparse(node)
        for node in ast.parse(path.read_text()).body
        if not isinstance(node, ast.Expr)
    )  # the source without its docstring
    for word in ("omega", "yc", "PHASE", "cam"):
        assert word not in code, word


def test_only_the_wire_imports_mpi4py():
    users = {
        name
        for name, path in MODULES.items()
        if any(m.startswith("mpi4py") for m in imports_of(path))
    }
    assert users == {"campar.sweep.wire"}, users


@pytest.mark.parametrize("package", ["campar.views.plot", "campar.sweep.store"])
def test_plotting_and_the_store_know_nothing_of_integration(package):
    """Of the core they may use its codes only (no numba, no kernel)."""
    for name, path in MODULES.items():
        if name.startswith(package):
            core = {m for m in imports_of(path) if m.startswith("campar.core.")}
            # codes, and the kernel's version number a store records (a constant)
            assert core <= {"campar.core.codes", "campar.core.version"}, (name, core)


def test_modules_stay_small():
    sizes = {name: len(path.read_text().splitlines()) for name, path in MODULES.items()}
    grown = [f"{name}: {lines} lines" for name, lines in sizes.items() if lines > 600]
    assert not grown, "past 600 lines:\n" + "\n".join(grown)


@pytest.mark.process
def test_importing_campar_has_no_side_effects():
    code = (
        "import sys, campar\n"
        "print(sorted(m for m in sys.modules if m.startswith(('campar', 'numba'))))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "['campar']"


def test_lazy_exports_resolve():
    campar = importlib.import_module("campar")
    for name in campar._EXPORTS:
        assert callable(getattr(campar, name))


def imported_modules(name: str, path: Path) -> set[str]:
    """The modules of campar that ``name`` imports, at module level or inside a function:
    ``from .a import b`` is campar's module a.b where that is a module, else a."""
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            base = package[: len(package) - (node.level - 1)] if node.level else []
            module = ".".join([*base, *([node.module] if node.module else [])])
            found.update(
                f"{module}.{a.name}" if f"{module}.{a.name}" in MODULES else module
                for a in node.names
            )
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
    return {m for m in found if m in MODULES and m != name}


def import_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm,
    iterative): every set of modules that import each other round a loop."""
    index, low, on_stack, stack, cycles = {}, {}, set(), [], []
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, edges = work[-1]
            for nxt in edges:
                if nxt not in index:
                    index[nxt] = low[nxt] = len(index)
                    stack.append(nxt)
                    on_stack.add(nxt)
                    work.append((nxt, iter(sorted(graph[nxt]))))
                    break
                if nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.append(member)
                        if member == node:
                            break
                    if len(component) > 1:
                        cycles.append(sorted(component))
    return sorted(cycles)


def test_the_cycle_finder_finds_a_loop_and_only_a_loop():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": {"e"}, "e": set(), "f": {"f"}}
    assert import_cycles(graph) == [["a", "b", "c"]]
    assert import_cycles({"a": {"b"}, "b": {"c"}, "c": set()}) == []


def test_the_import_graph_has_no_cycle_even_through_function_level_imports():
    graph = {name: imported_modules(name, path) for name, path in MODULES.items()}
    assert import_cycles(graph) == []


def test_no_module_registers_itself_into_another_when_imported():
    """A module's top level calls nothing it imported from campar: what a module does is
    called by its caller, never done as a side effect of importing it."""
    for name, path in MODULES.items():
        tree = ast.parse(path.read_text())
        from_campar = {
            alias.asname or alias.name
            for node in tree.body
            if isinstance(node, ast.ImportFrom) and (node.level or node.module.startswith("campar"))
            for alias in node.names
        }
        for node in tree.body:
            if isinstance(node, ast.Expr) and isinstance(node.value, ast.Call):
                callee = node.value.func
                while isinstance(callee, ast.Attribute):
                    callee = callee.value
                assert not (isinstance(callee, ast.Name) and callee.id in from_campar), (
                    f"{name}:{node.lineno} calls {ast.unparse(node.value.func)} when imported"
                )


def test_no_module_takes_names_from_its_own_package_face():
    """A package's __init__ hands names on (some lazily, by importing its modules when
    asked): a module of the package that took names from it would close a loop, hidden
    in that lazy import. The package's own modules import each other directly."""
    for name, path in MODULES.items():
        if path.name in ("__init__.py", "__main__.py") or name.count(".") < 2:
            continue
        package = name.rsplit(".", 1)[0]
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level == 1 and node.module is None:
                names = [a.name for a in node.names if f"{package}.{a.name}" not in MODULES]
                assert not names, f"{name} takes {names} from {package}"


# The layers that compute one cell, a line or a branch from a Model (campar.model): they
# neither reach the sweep's tiles nor build a sweep Job. Readers of a store's own job
# (views.dataset) and the builder of a map's curves job (views.map_curves) name Job.
CELL_LAYERS = ("core", "model", "continuation", "views")
JOB_READERS = {"campar.views.dataset", "campar.views.map_curves"}


@pytest.mark.parametrize("name", [m for m in sorted(MODULES) if layer(m) in CELL_LAYERS])
def test_cells_are_computed_from_a_model_not_through_the_sweep(name):
    imported = imports_of(MODULES[name])
    assert "campar.sweep.tile" not in imported, name
    code = MODULES[name].read_text()
    for builder in ("cell_job(", "Job(", "Job.model_validate(", "point_job(", "line_job("):
        assert builder not in code, (name, builder)
    if name not in JOB_READERS:
        assert "Job.from_dict(" not in code, name


@pytest.mark.process
def test_the_model_layer_loads_no_numba():
    code = (
        "import sys, campar.model\nprint(sorted(m for m in sys.modules if m.startswith('numba')))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_the_sweep_has_no_import_cycle_function_level_imports_included():
    """The model and the sweep's computing modules (the store: its own test)."""
    graph = {
        name: {m for m in imports_of(path) if m in MODULES and m != name}
        for name, path in MODULES.items()
        if layer(name) in ("sweep", "model") and not name.startswith("campar.sweep.store")
    }
    state: dict[str, int] = {}

    def visit(node, path):
        state[node] = 1
        for nxt in graph.get(node, ()):
            if state.get(nxt) == 1:
                raise AssertionError(" → ".join([*path, node, nxt]))
            if nxt not in state:
                visit(nxt, [*path, node])
        state[node] = 2

    for node in graph:
        if node not in state:
            visit(node, [])
