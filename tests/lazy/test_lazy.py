"""deformctl.lazy: a lazily exported name is imported on first use, then cached in the package;
a package face lists each name once, as an import for type checkers."""

from __future__ import annotations

import importlib
import json
import sys
from pathlib import Path
from typing import Any

import pytest

from deformctl.lazy import lazy_exports, lazy_face, typing_imports


def test_a_name_is_imported_on_first_use_and_cached(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delitem(sys.modules, "colorsys", raising=False)
    namespace: dict[str, Any] = {"__name__": "pkg", "kept": 1}
    getattr_, _ = lazy_exports(namespace, {"rgb_to_hsv": "colorsys"})
    assert "colorsys" not in sys.modules  # building the hooks imports nothing
    value = getattr_("rgb_to_hsv")
    assert "colorsys" in sys.modules
    assert value is sys.modules["colorsys"].rgb_to_hsv
    assert namespace["rgb_to_hsv"] is value  # cached: the next lookup is a plain global
    assert value(1.0, 0.0, 0.0) == (0.0, 1.0, 1.0)


def test_an_unknown_name_is_the_usual_attribute_error() -> None:
    getattr_, _ = lazy_exports({"__name__": "pkg"}, {"sqrt": "math"})
    with pytest.raises(AttributeError, match=r"^module 'pkg' has no attribute 'nope'$"):
        getattr_("nope")
    with pytest.raises(AttributeError, match="has no attribute 'sqrt'"):
        lazy_exports({"__name__": "pkg"}, {"sqrt": "json"})[0]("sqrt")  # json has no sqrt


def test_dir_lists_loaded_and_not_yet_loaded_names_once() -> None:
    namespace: dict[str, Any] = {"__name__": "pkg", "b": 2}
    getattr_, dir_ = lazy_exports(namespace, {"sqrt": "math", "dumps": "json"})
    assert dir_() == ["__name__", "b", "dumps", "sqrt"]
    getattr_("sqrt")
    assert dir_() == ["__name__", "b", "dumps", "sqrt"]


FACE = '''"""A package face."""
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    __version__: str

if TYPE_CHECKING:
    from json import dumps, loads
    from math import (
        sqrt,
    )
'''


def test_the_typing_imports_are_the_public_names() -> None:
    assert typing_imports(FACE) == {"dumps": "json", "loads": "json", "sqrt": "math"}
    for bad in ("from . import x", "import json"):
        with pytest.raises(ValueError, match="not an absolute from-import"):
            typing_imports(f"if TYPE_CHECKING:\n    {bad}\n")
    with pytest.raises(ValueError, match="a renamed import"):
        typing_imports("if TYPE_CHECKING:\n    from json import loads as parse\n")


def test_a_face_gets_its_names_from_its_own_source(tmp_path: Path) -> None:
    (tmp_path / "face.py").write_text(FACE)
    namespace: dict[str, Any] = {"__name__": "pkg", "__file__": str(tmp_path / "face.py")}
    getattr_, dir_ = lazy_face(namespace, first=("Own",))
    assert namespace["__all__"] == ["Own", "dumps", "loads", "sqrt"]
    assert getattr_("loads") is json.loads
    assert "sqrt" in dir_()


@pytest.mark.parametrize(
    "package",
    [
        "deformctl",
        "deformctl.artifacts",
        "deformctl.characterize",
        "deformctl.lift",
        "deformctl.measure",
        "deformctl.parallel",
    ],
)
def test_every_name_of_a_face_loads_from_the_module_it_names(package: str) -> None:
    face = importlib.import_module(package)
    names = typing_imports(Path(face.__file__ or "").read_text())
    assert set(names) <= set(face.__all__)
    for name, module in names.items():
        assert getattr(face, name) is getattr(importlib.import_module(module), name), name
