"""Lazy public names for a package (PEP 562), so importing the package imports none of its
submodules and a command pays only for the modules it uses.

A package's face lists each public name once, as an import under ``if TYPE_CHECKING:`` (what
type checkers and editors read); :func:`lazy_face` reads the same lines from the package's source
and gives the module-level ``__getattr__`` and ``__dir__``, and sets ``__all__``.
"""

from __future__ import annotations

import ast
import importlib
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any


def lazy_exports(
    namespace: dict[str, Any], exports: Mapping[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The module-level ``__getattr__`` and ``__dir__`` of the package whose globals are
    ``namespace``: ``exports`` maps each public name to the module that defines it. A name is
    imported on first use and then cached in ``namespace``."""
    package = namespace["__name__"]

    def __getattr__(name: str) -> Any:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted({*namespace, *exports})

    return __getattr__, __dir__


def typing_imports(source: str) -> dict[str, str]:
    """Each name the module ``source`` imports under a top-level ``if TYPE_CHECKING:`` → the
    module it comes from (absolute ``from module import name`` statements, not renamed;
    declarations are skipped)."""
    exports: dict[str, str] = {}
    for node in ast.parse(source).body:
        if not (isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING"):
            continue
        for statement in node.body:
            if isinstance(statement, ast.AnnAssign):  # a declaration, such as ``__version__: str``
                continue
            if not isinstance(statement, ast.ImportFrom) or statement.level or not statement.module:
                raise ValueError(f"not an absolute from-import: {ast.unparse(statement)}")
            for alias in statement.names:
                if alias.asname not in (None, alias.name):
                    raise ValueError(f"a renamed import: {ast.unparse(statement)}")
                exports[alias.name] = statement.module
    return exports


def lazy_face(
    namespace: dict[str, Any], *, first: tuple[str, ...] = ()
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The ``__getattr__`` and ``__dir__`` of the package whose globals are ``namespace``, with
    the names its ``if TYPE_CHECKING:`` block imports (:func:`typing_imports`) as the public
    names; ``__all__`` is set to ``first`` (names the package defines itself), then them, sorted."""
    exports = typing_imports(Path(namespace["__file__"]).read_text(encoding="utf-8"))
    namespace["__all__"] = [*first, *sorted(exports)]
    return lazy_exports(namespace, exports)
