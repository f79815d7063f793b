"""ROS 2 MCAP bags with a known Kelvin–Voigt response, written with ``mcap_ros2.writer``.

:func:`write_bag` writes two ``WrenchStamped`` palms at 1 kHz (1 % force noise) and one
``PoseStamped`` palm (or a ``JointState`` gripper width) at 100 Hz with 0.05 mm noise, three
ramp-hold-release squeezes of an object with the D and λ given; the ``edit_*`` hooks damage a
stream on purpose. Used by the bag tests of ``measure``, the CLI, the log clock and the fuzz suite.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
from mcap_ros2.writer import Writer

from deformctl.characterize import kelvin_voigt_piecewise_linear

HEADER_DEFS = """
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
"""


WRENCH_STAMPED = (
    "std_msgs/Header header\nWrench wrench\n"
    + HEADER_DEFS
    + """================================================================================
MSG: geometry_msgs/Wrench
Vector3 force
Vector3 torque
================================================================================
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
"""
)


POSE_STAMPED = (
    "std_msgs/Header header\nPose pose\n"
    + HEADER_DEFS
    + """================================================================================
MSG: geometry_msgs/Pose
Point position
Quaternion orientation
================================================================================
MSG: geometry_msgs/Point
float64 x
float64 y
float64 z
================================================================================
MSG: geometry_msgs/Quaternion
float64 x
float64 y
float64 z
float64 w
"""
)


JOINT_STATE = (
    "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\n"
    "float64[] effort\n" + HEADER_DEFS
)


EPOCH_NS = 1_700_000_000 * 1_000_000_000


LEFT, RIGHT, POSE, JOINTS = "/left/wrench", "/right/wrench", "/left/palm_pose", "/joint_states"


def recording(
    d_n_per_cm: float, lam_ns_per_cm: float, n_squeezes: int = 3, peak_force_n: float = 10.0
) -> tuple[np.ndarray, np.ndarray]:
    """Knots ``(time_s [K], force_n [K])`` of ``n`` ramp-hold-release squeezes with rests."""
    t, f = [0.0], [0.0]
    for _ in range(n_squeezes):
        t0 = t[-1] + 0.5
        t += [t0, t0 + 1.0, t0 + 2.6, t0 + 3.6]
        f += [0.0, peak_force_n, peak_force_n, 0.0]
    t.append(t[-1] + 1.5)
    f.append(0.0)
    return np.asarray(t), np.asarray(f)


def _stamp(t_ns: int) -> dict[str, int]:
    return {"sec": t_ns // 1_000_000_000, "nanosec": t_ns % 1_000_000_000}


def write_bag(
    path: Path,
    d_n_per_cm: float,
    lam_ns_per_cm: float,
    *,
    seed: int = 0,
    force_rate_hz: float = 1000.0,
    pose_rate_hz: float = 100.0,
    pose_offset_s: float = 0.003,
    joint_state: bool = False,
    n_squeezes: int = 3,
    edit_force: Callable[[np.ndarray, np.ndarray], None] | None = None,
    edit_pose: Callable[[np.ndarray, np.ndarray], None] | None = None,
    wrench_topics: tuple[str, ...] = (LEFT, RIGHT),
    receive_delay_s: float = 0.0,
) -> None:
    """Write a two-palm squeeze recording with known Kelvin–Voigt D and λ.

    The left palm starts at x = −0.05 m and moves +x by d/2 (toward the object centre); the
    right palm mirrors it. Pose is the left palm; force.x is +f on the left wrench,
    −f on the right one (``wrench_topics`` names them; one topic: the left palm only). With
    ``joint_state`` the position topic is a JointState whose joint
    ``gripper_width`` is the gap between the palms. Each message is logged ``receive_delay_s``
    after its header stamp (its MCAP ``log_time``, the recorder's receive time).
    """
    knots_t, knots_f = recording(d_n_per_cm, lam_ns_per_cm, n_squeezes)
    rng = np.random.default_rng(seed)
    k, c = d_n_per_cm * 100.0, lam_ns_per_cm * 100.0
    tf = np.arange(0.0, knots_t[-1], 1.0 / force_rate_hz)
    ff = np.interp(tf, knots_t, knots_f)
    fl = ff + rng.normal(0, 0.01 * knots_f.max(), tf.size)
    fr = -(ff + rng.normal(0, 0.01 * knots_f.max(), tf.size))
    tp = np.arange(pose_offset_s, knots_t[-1], 1.0 / pose_rate_hz)
    comp = kelvin_voigt_piecewise_linear(np.clip(tp, 0, knots_t[-1]), knots_t, knots_f, k, c)
    if joint_state:
        pos = 0.10 - comp + rng.normal(0, 5e-5, tp.size)
    else:
        pos = -0.05 + comp / 2.0 + rng.normal(0, 5e-5, tp.size)
    if edit_force is not None:
        edit_force(tf, fl)
    if edit_pose is not None:
        edit_pose(tp, pos)
    delay_ns = round(receive_delay_s * 1e9)
    with path.open("wb") as fh, Writer(fh) as w:
        ws = w.register_msgdef("geometry_msgs/msg/WrenchStamped", WRENCH_STAMPED)
        for topic, values in zip(wrench_topics, (fl, fr), strict=False):
            for ti, fi in zip(tf, values, strict=True):
                t_ns = EPOCH_NS + round(ti * 1e9)
                msg = {
                    "header": {"stamp": _stamp(t_ns), "frame_id": topic},
                    "wrench": {"force": {"x": fi, "y": 0.1, "z": -0.2}, "torque": {}},
                }
                w.write_message(topic, ws, msg, log_time=t_ns + delay_ns)
        if joint_state:
            js = w.register_msgdef("sensor_msgs/msg/JointState", JOINT_STATE)
            for ti, pi in zip(tp, pos, strict=True):
                t_ns = EPOCH_NS + round(ti * 1e9)
                msg = {
                    "header": {"stamp": _stamp(t_ns), "frame_id": ""},
                    "name": ["wrist", "gripper_width"],
                    "position": [0.3, pi],
                    "velocity": [],
                    "effort": [],
                }
                w.write_message(JOINTS, js, msg, log_time=t_ns + delay_ns)
        else:
            ps = w.register_msgdef("geometry_msgs/msg/PoseStamped", POSE_STAMPED)
            for ti, pi in zip(tp, pos, strict=True):
                t_ns = EPOCH_NS + round(ti * 1e9)
                msg = {
                    "header": {"stamp": _stamp(t_ns), "frame_id": "world"},
                    "pose": {"position": {"x": pi, "y": 0.0, "z": 0.2}, "orientation": {"w": 1.0}},
                }
                w.write_message(POSE, ps, msg, log_time=t_ns + delay_ns)


def _backwards_force(tf: np.ndarray, f: np.ndarray) -> None:
    tf[700] = tf[690]


def _nan_force(tf: np.ndarray, f: np.ndarray) -> None:
    f[1234] = math.nan
