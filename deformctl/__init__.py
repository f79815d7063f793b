"""deformctl: learn the minimum force that lifts a deformable object without slip.

The library is organised by pipeline stage (``measure``, ``characterize``, ``lift``, ``table``,
``train``); the ``deformctl`` command is a thin layer over it.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from deformctl.errors import DeformctlError

try:
    __version__ = version("deformctl")
except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
    __version__ = "0.0.0+unknown"

__all__ = ["DeformctlError", "__version__"]
