"""Every test asserts something: no test that cannot fail.

A test function passes the check when its body, read as Python (``ast``), contains an
``assert``, a ``raise``, ``pytest.raises`` / ``pytest.warns`` / ``pytest.fail``, a call whose name
starts with ``assert`` (``np.testing.assert_allclose``, a mock's ``assert_called``), a
``subprocess.run(..., check=True)``, or a call of a helper that does (found through the test
modules and the helpers they import, to a fixed point). Modules are told apart by their path
under ``tests/`` (``cli/test_table.py`` and ``table/test_table.py`` are two modules), and an
import is followed to the file it names (``tests._helpers.cli``, ``._truth``). It is a floor, not
a proof: a test can still assert something beside the point. The few tests whose checks live in
a library are listed in :data:`ASSERTED_ELSEWHERE` with the reason.
"""

from __future__ import annotations

import ast
import textwrap
from collections.abc import Iterable
from pathlib import Path

TESTS = Path(__file__).resolve().parent
#: (file, test) -> where its assertions are.
ASSERTED_ELSEWHERE: dict[tuple[str, str], str] = {
    ("model/test_model.py", "test_sklearn_estimator_contract"): "scikit-learn's checks assert",
}
_PYTEST_ASSERTING = {"raises", "warns", "fail", "deprecated_call"}

Function = ast.FunctionDef | ast.AsyncFunctionDef


def _call_name(call: ast.Call) -> tuple[str | None, str | None]:
    """``(name, owner)`` of a call: ``pytest.raises(...)`` gives ``("raises", "pytest")``."""
    f = call.func
    if isinstance(f, ast.Name):
        return f.id, None
    if isinstance(f, ast.Attribute):
        base = f.value
        owner = base.id if isinstance(base, ast.Name) else getattr(base, "attr", None)
        return f.attr, owner
    return None, None


def _asserts_by_itself(function: Function) -> bool:
    for node in ast.walk(function):
        if isinstance(node, ast.Assert | ast.Raise):
            return True
        if not isinstance(node, ast.Call):
            continue
        name, owner = _call_name(node)
        if name is None:
            continue
        if owner == "pytest" and name in _PYTEST_ASSERTING:
            return True
        if name.startswith("assert"):
            return True
        checked = any(
            k.arg == "check" and isinstance(k.value, ast.Constant) and k.value.value is True
            for k in node.keywords
        )
        if owner == "subprocess" and name == "run" and checked:
            return True
    return False


def _module_of(name: str) -> str:
    """The dotted module of a file named by its path under ``tests/``: ``cli/test_x.py`` ->
    ``cli.test_x``."""
    return ".".join(Path(name).with_suffix("").parts)


def _imported_module(node: ast.ImportFrom, module: str, modules: set[str]) -> str:
    """The module (as :func:`_module_of` names it) that ``from ... import`` reads in ``module``:
    relative imports from the importing package, ``tests.`` dropped, and a bare name that is no
    known module resolved by its last part when one module alone ends so."""
    if node.level:
        package = module.split(".")[: -node.level]
        target = ".".join([*package, *([node.module] if node.module else [])])
    else:
        target = node.module or ""
        target = target.removeprefix("tests.")
    if target in modules:
        return target
    ends = [m for m in modules if m.rsplit(".", 1)[-1] == target.rsplit(".", 1)[-1]]
    return ends[0] if len(ends) == 1 else target


def unasserted_tests(sources: dict[str, str]) -> list[tuple[str, str]]:
    """``(file, test)`` of each test function in ``sources`` (path under ``tests/`` -> text) that
    asserts nothing, by the rules of the module docstring."""
    functions: dict[tuple[str, str], Function] = {}
    imported: dict[str, dict[str, tuple[str, str]]] = {}
    trees = {name: ast.parse(text) for name, text in sources.items()}
    modules = {_module_of(name) for name in trees}
    for name, tree in trees.items():
        module = _module_of(name)
        imported[module] = {
            alias.asname or alias.name: (_imported_module(node, module, modules), alias.name)
            for node in ast.walk(tree)
            if isinstance(node, ast.ImportFrom)
            for alias in node.names
        }
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                functions.setdefault((module, node.name), node)
    asserting = {key for key, fn in functions.items() if _asserts_by_itself(fn)}
    grew = True
    while grew:  # a function that calls an asserting one asserts too
        grew = False
        for (module, name), fn in functions.items():
            if (module, name) in asserting:
                continue
            if any(target in asserting for target in _callees(fn, module, imported[module])):
                asserting.add((module, name))
                grew = True
    out: list[tuple[str, str]] = []
    for name, tree in trees.items():
        if not Path(name).name.startswith("test_"):
            continue
        tests = [
            node
            for node in ast.walk(tree)
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
            and node.name.startswith("test_")
        ]
        out.extend((name, t.name) for t in tests if (_module_of(name), t.name) not in asserting)
    return out


def _callees(
    fn: Function, module: str, imported: dict[str, tuple[str, str]]
) -> Iterable[tuple[str, str]]:
    for node in ast.walk(fn):
        if isinstance(node, ast.Call):
            name, _ = _call_name(node)
            if name is not None:
                yield (module, name)
                if name in imported:
                    yield imported[name]


def test_every_test_asserts_something() -> None:
    sources = {p.relative_to(TESTS).as_posix(): p.read_text() for p in sorted(TESTS.rglob("*.py"))}
    found = [t for t in unasserted_tests(sources) if t not in ASSERTED_ELSEWHERE]
    assert not found, f"tests that assert nothing: {found}"
    assert len(sources) > 50  # the walk found the suite


def test_the_check_finds_a_test_that_cannot_fail() -> None:
    helper = "def check(x):\n    assert x\n\ndef quiet(x):\n    return x\n"
    module = textwrap.dedent(
        """
        import subprocess
        import pytest
        from helpers import check, quiet

        def test_prints():
            print(1 + 1)

        def test_calls_a_quiet_helper():
            quiet(2)

        def test_catches_everything():
            try:
                quiet(2)
            except Exception:
                pass

        def test_asserts():
            assert 1 + 1 == 2

        def test_raises():
            with pytest.raises(ZeroDivisionError):
                1 / 0

        def test_calls_an_asserting_helper():
            check(2)

        def test_runs_a_checked_process():
            subprocess.run(["true"], check=True)
        """
    )
    found = unasserted_tests({"helpers.py": helper, "test_fake.py": module})
    assert found == [
        ("test_fake.py", "test_prints"),
        ("test_fake.py", "test_calls_a_quiet_helper"),
        ("test_fake.py", "test_catches_everything"),
    ]


def test_the_check_tells_modules_of_the_same_name_apart() -> None:
    # cli/test_table.py and table/test_table.py hold a test of the same name: only one asserts,
    # and the helper each imports is the one its path names, not another module's namesake
    asserting = "def test_lookup():\n    assert 1\n"
    quiet = "def test_lookup():\n    print(1)\n"
    calls = "from {module} import check\n\ndef test_checked():\n    check(2)\n"
    found = unasserted_tests(
        {
            "cli/test_table.py": asserting,
            "table/test_table.py": quiet,
            "_helpers/check.py": "def check(x):\n    assert x\n",
            "table/check.py": "def check(x):\n    return x\n",
            "cli/test_uses_the_helper.py": calls.format(module="tests._helpers.check"),
            "table/test_uses_its_own.py": calls.format(module=".check"),
        }
    )
    assert found == [
        ("table/test_table.py", "test_lookup"),
        ("table/test_uses_its_own.py", "test_checked"),
    ]
