"""Every computed coefficients column is finite, or null with a flag; a failure names a cause.

Known truth: a loading curve with a falling stretch (a slip, a buckling dip) has no tangent
stiffness spread (slopes of both signs); a relaxation's positive force has its peak where it
jumps; an exception's class maps to the documented cause list.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from deformctl.artifacts.dataset import FAILURE_CAUSES, failure_cause
from deformctl.characterize.quality import (
    FLAGS,
    NONLINEAR_STIFFNESS,
    NOT_FINITE,
    describe_flag,
    finite_row,
)
from deformctl.characterize.stiffness import LoadingStiffness, loading_stiffness
from deformctl.squeeze.rupture import phase_slice


def test_a_falling_stretch_has_a_null_spread_and_is_flagged() -> None:
    d = np.linspace(0.0, 0.01, 1001)
    f = 1000.0 * d
    f[400:600] = f[400] - 300.0 * (d[400:600] - d[400])  # a dip before the peak
    f[600:] = f[599] + 1000.0 * (d[600:] - d[599])
    stiff = loading_stiffness(d, f)
    assert stiff.falling
    assert math.isnan(stiff.tangent_spread)
    assert stiff.nonlinear
    row = {"tangent_stiffness_spread": stiff.tangent_spread, "operating_force_n": 3.0}
    assert "falls or is flat over a stretch" in describe_flag(NONLINEAR_STIFFNESS, row)


def test_a_straight_loading_is_not_falling() -> None:
    stiff = LoadingStiffness(1000.0, 1000.0, (1000.0, 1010.0, 990.0))
    assert not stiff.falling
    assert stiff.tangent_spread == pytest.approx(1010.0 / 990.0)
    assert not stiff.nonlinear


def test_an_infinite_column_is_written_null_with_a_flag() -> None:
    row = {"quality": "rupture", "stiffening_ratio": math.inf, "r2": 0.99, "n_squeezes": 1}
    out = finite_row(row)
    assert math.isnan(out["stiffening_ratio"])
    assert out["quality"] == f"rupture,{NOT_FINITE}"
    assert NOT_FINITE in FLAGS
    assert finite_row({"quality": "ok", "r2": 0.99}) == {"quality": "ok", "r2": 0.99}


def test_the_peak_of_a_force_at_or_below_zero_is_found() -> None:
    t = np.arange(200) / 100.0
    f = -3.0 + np.exp(-((t - 0.5) ** 2) / 0.01)  # a pulse that never reaches 0
    sl = phase_slice(t, f, "loading", window_s=0.05)
    assert 40 <= sl.stop <= 60


@pytest.mark.parametrize(
    ("error_type", "cause"),
    [
        ("InputDataError", "bad_input"),
        ("SchemaError", "bad_input"),
        ("MissingInputError", "missing_input"),
        ("UsageError", "bad_option"),
        ("SearchError", "not_converged"),
        ("NotConverged", "not_converged"),
        ("ObjectFailed", "object_failed"),
        ("MemoryError", "out_of_memory"),
        ("IndexError", "internal_error"),
        ("ValueError", "internal_error"),
    ],
)
def test_a_failure_names_a_documented_cause(error_type: str, cause: str) -> None:
    assert failure_cause(error_type) == cause
    assert cause in FAILURE_CAUSES


def test_every_cause_is_documented() -> None:
    from pathlib import Path

    doc = (Path(__file__).resolve().parents[2] / "docs" / "reference" / "exit-codes.md").read_text(
        encoding="utf-8"
    )
    for cause in FAILURE_CAUSES:
        assert f"| `{cause}` |" in doc, cause
