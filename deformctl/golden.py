"""Moved to :mod:`deformctl.repro.golden`; this name is kept for ``tests/repro/test_golden.py``.

``python -m deformctl.golden [--update]`` still works and runs :func:`deformctl.repro.golden.main`.
"""

from __future__ import annotations

import sys

from deformctl.repro.golden import (
    EXPECTED_PATH,
    GOLDEN_SEED,
    GOLDEN_TRAIN_SIZE,
    TOLERANCES,
    Tolerance,
    compare,
    compute_golden,
    main,
)

__all__ = [
    "EXPECTED_PATH",
    "GOLDEN_SEED",
    "GOLDEN_TRAIN_SIZE",
    "TOLERANCES",
    "Tolerance",
    "compare",
    "compute_golden",
    "main",
]

if __name__ == "__main__":
    sys.exit(main())
