"""deformctl.scene: the scene rate (one rule, ``check_scene_hz``) and the frames' shape contract."""

from __future__ import annotations

import math

import numpy as np
import pytest

from deformctl.errors import UsageError
from deformctl.scene import DEFAULT_SCENE_HZ, SceneFrames, check_scene_hz, scene_every_steps


@pytest.mark.parametrize(
    ("hz", "dt", "every"),
    [
        (0.0, 1e-3, 0),
        (30.0, 1e-3, 33),
        (DEFAULT_SCENE_HZ, 2e-3, 17),
        (1000.0, 1e-3, 1),
        (7, 0.05, 3),
    ],
)
def test_steps_between_frames(hz: float, dt: float, every: int) -> None:
    assert check_scene_hz(hz, dt) == hz
    assert scene_every_steps(hz, dt) == every
    if every:  # the frame period is the one asked for to within half a step
        assert abs(every - 1.0 / (hz * dt)) <= 0.5


@pytest.mark.parametrize("hz", [-1.0, -1e-9, math.inf, math.nan, 1000.1, 5000.0])
def test_bad_rates_are_usage_errors(hz: float) -> None:
    with pytest.raises(UsageError, match="--scene-hz"):
        check_scene_hz(hz, 1e-3)


def test_frames_refuse_inconsistent_shapes() -> None:
    k, m = 3, 4
    ok = {
        "time_s": np.zeros(k),
        "positions_m": np.zeros((k, m, 3)),
        "particle_index": np.arange(m),
        "contact_side": np.zeros(m, dtype=np.int64),
        "palm_x_m": np.zeros((k, 2)),
        "palm_z_m": np.zeros(k),
        "normal_force_n": np.zeros((k, 2)),
        "tangential_force_n": np.zeros((k, 2)),
        "slip_m": np.zeros((k, 2)),
        "slipping": np.zeros((k, 2), dtype=bool),
        "palm_size_m": (0.01, 0.1, 0.1),
        "palm_centre_m": (0.0, 0.05),
        "particle_diameter_m": 0.003,
        "table": True,
    }
    frames = SceneFrames(**ok)  # type: ignore[arg-type]
    assert len(frames) == k
    np.testing.assert_allclose(frames.palm_centres_m(0), [[-0.005, 0.0, 0.05], [0.005, 0.0, 0.05]])
    with pytest.raises(ValueError, match="positions_m"):
        SceneFrames(**{**ok, "positions_m": np.zeros((k, m + 1, 3))})  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="slipping"):
        SceneFrames(**{**ok, "slipping": np.zeros((k + 1, 2), dtype=bool)})  # type: ignore[arg-type]
