"""The installed package's version (``deformctl --version``; every artifact's provenance).

``deformctl.__version__`` and this module's ``__version__`` are read on first use: the lookup
(:mod:`importlib.metadata`) costs a good part of a one-object ``predict``'s start-up.
"""

from __future__ import annotations

from functools import cache
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover - read on first use (module __getattr__)
    __version__: str

__all__ = ["__version__", "version_string"]


@cache
def version_string() -> str:
    """The installed distribution's version (``0.0.0+unknown`` in a source tree without one)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("deformctl")
    except PackageNotFoundError:  # pragma: no cover - a source tree without install
        return "0.0.0+unknown"


def __getattr__(name: str) -> Any:
    if name != "__version__":
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return version_string()
