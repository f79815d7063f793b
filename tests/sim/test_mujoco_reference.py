"""The MuJoCo flex cube that ``make bench`` times against ours (bench/bench_mujoco.py) is the
same object: squeezed by the same force, it compresses by F / D, as ours does. Skipped without
MuJoCo (the ``bench`` extra; ``make test`` does not install it)."""

from __future__ import annotations

import pytest

pytest.importorskip("mujoco")

from bench.bench_mujoco import (
    DAMPED,
    PEAK_N,
    SHORT_HOLD_S,
    SHORT_RAMP_S,
    mujoco_squeeze,
    ours_squeeze,
)


def test_the_mujoco_cube_compresses_by_force_over_stiffness_as_ours_does() -> None:
    static_m = PEAK_N / (DAMPED.stiffness_n_per_cm * 100.0)
    result = mujoco_squeeze(5, 1e-3, SHORT_RAMP_S, SHORT_HOLD_S)
    assert result is not None, "MuJoCo warned on the 5^3 cube at 1 ms"
    cpu_s, mujoco_m = result
    assert cpu_s > 0
    # at the end of the short squeeze's hold: two retardation times (lambda / D = 50 ms) after
    # its ramp (MuJoCo's cube keeps creeping through a longer hold: 7.5 mm after 0.75 s)
    assert mujoco_m == pytest.approx(static_m, rel=0.1)
    assert ours_squeeze(5, SHORT_RAMP_S, SHORT_HOLD_S)[1] == pytest.approx(static_m, rel=0.1)
