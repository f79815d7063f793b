"""Write the sample rig recordings of ``datasets/examples/``: a ROS 2 bag and a CSV export.

Usage::

    python examples/make_sample_recordings.py OUTDIR

writes two recordings of Kelvin–Voigt objects whose D and λ are known, so that ``measure`` and
``characterize`` can be tried on them at once:

* ``OUTDIR/gripper.mcap``: a ROS 2 bag (MCAP, ``ros2msg``/``cdr``, written with
  mcap-ros2-support) of a parallel gripper squeezing a sponge (D = 8 N/cm, λ = 1.5 N·s/cm) twice,
  9 s from 2024-06-01T12:00:00Z at 250 Hz: ``/left/wrench`` and ``/right/wrench``
  (``geometry_msgs/msg/WrenchStamped``, ±f along x, 0.02 N noise), ``/left/palm_pose``
  (``geometry_msgs/msg/PoseStamped``, the left palm's x; the right palm mirrors it) and
  ``/joint_states`` (``sensor_msgs/msg/JointState``, joint ``gripper_width``: the gap between
  the palms, 20 µm noise). Every message is logged 3 ms after its header stamp (the recorder's
  receive time); ``measure`` keeps the header stamps as the squeeze log's ``log_time``.
* ``OUTDIR/utm_export.csv``: a universal testing machine's export with two header rows (names
  ``Time,Force,Crosshead``, then units ``(s),[kN],(mm)``): one force-controlled load–hold–unload
  cycle of a foam block (D = 20 N/cm, λ = 3 N·s/cm) at 100 Hz, the crosshead travel being the
  compression.

The same script gives the same files (seeded noise, fixed stamps); then::

    deformctl measure bag OUTDIR/gripper.mcap --wrench-topic /left/wrench \\
        --wrench-topic /right/wrench --position-topic /joint_states --joint gripper_width \\
        --position-is gap --object-id sponge --weight-n 0.6 -o sponge.mcap
    deformctl measure csv OUTDIR/utm_export.csv \\
        --columns time=Time,force=Force,compression=Crosshead \\
        --object-id foam --weight-n 0.7 -o foam.mcap
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from mcap_ros2.writer import Writer

from deformctl.characterize import kelvin_voigt_piecewise_linear

START_NS = 1_717_243_200 * 1_000_000_000  #: 2024-06-01T12:00:00Z, the bag's first stamp
RECEIVE_DELAY_NS = 3_000_000  #: each message is logged 3 ms after its header stamp
BAG_RATE_HZ = 250.0
SPONGE = (8.0, 1.5)  #: D N/cm, λ N·s/cm
FOAM = (20.0, 3.0)
HALF_GAP_M = 0.05  #: each palm's distance from the object centre before contact

_HEADER = """
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
"""
_VECTOR3 = """================================================================================
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
"""
WRENCH_STAMPED = (
    "std_msgs/Header header\nWrench wrench\n"
    + _HEADER
    + "================================================================================\n"
    "MSG: geometry_msgs/Wrench\nVector3 force\nVector3 torque\n" + _VECTOR3
)
POSE_STAMPED = (
    "std_msgs/Header header\nPose pose\n"
    + _HEADER
    + "================================================================================\n"
    "MSG: geometry_msgs/Pose\nPoint position\nQuaternion orientation\n"
    "================================================================================\n"
    "MSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n"
    "================================================================================\n"
    "MSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n"
)
JOINT_STATE = (
    "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\n"
    "float64[] effort\n" + _HEADER
)


def _squeeze(
    knots_t: list[float], knots_f: list[float], coefficients: tuple[float, float], rate_hz: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(t s, f N, d m)`` of a Kelvin–Voigt object under a piecewise-linear force."""
    kt, kf = np.asarray(knots_t), np.asarray(knots_f)
    t = np.arange(round(kt[-1] * rate_hz) + 1) / rate_hz
    d = kelvin_voigt_piecewise_linear(t, kt, kf, coefficients[0] * 100.0, coefficients[1] * 100.0)
    return t, np.interp(t, kt, kf), d


def _stamp(t_ns: int) -> dict[str, int]:
    return {"sec": t_ns // 1_000_000_000, "nanosec": t_ns % 1_000_000_000}


def write_bag(path: Path) -> None:
    """The gripper bag: two squeezes of a sponge (peaks 6 N and 4 N), see the module docstring."""
    t, f, d = _squeeze(
        [0.0, 1.0, 2.0, 3.5, 4.3, 5.0, 6.0, 7.5, 8.3, 9.0],
        [0.0, 0.0, 6.0, 6.0, 0.0, 0.0, 4.0, 4.0, 0.0, 0.0],
        SPONGE,
        BAG_RATE_HZ,
    )
    rng = np.random.default_rng(15)
    left = f + rng.normal(0.0, 0.02, t.size)
    right = -(f + rng.normal(0.0, 0.02, t.size))
    d_seen = d + rng.normal(0.0, 20e-6, t.size)
    stamps = [START_NS + round(ti * 1e9) for ti in t]
    with path.open("wb") as fh, Writer(fh) as w:
        wrench = w.register_msgdef("geometry_msgs/msg/WrenchStamped", WRENCH_STAMPED)
        pose = w.register_msgdef("geometry_msgs/msg/PoseStamped", POSE_STAMPED)
        joints = w.register_msgdef("sensor_msgs/msg/JointState", JOINT_STATE)
        for i, t_ns in enumerate(stamps):
            at = t_ns + RECEIVE_DELAY_NS
            for topic, frame, fx in (("/left/wrench", "left_palm", left[i]),
                                     ("/right/wrench", "right_palm", right[i])):  # fmt: skip
                msg = {
                    "header": {"stamp": _stamp(t_ns), "frame_id": frame},
                    "wrench": {"force": {"x": float(fx), "y": 0.01, "z": -0.02}, "torque": {}},
                }
                w.write_message(topic, wrench, msg, log_time=at, publish_time=t_ns)
            x = -HALF_GAP_M + float(d_seen[i]) / 2.0
            msg = {
                "header": {"stamp": _stamp(t_ns), "frame_id": "base_link"},
                "pose": {"position": {"x": x, "y": 0.0, "z": 0.12}, "orientation": {"w": 1.0}},
            }
            w.write_message("/left/palm_pose", pose, msg, log_time=at, publish_time=t_ns)
            msg = {
                "header": {"stamp": _stamp(t_ns), "frame_id": ""},
                "name": ["wrist", "gripper_width"],
                "position": [0.0, 2.0 * HALF_GAP_M - float(d_seen[i])],
                "velocity": [],
                "effort": [],
            }
            w.write_message("/joint_states", joints, msg, log_time=at, publish_time=t_ns)


def write_csv(path: Path) -> None:
    """The testing machine's export: one load–hold–unload cycle of foam to 20 N at 100 Hz."""
    t, f, d = _squeeze(
        [0.0, 0.5, 2.5, 4.5, 6.5, 7.0], [0.0, 0.0, 20.0, 20.0, 0.0, 0.0], FOAM, 100.0
    )
    rng = np.random.default_rng(16)
    f_kn = (f + rng.normal(0.0, 0.05, t.size)) / 1000.0
    d_mm = 1000.0 * (d + rng.normal(0.0, 5e-6, t.size))
    lines = ["Time,Force,Crosshead", "(s),[kN],(mm)"]
    lines += [f"{a:.2f},{b:.6f},{c:.4f}" for a, b, c in zip(t, f_kn, d_mm, strict=True)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("outdir", type=Path)
    out = parser.parse_args().outdir
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        sys.exit(f"error: {out}: cannot make the folder ({err.strerror})")
    write_bag(out / "gripper.mcap")
    write_csv(out / "utm_export.csv")
    print(f"wrote {out / 'gripper.mcap'} and {out / 'utm_export.csv'}")


if __name__ == "__main__":
    main()
