"""Ingestion of real-rig logs: ROS 2 MCAP bags (written here with mcap_ros2.writer) and CSV.

The bags hold a known Kelvin–Voigt response: two WrenchStamped palms at 1 kHz (1 % noise) and
one PoseStamped palm at 100 Hz (0.05 mm noise), three squeezes in one recording. Going through
``squeeze_from_ros2_bag`` and ``fit_lsq`` must give back the D and λ the bag was written with.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from deformctl.characterize import fit_lsq, kelvin_voigt_piecewise_linear
from deformctl.errors import (
    EXIT_DATAERR,
    EXIT_NOINPUT,
    EXIT_USAGE,
    InputDataError,
    MissingInputError,
    UsageError,
)
from deformctl.measure import segment_squeezes, squeeze_from_csv, squeeze_from_ros2_bag
from tests._helpers.ros2_bags import (
    JOINTS,
    LEFT,
    POSE,
    RIGHT,
    _backwards_force,
    _nan_force,
    write_bag,
)

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
    squeezes = squeeze_from_ros2_bag(
        good_bag, wrench_topics=[LEFT, RIGHT], position_topic=POSE, object_id="sand"
    )
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
    (whole,) = squeeze_from_ros2_bag(
        good_bag, wrench_topics=[RIGHT], position_topic=POSE, object_id="sand", segment=False
    )
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
    squeezes = squeeze_from_ros2_bag(
        path,
        wrench_topics=[LEFT, RIGHT],
        position_topic=JOINTS,
        joint="gripper_width",
        position_is="gap",
        object_id="cotton",
    )
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


def _err(fn: Callable[[], object], cls: type[Exception], match: str) -> str:
    with pytest.raises(cls, match=match) as info:
        fn()
    msg = str(info.value)
    assert "\n" not in msg
    return msg


def test_bag_topic_not_in_bag_lists_topics(good_bag: Path) -> None:
    msg = _err(
        lambda: squeeze_from_ros2_bag(
            good_bag, wrench_topics=["/ft"], position_topic=POSE, object_id="x"
        ),
        InputDataError,
        "topic '/ft' is not in the bag",
    )
    assert f"topics: {POSE}, {LEFT}, {RIGHT}" in msg
    assert InputDataError.exit_code == EXIT_DATAERR


def test_bag_topic_of_wrong_type(good_bag: Path) -> None:
    _err(
        lambda: squeeze_from_ros2_bag(
            good_bag, wrench_topics=[POSE], position_topic=LEFT, object_id="x"
        ),
        InputDataError,
        f"topic '{POSE}' has type geometry_msgs/msg/PoseStamped, expected "
        "geometry_msgs/msg/WrenchStamped",
    )


def test_bag_missing_file(tmp_path: Path) -> None:
    with pytest.raises(MissingInputError, match="no such bag file") as info:
        squeeze_from_ros2_bag(
            tmp_path / "nope.mcap", wrench_topics=[LEFT], position_topic=POSE, object_id="x"
        )
    assert info.value.exit_code == EXIT_NOINPUT


def test_bag_not_mcap(tmp_path: Path) -> None:
    path = tmp_path / "junk.mcap"
    path.write_bytes(b"not an mcap file at all")
    _err(
        lambda: squeeze_from_ros2_bag(
            path, wrench_topics=[LEFT], position_topic=POSE, object_id="x"
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
    write_bag(path, 20.0, 1.0, n_squeezes=1, **kwargs)  # type: ignore[arg-type]
    msg = _err(
        lambda: squeeze_from_ros2_bag(
            path, wrench_topics=[LEFT, RIGHT], position_topic=POSE, object_id="x"
        ),
        InputDataError,
        match,
    )
    assert msg.startswith(str(path))


def test_bag_joint_state_needs_joint(tmp_path: Path) -> None:
    path = tmp_path / "js.mcap"
    write_bag(path, 20.0, 1.0, joint_state=True, n_squeezes=1)
    with pytest.raises(UsageError, match="pass a joint name") as info:
        squeeze_from_ros2_bag(path, wrench_topics=[LEFT], position_topic=JOINTS, object_id="x")
    assert info.value.exit_code == EXIT_USAGE
    _err(
        lambda: squeeze_from_ros2_bag(
            path, wrench_topics=[LEFT], position_topic=JOINTS, joint="finger", object_id="x"
        ),
        InputDataError,
        "joint 'finger' not in the JointState names",
    )


# --- CSV ------------------------------------------------------------------------------------


def _csv_rows(rate_hz: float = 500.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(0.0, 4.0, 1.0 / rate_hz)
    knots_t = np.array([0.0, 1.0, 2.6, 3.6, 4.0])
    knots_f = np.array([0.0, 10.0, 10.0, 0.0, 0.0])
    f = np.interp(t, knots_t, knots_f)
    d = kelvin_voigt_piecewise_linear(t, knots_t, knots_f, 2000.0, 300.0)  # 20 N/cm, 3 N·s/cm
    return t, f, d


def test_csv_plain_with_option_units(tmp_path: Path) -> None:
    t, f, d = _csv_rows()
    path = tmp_path / "plain.csv"
    lines = ["Time,Load,Crosshead"] + [
        f"{ti * 1e3:.6f},{fi / 4.4482216152605:.9f},{di * 1e3:.9f}"
        for ti, fi, di in zip(t, f, d, strict=True)
    ]
    path.write_text("\n".join(lines) + "\n")
    (sq,) = squeeze_from_csv(
        path,
        columns={"time": "Time", "force": "Load", "compression": "Crosshead"},
        units={"time": "ms", "force": "lbf", "compression": "mm"},
        object_id="foam",
    )
    np.testing.assert_allclose(sq.time_s, t, atol=1e-9)
    np.testing.assert_allclose(sq.force_n, f, atol=1e-7)
    np.testing.assert_allclose(sq.compression_m, d, atol=1e-11)
    fit = fit_lsq([sq])
    assert fit.deformability_n_per_cm == pytest.approx(20.0, rel=1e-3)
    assert fit.damping_ns_per_cm == pytest.approx(3.0, rel=1e-3)


def _two_header_csv(path: Path, units: tuple[str, str, str]) -> None:
    t, f, d = _csv_rows()
    gap_in = (0.1 - d) / 0.0254
    lines = ["Zeit,Kraft,Weg", ",".join(units)] + [
        f"{ti:.6f},{fi / 1e3:.12f},{gi:.12f}" for ti, fi, gi in zip(t, f, gap_in, strict=True)
    ]
    path.write_text("\ufeff" + "\n".join(lines) + "\n")


def test_csv_two_header_rows_units_from_file(tmp_path: Path) -> None:
    path = tmp_path / "machine.csv"
    _two_header_csv(path, ("s", "[kN]", "(in)"))
    (sq,) = squeeze_from_csv(
        path, columns={"time": "Zeit", "force": "Kraft", "gap": "Weg"}, object_id="foam"
    )
    _, f, d = _csv_rows()
    np.testing.assert_allclose(sq.force_n, f, atol=1e-8)
    np.testing.assert_allclose(sq.compression_m, d, atol=1e-12)
    # an option that agrees with the file is fine
    squeeze_from_csv(
        path,
        columns={"time": "Zeit", "force": "Kraft", "gap": "Weg"},
        units={"force": "kN"},
        object_id="foam",
    )


def test_csv_missing_column(tmp_path: Path) -> None:
    path = tmp_path / "m.csv"
    _two_header_csv(path, ("s", "kN", "in"))
    msg = _err(
        lambda: squeeze_from_csv(
            path, columns={"time": "Zeit", "force": "Force", "gap": "Weg"}, object_id="x"
        ),
        InputDataError,
        "--columns force='Force' names no column of the header \\(line 1: 'Zeit', 'Kraft', "
        "'Weg'\\)",
    )
    assert msg.startswith(str(path))


def test_csv_unknown_unit_in_file_and_option(tmp_path: Path) -> None:
    path = tmp_path / "u.csv"
    _two_header_csv(path, ("s", "kgm", "in"))
    cols = {"time": "Zeit", "force": "Kraft", "gap": "Weg"}
    _err(
        lambda: squeeze_from_csv(path, columns=cols, object_id="x"),
        InputDataError,
        "column 'Kraft' \\(force\\): unit 'kgm' in the units row is not a known force unit; known: "
        "N, kN, mN, daN, lbf, ozf, kgf, gf",
    )
    with pytest.raises(UsageError, match="unknown time unit 'fortnight'") as info:
        squeeze_from_csv(path, columns=cols, units={"time": "fortnight"}, object_id="x")
    assert info.value.exit_code == EXIT_USAGE


def test_csv_conflicting_units(tmp_path: Path) -> None:
    path = tmp_path / "c.csv"
    _two_header_csv(path, ("s", "kN", "in"))
    _err(
        lambda: squeeze_from_csv(
            path,
            columns={"time": "Zeit", "force": "Kraft", "gap": "Weg"},
            units={"gap": "mm"},
            object_id="x",
        ),
        UsageError,
        "--units gap=mm contradicts the file: column 'Weg' is in in \\(its units row says 'in'\\)",
    )


def test_csv_bad_columns_mapping_and_missing_file(tmp_path: Path) -> None:
    with pytest.raises(MissingInputError):
        squeeze_from_csv(
            tmp_path / "no.csv", columns={"time": "t", "force": "f", "gap": "g"}, object_id="x"
        )
    path = tmp_path / "c.csv"
    _two_header_csv(path, ("s", "kN", "in"))
    with pytest.raises(UsageError, match="--columns maps position and gap: give one position"):
        squeeze_from_csv(
            path,
            columns={"time": "Zeit", "force": "Kraft", "gap": "Weg", "position": "Weg"},
            object_id="x",
        )
