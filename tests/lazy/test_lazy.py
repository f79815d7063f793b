"""deformctl.lazy: a lazily exported name is imported on first use, then cached in the package."""

from __future__ import annotations

import sys
from typing import Any

import pytest

from deformctl.lazy import lazy_exports


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
