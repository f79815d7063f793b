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

from importlib.metadata import PackageNotFoundError, version

from deformctl.errors import DeformctlError

try:
    __version__ = version("deformctl")
except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
    __version__ = "0.0.0+unknown"

__all__ = ["DeformctlError", "__version__"]
