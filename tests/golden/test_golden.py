"""deformctl.golden, the old home of the dataset regression: a shim that re-exports
:mod:`deformctl.repro.golden` (tested in tests/repro/test_golden.py)."""

from __future__ import annotations

from deformctl import golden
from deformctl.repro import golden as repro_golden


def test_the_shim_re_exports_the_same_objects() -> None:
    assert golden.__all__, "nothing re-exported"
    for name in golden.__all__:
        assert getattr(golden, name) is getattr(repro_golden, name), name
    assert {"compare", "compute_golden", "main", "TOLERANCES"} <= set(golden.__all__)
