"""deformctl: learn the minimum force that lifts a deformable object without slip.

The library is organised by pipeline stage: :mod:`~deformctl.population`,
:mod:`~deformctl.measure`, :mod:`~deformctl.characterize`, :mod:`deformctl.lift` (search, stage,
runners), :mod:`~deformctl.table`, :mod:`~deformctl.train`, with :mod:`deformctl.vision` for
OpenCV measurements. Below the stages: :mod:`~deformctl.catalog` (the typed catalog row),
:mod:`~deformctl.parallel` (the sweep executor), :mod:`deformctl.artifacts` (every file format,
the dataset directory), :mod:`deformctl.sim` (physics only) and :mod:`~deformctl.physics` (the
one F_w). Above them: :mod:`deformctl.repro` (the paper's reproduction and the golden regression
on the bundled data) and :mod:`deformctl.cli`, the ``deformctl`` command, a thin layer over the
library. The README's Architecture section says what each package owns.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from deformctl.errors import DeformctlError

if TYPE_CHECKING:  # pragma: no cover - computed on first use (module __getattr__)
    __version__: str

__all__ = ["DeformctlError", "__version__"]


def __getattr__(name: str) -> Any:
    """``__version__``, read from the installed distribution on first use: the lookup
    (``importlib.metadata``) costs a good part of a one-object ``predict``'s start-up."""
    if name != "__version__":
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from importlib.metadata import PackageNotFoundError, version

    try:
        value = version("deformctl")
    except PackageNotFoundError:  # pragma: no cover - a source tree without install
        value = "0.0.0+unknown"
    globals()["__version__"] = value
    return value
