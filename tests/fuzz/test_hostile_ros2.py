"""ROS 2 bags whose message definitions or payloads do not match the type name.

Every case ends in one ``error:`` line naming the bag, the topic, the type and the field (exit 65).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.writer import Writer as RawWriter
from mcap_ros2.writer import Writer
from typer.testing import CliRunner

from deformctl.cli import app
from tests._helpers.ros2_bags import (
    EPOCH_NS,
    HEADER_DEFS,
    JOINT_STATE,
    JOINTS,
    LEFT,
    POSE,
    POSE_STAMPED,
    WRENCH_STAMPED,
    _stamp,
    write_bag,
)

runner = CliRunner()
WRENCH, POSE_T, JS = (
    "geometry_msgs/msg/WrenchStamped",
    "geometry_msgs/msg/PoseStamped",
    "sensor_msgs/msg/JointState",
)


def _msg(definition: str, t_ns: int) -> dict[str, object]:
    """A message dict that fits ``definition`` (one of the test module's msgdefs)."""
    header = {"stamp": _stamp(t_ns), "frame_id": ""}
    if definition.startswith("Wrench wrench"):
        return {"wrench": {"force": {"x": 1.0}}}
    if definition is WRENCH_STAMPED:
        return {"header": header, "wrench": {"force": {"x": 1.0, "y": 0.0, "z": 0.0}}}
    if definition is POSE_STAMPED:
        return {"header": header, "pose": {"position": {"x": 0.0}}}
    if definition is JOINT_STATE:
        return {"header": header, "name": ["g"], "position": [0.1], "velocity": [], "effort": []}
    return {"header": header, "name": ["g"]}


def _bag(path: Path, wrench_def: str, pose_type: str, pose_def: str) -> Path:
    """A bag with a wrench topic and a position topic whose definitions we choose."""
    with path.open("wb") as fh, Writer(fh) as w:
        ws = w.register_msgdef(WRENCH, wrench_def)
        ps = w.register_msgdef(pose_type, pose_def)
        for i in range(20):
            t_ns = EPOCH_NS + i * 10_000_000
            w.write_message(LEFT, ws, _msg(wrench_def, t_ns), log_time=t_ns)
            w.write_message(POSE, ps, _msg(pose_def, t_ns), log_time=t_ns)
    return path


WRENCH_WITHOUT_HEADER = "Wrench wrench\n" + WRENCH_STAMPED.split("\n", 2)[2]
JOINT_STATE_WITHOUT_POSITION = "std_msgs/Header header\nstring[] name\n" + HEADER_DEFS
MISMATCHES = {
    "wrench without header": (WRENCH_WITHOUT_HEADER, POSE_T, POSE_STAMPED, "'header.stamp.sec'"),
    "wrench carrying a JointState": (JOINT_STATE, POSE_T, POSE_STAMPED, "'wrench.force'"),
    "pose carrying a JointState": (WRENCH_STAMPED, POSE_T, JOINT_STATE, "'pose.position'"),
    "JointState without position": (
        WRENCH_STAMPED,
        JS,
        JOINT_STATE_WITHOUT_POSITION,
        "'position'",
    ),
}


def _measure(bag: Path, out: Path, *, joint: bool = False) -> tuple[int, str]:
    argv = ["measure", "bag", str(bag), "--wrench-topic", LEFT]
    argv += ["--position-topic", JOINTS if joint else POSE, "--object-id", "x"]
    argv += ["--joint", "g"] if joint else []
    result = runner.invoke(app, [*argv, "--weight-n", "1", "-o", str(out)])
    return result.exit_code, result.stderr


def _one_line(stderr: str) -> str:
    assert stderr.startswith("error: "), stderr
    assert stderr.count("\n") == 1, stderr
    return stderr


@pytest.mark.parametrize("case", list(MISMATCHES))
def test_a_definition_that_does_not_match_its_type_is_named(case: str, tmp_path: Path) -> None:
    wrench_def, pose_type, pose_def, field = MISMATCHES[case]
    bag = _bag(tmp_path / "bag.mcap", wrench_def, pose_type, pose_def)
    if pose_type == JS:  # the JointState topic is the position topic
        bag = _rename_topic(bag, POSE, JOINTS)
    code, stderr = _measure(bag, tmp_path / "s.mcap", joint=pose_type == JS)
    assert code == 65, stderr
    line = _one_line(stderr)
    assert bag.name in line
    assert field in line
    assert "topic" in line
    assert not (tmp_path / "s.mcap").exists()


def _rename_topic(bag: Path, old: str, new: str) -> Path:
    return _rewrite(bag, bag.with_name("renamed.mcap"), topic=old, new_topic=new)


def _rewrite(
    src: Path,
    dst: Path,
    *,
    topic: str,
    edit: Callable[[bytes], bytes] = lambda b: b,
    new_topic: str | None = None,
    schema_data: bytes | None = None,
) -> Path:
    """Copy ``src`` message by message, editing the payloads (or the msgdef) of ``topic``."""
    with src.open("rb") as fin, dst.open("wb") as fout:
        reader = make_reader(fin)
        w = RawWriter(fout)
        w.start(profile="ros2")
        schema_ids: dict[int, int] = {}
        channel_ids: dict[int, int] = {}
        for schema, channel, message in reader.iter_messages():
            if schema is not None and schema.id not in schema_ids:
                data = schema_data if schema_data is not None and channel.topic == topic else None
                schema_ids[schema.id] = w.register_schema(
                    schema.name, schema.encoding, data if data is not None else schema.data
                )
            if channel.id not in channel_ids:
                name = new_topic if new_topic is not None and channel.topic == topic else None
                channel_ids[channel.id] = w.register_channel(
                    name or channel.topic,
                    channel.message_encoding,
                    schema_ids[channel.schema_id],
                )
            data = edit(message.data) if channel.topic == topic else message.data
            w.add_message(channel_ids[channel.id], message.log_time, data, message.publish_time)
        w.finish()
    return dst


@pytest.fixture(scope="module")
def good_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("bag") / "good.mcap"
    write_bag(path, 30.0, 5.0, n_squeezes=1, force_rate_hz=200.0, pose_rate_hz=50.0)
    return path


PAYLOADS: dict[str, Callable[[bytes], bytes]] = {
    "truncated": lambda b: b[: len(b) // 2],
    "header only": lambda b: b[:4],
    "empty": lambda b: b"",
    "bad encapsulation": lambda b: b"\x07\x07" + b[2:],
}


@pytest.mark.parametrize("case", list(PAYLOADS))
def test_a_bad_cdr_payload_is_named(case: str, good_bag: Path, tmp_path: Path) -> None:
    bag = _rewrite(good_bag, tmp_path / "bag.mcap", topic=LEFT, edit=PAYLOADS[case])
    code, stderr = _measure(bag, tmp_path / "s.mcap")
    assert code == 65, stderr
    line = _one_line(stderr)
    assert "bag.mcap" in line
    assert f"topic '{LEFT}' ({WRENCH})" in line
    assert "message 0" in line


@pytest.mark.parametrize(
    "msgdef", [b"this is not ( a message definition", b"", b"\xff\xfe", b"float64 x\n" * 3]
)
def test_an_unparseable_or_foreign_definition_is_named(
    msgdef: bytes, good_bag: Path, tmp_path: Path
) -> None:
    bag = _rewrite(good_bag, tmp_path / "bag.mcap", topic=LEFT, schema_data=msgdef)
    code, stderr = _measure(bag, tmp_path / "s.mcap")
    assert code == 65, stderr
    line = _one_line(stderr)
    assert "bag.mcap" in line
    assert f"topic '{LEFT}'" in line
