"""deformctl.golden, the old home of the dataset regression: a shim that re-exports
:mod:`deformctl.repro.golden` (tested in tests/repro/test_golden.py)."""

from __future__ import annotations

import pytest

from deformctl import golden
from deformctl.repro import golden as repro_golden


def test_the_shim_re_exports_the_same_objects() -> None:
    assert golden.__all__, "nothing re-exported"
    for name in golden.__all__:
        assert getattr(golden, name) is getattr(repro_golden, name), name
    assert {"compare", "compute_golden", "main", "TOLERANCES"} <= set(golden.__all__)


def test_help_and_unknown_arguments_stop_before_the_pipeline(
    capsys: pytest.CaptureFixture[str],
) -> None:
    for args, code in ((["--help"], 0), (["--bogus"], 2)):
        with pytest.raises(SystemExit) as stop:
            repro_golden.main(args)
        assert stop.value.code == code
    out = capsys.readouterr()
    assert "usage: python -m deformctl.repro.golden" in out.out + out.err
    assert "unrecognized arguments: --bogus" in out.err
