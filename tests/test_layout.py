"""The layout's rules, checked: where things live, how large the commands are, what imports what."""

from __future__ import annotations

import ast
import dataclasses
import inspect
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path

import pytest

import deformctl
from deformctl.cli import COMMANDS
from deformctl.cli._options import HEAVY_DEFAULTS

PACKAGE = Path(deformctl.__file__).resolve().parent
TESTS = Path(__file__).resolve().parent
#: The test modules that stay at the top of tests/: each tests the project as a whole.
PROJECT_WIDE = {
    "test_api.py": "the public API (deformctl/__init__.py) against every command's defaults",
    "test_assertions.py": "every test module of the suite asserts something",
    "test_docs.py": "every shell block of README.md and docs/ runs; the CLI reference is current",
    "test_imports.py": "the import graph and the module sizes of the whole package",
    "test_layout.py": "where things live, in deformctl/ and in tests/",
    "test_wheel.py": "the built wheel, installed and run without the checkout",
}
#: Test folders that mirror no module: hostile inputs sent through every command and reader.
CROSS_CUTTING = {"fuzz": "hostile and property-based inputs across commands and readers"}
#: Catalog columns no other table has: only deformctl/catalog.py names them.
CATALOG_ONLY = {
    "size_x_cm",
    "size_y_cm",
    "size_z_cm",
    "material_stiffness_n_per_cm",
    "material_damping_ns_per_cm",
}


def _sources() -> list[Path]:
    return sorted(PACKAGE.rglob("*.py"))


#: The most parameters a function of the package takes (``self`` and ``cls`` not counted): more
#: is a bundle of options that belongs in an options type.
MAX_PARAMETERS = 15


def parameter_counts(tree: ast.AST) -> dict[str, int]:
    """Each function's parameters (positional, keyword-only, ``*args``, ``**kwargs``), by name."""
    counts = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            a = node.args
            names = [p.arg for p in (*a.posonlyargs, *a.args, *a.kwonlyargs)]
            names += [p.arg for p in (a.vararg, a.kwarg) if p is not None]
            counts[f"{node.name}:{node.lineno}"] = len(names) - (names[:1] in (["self"], ["cls"]))
    return counts


def test_parameter_counts_are_counted() -> None:
    tree = ast.parse("def f(a, /, b, *c, d, **e): ...\nclass C:\n    def m(self, x): ...")
    assert parameter_counts(tree) == {"f:1": 5, "m:3": 1}


def test_no_function_takes_more_than_fifteen_parameters() -> None:
    wide = {
        f"{path.relative_to(PACKAGE)}:{name}": n
        for path in _sources()
        for name, n in parameter_counts(ast.parse(path.read_text())).items()
        if n > MAX_PARAMETERS
    }
    assert not wide, wide


def test_restated_heavy_defaults_are_the_librarys() -> None:
    from deformctl.measure.sim import simulate_squeezes
    from deformctl.sim import LiftProfile, SimSettings, SlipCriterion
    from deformctl.vision import detect_slip, measure_object_size

    objects = {"SimSettings": SimSettings(), "LiftProfile": LiftProfile()}
    objects["SlipCriterion"] = SlipCriterion()
    for name, value in HEAVY_DEFAULTS.items():
        owner, field = name.split(".")
        if owner in objects:
            assert dataclasses.asdict(objects[owner])[field] == value, name  # type: ignore[call-overload]
        else:
            function = {"detect_slip": detect_slip, "measure_object_size": measure_object_size,
                        "simulate_squeezes": simulate_squeezes}  # fmt: skip
            assert inspect.signature(function[owner]).parameters[field].default == value, name


def test_cli_modules_and_command_bodies_stay_small() -> None:
    for path in sorted((PACKAGE / "cli").glob("*.py")):
        assert len(path.read_text().splitlines()) <= 250, path.name
    for command in COMMANDS:
        tree = ast.parse(Path(inspect.getfile(inspect.unwrap(command))).read_text())
        fn = next(
            n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == command.__name__
        )
        body = fn.body[1:] if ast.get_docstring(fn) else fn.body
        assert body[-1].end_lineno - body[0].lineno + 1 <= 60, command.__name__  # type: ignore[operator]


def test_bundled_data_is_found_through_the_package_not_the_checkout() -> None:
    for path in _sources():
        text = path.read_text()
        assert "parents[1]" not in text, path
        assert "parent.parent" not in text, path


def test_only_the_catalog_module_names_catalog_columns() -> None:
    for path in _sources():
        if path.name == "catalog.py" and path.parent == PACKAGE:
            continue
        tree = ast.parse(path.read_text())
        docstrings = {
            id(node.body[0].value)
            for node in ast.walk(tree)
            if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef)
            and node.body
            and isinstance(node.body[0], ast.Expr)
            and isinstance(node.body[0].value, ast.Constant)
        }
        named = {
            node.value
            for node in ast.walk(tree)
            if isinstance(node, ast.Constant) and id(node) not in docstrings
        }
        assert not named & CATALOG_ONLY, (path, named & CATALOG_ONLY)


@pytest.mark.parametrize(
    "module",
    [
        "deformctl.parallel",
        "deformctl.artifacts",
        "deformctl.artifacts.mcap",
        "deformctl.artifacts.mcap.write",
        "deformctl.characterize",
        "deformctl.squeeze.rupture",
        "deformctl.lift",
        "deformctl.lift.stage",
        "deformctl.lift.runners.sim",
        "deformctl.catalog",
        "deformctl.measure",
        "deformctl.measure.csv",
        "deformctl.model",
        "deformctl.repro.golden",
    ],
)
def test_every_entry_module_imports_first(module: str) -> None:
    # a fresh interpreter per module: an import cycle shows up only for some import orders
    subprocess.run([sys.executable, "-c", f"import {module}"], check=True, capture_output=True)


def test_make_examples_runs_every_example() -> None:
    makefile = (PACKAGE.parent / "Makefile").read_text()
    recipe = makefile.split("\nexamples: install\n", 1)[1].split("\n\n", 1)[0]
    for example in sorted((PACKAGE.parent / "examples").glob("[!_]*.py")):
        assert f"examples/{example.name}" in recipe, example.name


def layout_problems(files: Mapping[str, str], source: set[str]) -> list[str]:
    """What breaks the tests' layout, one line each.

    ``files`` maps each Python file under ``tests/`` (its path there, ``cli/test_lift.py``) to its
    text, ``source`` holds the paths of the package's files under ``deformctl/``. The rules:

    * a test module at the top of ``tests/`` is one of :data:`PROJECT_WIDE`;
    * any other sits in ``tests/<package>/...``, mirroring a package or module of ``deformctl/``
      (``tests/lift/`` for ``deformctl/lift/``, ``tests/table/`` for ``deformctl/table.py``,
      ``tests/lift/runners/`` for ``deformctl/lift/runners/``), or in a :data:`CROSS_CUTTING`
      folder;
    * every folder from ``tests/`` down to a test module has an ``__init__.py``, so two test
      modules of the same name in two folders are two modules;
    * no file imports a test module (shared code lives in ``tests/_helpers/``, fixtures in
      ``tests/conftest.py``);
    * every package of ``deformctl/`` has a test folder, and so has every top-level module
      (``tests/units/`` for ``deformctl/units.py``; not ``__init__.py`` nor ``__main__.py``).
    """
    problems = []
    tested: set[str] = set()
    for name, text in sorted(files.items()):
        path = Path(name)
        folders = path.parent.parts
        if path.name.startswith("test_"):
            if not folders and path.name not in PROJECT_WIDE:
                problems.append(f"{name}: a top-level test module outside PROJECT_WIDE")
            elif folders and folders[0] not in CROSS_CUTTING:
                mirrored = "/".join(folders)
                if f"{mirrored}/__init__.py" not in source and f"{mirrored}.py" not in source:
                    problems.append(f"{name}: deformctl/ has no {mirrored}/ nor {mirrored}.py")
            tested.add(folders[0] if folders else "")
            for k in range(len(folders) + 1):
                init = "/".join([*folders[:k], "__init__.py"])
                if init not in files:
                    problems.append(f"{name}: no {init}")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.Import):
                modules = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                modules = [node.module or ""] + [alias.name for alias in node.names]
            else:
                continue
            if any(part.startswith("test_") for m in modules for part in m.split(".")):
                problems.append(f"{name}:{node.lineno}: imports a test module")
    packages = {Path(p).parts[0] for p in source if len(Path(p).parts) == 2}
    problems += [f"deformctl/{p}/ has no tests/{p}/" for p in sorted(packages - tested)]
    modules = {
        Path(p).stem
        for p in source
        if len(Path(p).parts) == 1 and p.endswith(".py") and p not in ("__init__.py", "__main__.py")
    }
    problems += [f"deformctl/{m}.py has no tests/{m}/" for m in sorted(modules - tested)]
    return sorted(set(problems))


def _tree(root: Path) -> dict[str, str]:
    return {
        p.relative_to(root).as_posix(): p.read_text(encoding="utf-8")
        for p in sorted(root.rglob("*.py"))
        if "__pycache__" not in p.parts
    }


def test_tests_mirror_the_source() -> None:
    files = _tree(TESTS)
    assert not layout_problems(files, set(_tree(PACKAGE)))
    assert sum(Path(name).name.startswith("test_") for name in files) > 100  # the walk found them


def test_the_layout_check_finds_each_misplaced_test() -> None:
    source = {"__init__.py", "__main__.py", "table.py", "lift/__init__.py",
              "lift/runners/__init__.py"}  # fmt: skip
    good = {
        "__init__.py": "",
        "test_docs.py": "",
        "_helpers/__init__.py": "",
        "_helpers/bags.py": "def write_bag():\n    pass\n",
        "table/__init__.py": "",
        "table/test_table.py": "from tests._helpers.bags import write_bag\n",
        "lift/__init__.py": "",
        "lift/test_search.py": "from ._threshold import ThresholdRunner\n",
        "lift/runners/__init__.py": "",
        "lift/runners/test_rig.py": "",
        "fuzz/__init__.py": "",
        "fuzz/test_hostile.py": "",
    }
    assert layout_problems(good, source) == []
    bad = {
        **good,
        "test_table.py": "",
        "tabel/__init__.py": "",
        "tabel/test_lookup.py": "",
        "lift/runners/test_sim.py": "from tests.lift.test_search import helper\n",
        "table/test_guards.py": "import test_table\nfrom . import test_table as t\n",
    }
    del bad["lift/runners/__init__.py"]
    assert layout_problems(bad, source) == [
        "lift/runners/test_rig.py: no lift/runners/__init__.py",
        "lift/runners/test_sim.py: no lift/runners/__init__.py",
        "lift/runners/test_sim.py:1: imports a test module",
        "tabel/test_lookup.py: deformctl/ has no tabel/ nor tabel.py",
        "table/test_guards.py:1: imports a test module",
        "table/test_guards.py:2: imports a test module",
        "test_table.py: a top-level test module outside PROJECT_WIDE",
    ]
    del bad["lift/test_search.py"], bad["lift/runners/test_rig.py"], bad["lift/runners/test_sim.py"]
    assert "deformctl/lift/ has no tests/lift/" in layout_problems(bad, source)
    untested = {k: v for k, v in good.items() if not k.startswith("table/")}
    assert layout_problems(untested, source) == ["deformctl/table.py has no tests/table/"]
    only_init = {**untested, "table/__init__.py": ""}  # a folder without a test module
    assert layout_problems(only_init, source) == ["deformctl/table.py has no tests/table/"]
    assert layout_problems(good, source | {"units.py"}) == [
        "deformctl/units.py has no tests/units/"
    ]
