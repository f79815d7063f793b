"""Imports only go down, and no module is too big: the import graph of ``deformctl/``, from ``ast``.

Every ``import`` counts, wherever it stands (a function-level import deferred for start-up time is
still a dependency, and so is one under ``TYPE_CHECKING``). Importing ``deformctl.a.b`` from
outside the package ``deformctl.a`` also runs ``deformctl/a/__init__.py``, so it depends on that
too. The layers are the README's architecture, top to bottom; a module may import its own layer
(no cycle allowed, see below) or any layer below it.
"""

from __future__ import annotations

import ast
import functools
from collections.abc import Iterator
from pathlib import Path

import deformctl

PACKAGE = Path(deformctl.__file__).resolve().parent
ROOT = "deformctl"

#: The layers, top to bottom: each entry is a top-level module or package of ``deformctl/``.
LAYERS: tuple[tuple[str, ...], ...] = (
    # the package's face (its library calls, imported when used) and the command
    ("__init__", "__main__", "cli"),
    ("repro", "testing"),
    # the stages, each one module or package (they may import each other, never in a cycle)
    (
        "population",
        "population_options",
        "measure",
        "characterize",
        "lift",
        "table",
        "train",
        "predict",
        "predict_json",
        "adapt",
        "vision",
    ),
    ("parallel",),
    ("artifacts",),
    ("model", "grip", "catalog", "presets"),
    ("sim",),
    (
        # what measure and characterize share about a squeeze (phase, rupture cut, window, flags)
        "squeeze",
        "version",
        "errors",
        "units",
        "series",
        "scene",
        "physics",
        "signals",
        "plausibility",
        "jsonsafe",
        "resources",
        "samples",
        "quantities",
        "reprs",
        "blas",
        "summary",
        "lazy",
        "arraytypes",
    ),
)

MAX_LINES = 800


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


@functools.cache
def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _is_package(name: str, modules: dict[str, Path]) -> bool:
    return modules[name].name == "__init__.py"


def _imported(node: ast.AST, name: str, modules: dict[str, Path]) -> Iterator[str]:
    """The ``deformctl`` modules an import statement names (``from a import b``: ``a.b`` when it
    is a module, else ``a``)."""
    if isinstance(node, ast.Import):
        for alias in node.names:
            yield alias.name
    elif isinstance(node, ast.ImportFrom):
        if node.level:
            package = name if _is_package(name, modules) else name.rpartition(".")[0]
            for _ in range(node.level - 1):
                package = package.rpartition(".")[0]
            base = f"{package}.{node.module}" if node.module else package
        else:
            base = node.module or ""
        for alias in node.names:
            sub = f"{base}.{alias.name}"
            yield sub if sub in modules else base


@functools.cache
def import_graph() -> dict[str, set[str]]:
    """Module -> the ``deformctl`` modules it imports (and the packages that run on the way)."""
    modules = _modules()
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        edges: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            for target in _imported(node, name, modules):
                if target != ROOT and not target.startswith(ROOT + "."):
                    continue
                while target not in modules:  # ``import deformctl.a.b as x`` of a name
                    target = target.rpartition(".")[0]
                edges.add(target)
                parent = target.rpartition(".")[0]
                while parent != ROOT and parent:  # packages entered from outside run __init__
                    if not (name == parent or name.startswith(parent + ".")):
                        edges.add(parent)
                    parent = parent.rpartition(".")[0]
        edges.discard(name)
        graph[name] = edges
    return graph


def _unit(module: str) -> str:
    """The top-level module or package of ``deformctl/`` a module belongs to."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def _layer(unit: str) -> int:
    for i, layer in enumerate(LAYERS):
        if unit in layer:
            return i
    raise AssertionError(f"deformctl/{unit}: not in any layer of LAYERS; add it to one")


def strongly_connected(graph: dict[str, set[str]]) -> list[set[str]]:
    """Tarjan's strongly connected components with more than one member (the cycles)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[set[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.add(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(component)

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_every_unit_has_a_layer() -> None:
    for module in _modules():
        _layer(_unit(module))


def upward_imports(graph: dict[str, set[str]]) -> list[str]:
    """``module -> target`` for every import of a higher layer."""
    return [
        f"{module} -> {target}"
        for module, targets in sorted(graph.items())
        for target in sorted(targets)
        if _layer(_unit(target)) < _layer(_unit(module))
    ]


def test_imports_only_go_down() -> None:
    upward = upward_imports(import_graph())
    assert not upward, "upward imports (see LAYERS):\n" + "\n".join(upward)


def test_no_import_cycle_between_modules() -> None:
    cycles = strongly_connected(import_graph())
    assert not cycles, "import cycles:\n" + "\n".join(" <-> ".join(sorted(c)) for c in cycles)


def test_no_import_cycle_between_packages() -> None:
    units: dict[str, set[str]] = {}
    for module, targets in import_graph().items():
        edges = units.setdefault(_unit(module), set())
        edges.update(_unit(t) for t in targets if _unit(t) != _unit(module))
    cycles = strongly_connected(units)
    text = "\n".join(" <-> ".join(sorted(c)) for c in cycles)
    assert not cycles, "cycles between packages:\n" + text


def test_the_graph_sees_deferred_imports_and_package_inits() -> None:
    graph = import_graph()
    # a function-level import (deferred for start-up time) is an edge
    assert "deformctl.sim" in graph["deformctl.catalog"]
    # entering a package from outside runs its __init__: an edge to the package too
    assert {"deformctl.artifacts", "deformctl.artifacts.dataset"} <= graph[
        "deformctl.parallel.sweep"
    ]
    # ... but not from inside it (the package is already being imported)
    assert "deformctl.artifacts" not in graph["deformctl.artifacts.mcap.write"]


def test_the_checks_fail_on_an_upward_import_and_a_cycle() -> None:
    fake = {
        "deformctl.artifacts.io": {"deformctl.lift.search"},  # artifacts -> a stage
        "deformctl.lift.search": {"deformctl.lift.stage"},
        "deformctl.lift.stage": {"deformctl.lift.search"},
    }
    assert upward_imports(fake) == ["deformctl.artifacts.io -> deformctl.lift.search"]
    assert strongly_connected(fake) == [{"deformctl.lift.search", "deformctl.lift.stage"}]


def test_no_module_is_too_long() -> None:
    long = [
        f"{path.relative_to(PACKAGE.parent)}: {n} lines"
        for path in _modules().values()
        if (n := len(path.read_text().splitlines())) > MAX_LINES
    ]
    assert not long, f"modules over {MAX_LINES} lines:\n" + "\n".join(long)
