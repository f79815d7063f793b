"""The layout's rules, checked: where things live, how large the commands are, what imports what."""

from __future__ import annotations

import ast
import dataclasses
import inspect
import subprocess
import sys
from pathlib import Path

import pytest

import deformctl
from deformctl.cli import COMMANDS
from deformctl.cli._options import HEAVY_DEFAULTS

PACKAGE = Path(deformctl.__file__).resolve().parent
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
        "deformctl.characterize.rupture",
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
