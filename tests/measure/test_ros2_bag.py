"""Ingestion of ROS 2 MCAP bags (written by tests/_helpers/ros2_bags.py) and their segmentation.

The bags hold a known Kelvin–Voigt response: two WrenchStamped palms at 1 kHz (1 % noise) and
one PoseStamped palm at 100 Hz (0.05 mm noise), three squeezes in one recording. Going through
``read_recording`` and ``fit_lsq`` must give back the D and λ the bag was written with.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from deformctl.characterize import fit_lsq
from deformctl.errors import (
    EXIT_DATAERR,
    EXIT_NOINPUT,
    EXIT_USAGE,
    InputDataError,
    MissingInputError,
    UsageError,
)
from deformctl.measure import BagSource, Segmentation, read_recording, segment_squeezes
from tests._helpers.ros2_bags import (
    JOINTS,
    LEFT,
    POSE,
    RIGHT,
    _backwards_force,
    _nan_force,
    write_bag,
)

from ._errors import _err

#: SG window for positions logged at 100 Hz: the default 0.2 s spans only 20 pose samples, and the
#: derivative of their noise pulls λ ~15 % low (errors in variables, measured); 0.5 s spans 50.
BAG_WINDOW_S = 0.5


@pytest.fixture(scope="module")
def good_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("bag") / "squeeze.mcap"
    write_bag(path, 30.02, 6.47, seed=1)
    return path


# --- ROS 2 bags -----------------------------------------------------------------------------


def test_bag_two_palms_recovers_d_and_lambda(good_bag: Path) -> None:
    squeezes = read_recording(
        good_bag, BagSource(wrench_topics=[LEFT, RIGHT], position_topic=POSE), "sand"
    ).squeezes
    assert [s.squeeze_index for s in squeezes] == [0, 1, 2]
    assert all(s.object_id == "sand" for s in squeezes)
    # 1 kHz force timestamps survive: uniform 1 ms steps
    assert np.allclose(np.diff(squeezes[0].time_s), 1e-3, atol=1e-9)
    fit = fit_lsq(squeezes, window_s=BAG_WINDOW_S)
    assert fit.deformability_n_per_cm == pytest.approx(30.02, rel=0.02)
    assert fit.damping_ns_per_cm == pytest.approx(6.47, rel=0.05)
    print(
        f"\nbag (1 kHz wrench x2, 100 Hz pose): D {fit.deformability_n_per_cm:.3f} (30.02), "
        f"λ {fit.damping_ns_per_cm:.3f} (6.47) ± {fit.damping_se_ns_per_cm:.3f}"
    )


def test_bag_one_palm_and_one_squeeze(good_bag: Path) -> None:
    (whole,) = read_recording(
        good_bag,
        BagSource(wrench_topics=[RIGHT], position_topic=POSE),
        "sand",
        Segmentation(segment=False),
    ).squeezes
    # the overlap is the pose span 3 ms..13.793 s (inclusive), and so is the force time base
    assert whole.time_s[0] == 0.0
    assert whole.time_s[-1] == pytest.approx(13.793 - 0.003, abs=1e-6)
    assert float(np.min(whole.force_n)) >= 0.0  # magnitude of a −x force
    fit = fit_lsq([whole], window_s=BAG_WINDOW_S)
    assert fit.deformability_n_per_cm == pytest.approx(30.02, rel=0.02)
    assert fit.damping_ns_per_cm == pytest.approx(6.47, rel=0.05)


def test_bag_joint_state_gap(tmp_path: Path) -> None:
    path = tmp_path / "js.mcap"
    write_bag(path, 13.03, 0.33, seed=2, joint_state=True)
    squeezes = read_recording(
        path,
        BagSource(
            wrench_topics=[LEFT, RIGHT],
            position_topic=JOINTS,
            joint="gripper_width",
            position_is="gap",
        ),
        "cotton",
    ).squeezes
    assert len(squeezes) == 3
    fit = fit_lsq(squeezes, window_s=BAG_WINDOW_S)
    assert fit.deformability_n_per_cm == pytest.approx(13.03, rel=0.02)
    assert fit.damping_ns_per_cm == pytest.approx(0.33, abs=0.05)


def test_segmentation_finds_each_squeeze() -> None:
    t = np.arange(0, 10, 0.001)
    f = np.where((t > 1) & (t < 3), 5.0, 0.0) + np.where((t > 5) & (t < 8), 5.0, 0.0)
    f[2000] = 0.0  # a one-sample dropout inside the first squeeze is not a new squeeze
    slices = segment_squeezes(t, f)
    assert len(slices) == 2
    assert slices[0].start == 0
    assert slices[1].stop == t.size
    assert slices[0].stop == slices[1].start == (3000 + 5001) // 2


def test_bag_topic_not_in_bag_lists_topics(good_bag: Path) -> None:
    msg = _err(
        lambda: (
            read_recording(
                good_bag, BagSource(wrench_topics=["/ft"], position_topic=POSE), "x"
            ).squeezes
        ),
        InputDataError,
        "topic '/ft' is not in the bag",
    )
    assert f"topics: {POSE}, {LEFT}, {RIGHT}" in msg
    assert InputDataError.exit_code == EXIT_DATAERR


def test_bag_topic_of_wrong_type(good_bag: Path) -> None:
    _err(
        lambda: (
            read_recording(
                good_bag, BagSource(wrench_topics=[POSE], position_topic=LEFT), "x"
            ).squeezes
        ),
        InputDataError,
        f"topic '{POSE}' has type geometry_msgs/msg/PoseStamped, expected "
        "geometry_msgs/msg/WrenchStamped",
    )


def test_bag_missing_file(tmp_path: Path) -> None:
    with pytest.raises(MissingInputError, match="no such bag file") as info:
        read_recording(
            tmp_path / "nope.mcap", BagSource(wrench_topics=[LEFT], position_topic=POSE), "x"
        )
    assert info.value.exit_code == EXIT_NOINPUT


def test_bag_not_mcap(tmp_path: Path) -> None:
    path = tmp_path / "junk.mcap"
    path.write_bytes(b"not an mcap file at all")
    _err(
        lambda: (
            read_recording(path, BagSource(wrench_topics=[LEFT], position_topic=POSE), "x").squeezes
        ),
        InputDataError,
        "not a readable MCAP file",
    )


def _shift_pose(tp: np.ndarray, pos: np.ndarray) -> None:
    tp += 100.0


def _still_pose(tp: np.ndarray, pos: np.ndarray) -> None:
    pos[:] = -0.05


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"edit_pose": _shift_pose}, "force and position streams do not overlap in time"),
        ({"edit_force": _backwards_force}, f"topic '{LEFT}': non-monotonic timestamps, sample 691"),
        ({"edit_force": _nan_force}, f"topic '{LEFT}': 1 NaN/inf sample"),
        ({"edit_pose": _still_pose}, "no compression"),
    ],
    ids=["no_overlap", "non_monotonic", "nan", "zero_displacement"],
)
def test_bag_bad_streams(tmp_path: Path, kwargs: dict[str, object], match: str) -> None:
    path = tmp_path / "bad.mcap"
    write_bag(path, 20.0, 1.0, n_squeezes=1, force_rate_hz=250.0, **kwargs)  # type: ignore[arg-type]
    msg = _err(
        lambda: (
            read_recording(
                path, BagSource(wrench_topics=[LEFT, RIGHT], position_topic=POSE), "x"
            ).squeezes
        ),
        InputDataError,
        match,
    )
    assert msg.startswith(str(path))


def test_bag_joint_state_needs_joint(tmp_path: Path) -> None:
    path = tmp_path / "js.mcap"
    write_bag(path, 20.0, 1.0, joint_state=True, n_squeezes=1)
    with pytest.raises(UsageError, match="pass a joint name") as info:
        read_recording(path, BagSource(wrench_topics=[LEFT], position_topic=JOINTS), "x")
    assert info.value.exit_code == EXIT_USAGE
    _err(
        lambda: (
            read_recording(
                path, BagSource(wrench_topics=[LEFT], position_topic=JOINTS, joint="finger"), "x"
            ).squeezes
        ),
        InputDataError,
        "joint 'finger' not in the JointState names",
    )
