"""The shared time-series containers validate their shapes."""

from __future__ import annotations

import numpy as np
import pytest

from deformctl.series import LiftAttemptSeries, SqueezeSeries


def test_squeeze_series_coerces_to_float_arrays() -> None:
    s = SqueezeSeries("A", 0, [0, 1, 2], [0, 1, 2], [0.0, 0.001, 0.002])
    assert s.time_s.dtype == np.float64
    assert len(s) == 3
    assert s.commanded_force_n is None


def test_squeeze_series_rejects_length_mismatch() -> None:
    with pytest.raises(ValueError, match="force_n has 2 samples"):
        SqueezeSeries("A", 0, [0, 1, 2], [0, 1], [0, 0, 0])


def test_lift_series_rejects_2d() -> None:
    with pytest.raises(ValueError, match="must be 1-D"):
        LiftAttemptSeries(np.zeros((2, 2)), [0], [0], [0], [0], [0])
