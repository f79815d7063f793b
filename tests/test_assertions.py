"""Every test asserts something: no test that cannot fail (issue 31, point 8).

A test function passes the check when its body, read as Python (``ast``), contains an
``assert``, a ``raise``, ``pytest.raises`` / ``pytest.warns`` / ``pytest.fail``, a call whose name
starts with ``assert`` (``np.testing.assert_allclose``, a mock's ``assert_called``), a
``subprocess.run(..., check=True)``, or a call of a helper that does (found through the test
modules and the helpers they import, to a fixed point). It is a floor, not a proof: a test can
still assert something beside the point. The few tests whose checks live in a library are listed
in :data:`ASSERTED_ELSEWHERE` with the reason.
"""

from __future__ import annotations

import ast
import textwrap
from collections.abc import Iterable
from pathlib import Path

TESTS = Path(__file__).resolve().parent
#: (file, test) -> where its assertions are.
ASSERTED_ELSEWHERE: dict[tuple[str, str], str] = {
    ("test_train.py", "test_sklearn_estimator_contract"): "scikit-learn's checks assert",
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


def unasserted_tests(sources: dict[str, str]) -> list[tuple[str, str]]:
    """``(file, test)`` of each test function in ``sources`` (file name -> text) that asserts
    nothing, by the rules of the module docstring."""
    functions: dict[tuple[str, str], Function] = {}
    imported: dict[str, dict[str, tuple[str, str]]] = {}
    trees = {name: ast.parse(text) for name, text in sources.items()}
    for name, tree in trees.items():
        stem = Path(name).stem
        imported[stem] = {
            alias.asname or alias.name: (node.module.split(".")[-1], alias.name)
            for node in ast.walk(tree)
            if isinstance(node, ast.ImportFrom) and node.module
            for alias in node.names
        }
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                functions.setdefault((stem, node.name), node)
    asserting = {key for key, fn in functions.items() if _asserts_by_itself(fn)}
    grew = True
    while grew:  # a function that calls an asserting one asserts too
        grew = False
        for (stem, name), fn in functions.items():
            if (stem, name) in asserting:
                continue
            if any(target in asserting for target in _callees(fn, stem, imported[stem])):
                asserting.add((stem, name))
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
        out.extend(
            (Path(name).name, t.name) for t in tests if (Path(name).stem, t.name) not in asserting
        )
    return out


def _callees(
    fn: Function, stem: str, imported: dict[str, tuple[str, str]]
) -> Iterable[tuple[str, str]]:
    for node in ast.walk(fn):
        if isinstance(node, ast.Call):
            name, _ = _call_name(node)
            if name is not None:
                yield (stem, name)
                if name in imported:
                    yield imported[name]


def test_every_test_asserts_something() -> None:
    sources = {str(p.relative_to(TESTS)): p.read_text() for p in sorted(TESTS.rglob("*.py"))}
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
