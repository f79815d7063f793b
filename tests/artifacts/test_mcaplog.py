"""MCAP squeeze and lift logs: round trips, layout, and refusal of damaged files."""

from __future__ import annotations

import io
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.writer import Writer

from deformctl.artifacts import (
    read_lift_log,
    read_squeeze_log,
    write_lift_log,
    write_squeeze_log,
)
from deformctl.artifacts.mcap import LOG_EPOCH_NS, decode_provenance, load_mcap
from deformctl.artifacts.schema import json_schema_bytes
from deformctl.errors import EXIT_DATAERR, InputDataError, OutputExistsError, SchemaError
from deformctl.lift.search import LiftAttempt
from deformctl.series import SqueezeSeries, TrialOutcome
from tests._helpers.builders import make_attempts, make_provenance, make_squeezes

OBJECTS = [
    {"object_id": "A", "weight_n": 0.7, "friction_mu": 0.5, "material_damping_ns_per_cm": math.nan},
    {"object_id": "B", "weight_n": 1.4, "friction_mu": 0.5, "name": "cotton"},
]


def _write_squeeze(path: Path, n: int = 5) -> list[SqueezeSeries]:
    squeezes = make_squeezes(n)
    write_squeeze_log(path, OBJECTS, squeezes, provenance=make_provenance())
    return squeezes


def _objects_equal(a: list[dict[str, object]], b: list[dict[str, object]]) -> bool:
    def norm(o: dict[str, object]) -> dict[str, object]:
        return {k: "nan" if isinstance(v, float) and math.isnan(v) else v for k, v in o.items()}

    return [norm(x) for x in a] == [norm(x) for x in b]


def test_squeeze_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "squeeze.mcap"
    squeezes = _write_squeeze(path)
    objects, back = read_squeeze_log(path)
    assert _objects_equal(objects, OBJECTS)
    assert len(back) == len(squeezes)
    for a, b in zip(squeezes, back, strict=True):
        assert (a.object_id, a.squeeze_index) == (b.object_id, b.squeeze_index)
        for name in ("time_s", "force_n", "compression_m", "commanded_force_n"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        for name in ("palm_left_x_m", "palm_right_x_m"):
            if getattr(a, name) is None:
                assert getattr(b, name) is None
            else:
                np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    data = path.read_bytes()
    assert decode_provenance(load_mcap(data, path)) == make_provenance()


def test_squeeze_log_layout_is_foxglove_json(tmp_path: Path) -> None:
    """Read with the mcap library alone: encodings, schema bytes, one sample per message."""
    path = tmp_path / "squeeze.mcap"
    squeezes = _write_squeeze(path, n=3)
    with path.open("rb") as fh:
        reader = make_reader(fh)
        messages = list(reader.iter_messages(log_time_order=False))
    with path.open("rb") as fh:
        meta = {m.name: m.metadata for m in make_reader(fh).iter_metadata()}
    assert meta["deformctl"] == {"kind": "squeeze_log", "format_version": "1"}
    assert json.loads(meta["provenance"]["seed"]) == 7
    assert len(messages) == sum(len(s) for s in squeezes) == 12
    schema, channel, _ = messages[0]
    assert channel.topic == "/squeeze/A"  # one channel per object
    assert [c.topic for _, c, _ in messages[6:7]] == ["/squeeze/B"]
    assert channel.message_encoding == "json"
    assert schema is not None
    assert schema.encoding == "jsonschema"
    assert schema.data == json_schema_bytes("squeeze_sample")
    assert json.loads(schema.data)["properties"]["force_n"]["x-unit"] == "N"
    # Simulated squeezes lie end to end from 2000-01-01 with a 1 s gap: 0, 0.25, 0.5 s each.
    times = [m.log_time for _, _, m in messages]
    expected = [k * 1_500_000_000 + i * 250_000_000 for k in range(4) for i in range(3)]
    assert times == [LOG_EPOCH_NS + t for t in expected]
    assert LOG_EPOCH_NS == 946_684_800_000_000_000  # 2000-01-01T00:00:00Z
    first = json.loads(messages[0][2].data)
    assert first["object_id"] == "A"
    assert first["compression_m"] == squeezes[0].compression_m[0]


def test_lift_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "lift.mcap"
    attempts = make_attempts()
    write_lift_log(path, OBJECTS, attempts, provenance=make_provenance())
    objects, back = read_lift_log(path)
    assert _objects_equal(objects, OBJECTS)
    assert [(a.object_id, a.attempt_index) for a in back] == [("A", 0), ("A", 1)]
    first, second = back
    assert first.outcome.grip_force_n == 0.7
    assert first.outcome.lifted is False
    assert first.outcome.slip_m == 0.0125
    assert first.outcome.details == {"note": "slipped"}
    assert first.outcome.series is not None
    src = attempts[0].outcome.series
    assert src is not None
    for name in ("time_s", "palm_z_m", "object_com_z_m", "slip_m", "friction_force_n"):
        np.testing.assert_array_equal(getattr(first.outcome.series, name), getattr(src, name))
    assert second.outcome.lifted is True
    assert math.isnan(second.outcome.slip_m)
    assert second.outcome.series is None


def _log_times(path: Path) -> list[tuple[str, int]]:
    with path.open("rb") as fh:
        return [(c.topic, m.log_time) for _, c, m in make_reader(fh).iter_messages()]


def test_squeezes_with_a_source_clock_keep_it_and_time_never_decreases(tmp_path: Path) -> None:
    t = np.array([0.0, 0.5, 1.0])
    start = 1_700_000_000 * 10**9
    squeezes = [
        SqueezeSeries("A", 0, t, t, t, start_time_ns=start),
        SqueezeSeries("A", 1, t, t, t, start_time_ns=start + 1_200_000_000),  # 0.2 s after
        SqueezeSeries("A", 2, t, t, t, start_time_ns=start),  # claims to overlap: clamped
    ]
    path = tmp_path / "bag.mcap"
    write_squeeze_log(path, [{"object_id": "A"}], squeezes, provenance=None)
    times = [ns for _, ns in _log_times(path)]
    half = 500_000_000
    assert times[:6] == [start, start + half, start + 2 * half, *(start + 1_200_000_000 + k * half
                                                                   for k in range(3))]  # fmt: skip
    assert times[6] == times[5]
    assert times == sorted(times)
    out = tmp_path / "epoch.mcap"
    write_squeeze_log(out, [{"object_id": "A"}], [SqueezeSeries("A", 0, t, t, t)],
                      provenance=None, epoch_ns=5 * 10**9)  # fmt: skip
    assert _log_times(out)[0] == ("/squeeze/A", 5 * 10**9)


def test_lift_log_has_a_channel_per_object_and_rig_attempts_keep_their_wall_clock(
    tmp_path: Path,
) -> None:
    sim = make_attempts()
    wall = 1_750_000_000 * 10**9
    rig = [LiftAttempt("B", 0, TrialOutcome(1.4, True, 0.0, None, {}, start_time_ns=wall))]
    path = tmp_path / "lift.mcap"
    write_lift_log(path, OBJECTS, [*sim, *rig], provenance=None)
    logged = _log_times(path)
    topics = [topic for topic, _ in logged]
    assert topics == ["/lift/A/attempt_sample"] * 4 + ["/lift/A/attempt_result"] * 2 + [
        "/lift/B/attempt_result"
    ]
    assert logged[0][1] == LOG_EPOCH_NS
    assert logged[-1][1] == wall
    _, back = read_lift_log(path)
    assert [(a.object_id, a.attempt_index) for a in back] == [("A", 0), ("A", 1), ("B", 0)]


def test_a_message_on_another_objects_channel_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "hand.mcap"
    _hand_written(path, [GOOD], topic="/squeeze/B")
    with pytest.raises(SchemaError, match="object_id 'A' on the channel of 'B'"):
        read_squeeze_log(path)


def test_read_from_stdin(tmp_path: Path) -> None:
    path = tmp_path / "squeeze.mcap"
    _write_squeeze(path)
    old = sys.stdin
    sys.stdin = io.TextIOWrapper(io.BytesIO(path.read_bytes()))
    try:
        _, back = read_squeeze_log("-")
    finally:
        sys.stdin = old
    assert len(back) == 4


def test_wrong_kind(tmp_path: Path) -> None:
    path = tmp_path / "lift.mcap"
    write_lift_log(path, OBJECTS, make_attempts(), provenance=None)
    with pytest.raises(SchemaError, match="is a lift_log, expected a squeeze_log"):
        read_squeeze_log(path)


def test_every_truncation_and_every_byte_flip_is_refused(tmp_path: Path) -> None:
    """Exhaustive over a small log: each prefix and each single-byte flip is an error (65)."""
    path = tmp_path / "squeeze.mcap"
    _write_squeeze(path, n=2)
    data = path.read_bytes()
    assert len(data) < 6000
    for cut in range(len(data)):
        with pytest.raises(InputDataError) as info:
            load_mcap(data[:cut], "t.mcap")
        assert info.value.exit_code == EXIT_DATAERR
    bad = tmp_path / "bad.mcap"
    for pos in range(len(data)):
        flipped = bytearray(data)
        flipped[pos] ^= 0xFF
        bad.write_bytes(bytes(flipped))
        with pytest.raises(InputDataError) as info:
            read_squeeze_log(bad)
        assert str(info.value).startswith(f"{bad}: ")
        assert "\n" not in str(info.value)


def test_not_mcap(tmp_path: Path) -> None:
    bad = tmp_path / "squeeze.mcap"
    bad.write_text("object_id,time_s\nA,0\n")
    with pytest.raises(InputDataError) as info:
        read_squeeze_log(bad)
    assert str(info.value) == f"{bad}: not an MCAP file (bad magic bytes)"


def _hand_written(path: Path, messages: list[dict[str, object]], topic: str = "/squeeze") -> None:
    """A well-formed MCAP (valid CRCs) whose messages we choose, written with mcap directly
    (on the first layout's shared ``/squeeze`` topic unless ``topic`` says otherwise)."""
    with path.open("wb") as fh:
        w = Writer(fh, enable_data_crcs=True)
        w.start()
        w.add_metadata("deformctl", {"kind": "squeeze_log", "format_version": "1"})
        sid = w.register_schema(
            "deformctl.SqueezeSample", "jsonschema", json_schema_bytes("squeeze_sample")
        )
        cid = w.register_channel(topic, "json", sid)
        for i, m in enumerate(messages):
            w.add_message(cid, i, json.dumps(m).encode(), i)
        w.finish()


GOOD = {"object_id": "A", "squeeze_index": 0, "time_s": 0.0, "force_n": 1.0, "compression_m": 0.0}


@pytest.mark.parametrize(
    ("messages", "match"),
    [
        ([{k: v for k, v in GOOD.items() if k != "force_n"}], "'force_n' is a required property"),
        ([{**GOOD, "force_n": "1.0"}], "field 'force_n': message 0 on /squeeze"),
        ([{**GOOD, "squeeze_index": -1}], "field 'squeeze_index'"),
        ([{**GOOD, "force_kn": 1.0}], "Additional properties"),
        ([GOOD, {**GOOD, "time_s": 0.1, "palm_left_x_m": 0.0}], "field 'palm_left_x_m'"),
        ([{**GOOD, "time_s": 1.0}, GOOD], "field 'time_s': object 'A' squeeze 0: time_s decreases"),
    ],
)
def test_message_schema_violations(
    tmp_path: Path, messages: list[dict[str, object]], match: str
) -> None:
    path = tmp_path / "hand.mcap"
    _hand_written(path, messages)
    with pytest.raises(SchemaError, match=match) as info:
        read_squeeze_log(path)
    assert info.value.exit_code == EXIT_DATAERR


def test_hand_written_valid_log_reads(tmp_path: Path) -> None:
    path = tmp_path / "hand.mcap"
    _hand_written(path, [GOOD, {**GOOD, "time_s": 0.5, "force_n": 2.0}])
    objects, back = read_squeeze_log(path)
    assert objects == []
    assert back[0].force_n.tolist() == [1.0, 2.0]


def test_existing_output_and_failed_write_leave_nothing(tmp_path: Path) -> None:
    path = tmp_path / "squeeze.mcap"
    path.write_bytes(b"old")
    with pytest.raises(OutputExistsError):
        write_squeeze_log(path, OBJECTS, make_squeezes(), provenance=None)
    assert path.read_bytes() == b"old"
    path.unlink()
    good = make_squeezes()
    bad = SqueezeSeries("C", 0, [0.0, 1.0], [0.0, math.nan], [0.0, 0.0])
    with pytest.raises(InputDataError, match="object 'C' squeeze 0: force_n has non-finite"):
        write_squeeze_log(path, OBJECTS, [*good, bad], provenance=None)
    assert list(tmp_path.iterdir()) == []


def test_sample_messages_are_exactly_json_dumps_bytes(tmp_path: Path) -> None:
    # The writer encodes samples from a template; each message must be the very bytes that
    # json.dumps gives for its content (compact separators, floats as repr, same key order).
    path = tmp_path / "s.mcap"
    series = SqueezeSeries(
        'A"quoted\\', 0, [0.0, 1e-3, 2.5e-3], [0.1, 1 / 3, 2e-17], [0.0, 1e300, -0.0]
    )
    write_squeeze_log(path, [{"object_id": 'A"quoted\\'}], [series], provenance=None)
    with path.open("rb") as fh:
        datas = [m.data for _, _, m in make_reader(fh).iter_messages()]
    assert len(datas) == 3
    for data in datas:
        assert data == json.dumps(json.loads(data), separators=(",", ":")).encode()
    assert json.loads(datas[1])["force_n"] == 1 / 3


def test_samples_and_scene_messages_merge_in_log_time_order_samples_first_at_ties() -> None:
    """add_samples' merge: scene messages before the first sample of a later time, a sample
    before a scene message of the same time, each topic numbered 0, 1, 2, ... in order."""
    from deformctl.artifacts.mcap.contents import LIFT_SAMPLE, PALMS_TOPIC, lift_topic
    from deformctl.artifacts.mcap.write import KIND_LIFT, _LogWriter

    buf = io.BytesIO()
    log = _LogWriter(buf, KIND_LIFT, None, 0)  # type: ignore[arg-type]
    topic = lift_topic("A", LIFT_SAMPLE)
    scene = [(t, PALMS_TOPIC, b"{}") for t in (5, 10, 25, 99)]
    log.add_samples(topic, [10, 20, 30], {"object_id": "A"}, {"x": [1.0, 2.5, 3.0]}, scene)
    log.add_samples(topic, [40], {"object_id": "A"}, {"x": [4.0]}, [(40, PALMS_TOPIC, b"{}")])
    log.finish()
    buf.seek(0)
    messages = make_reader(buf).iter_messages(log_time_order=False)
    got = [(c.topic == topic, m.log_time, m.sequence, m.data) for _, c, m in messages]
    order = ["S5/0", "A10/0", "S10/1", "A20/1", "S25/2", "A30/2", "S99/3", "A40/3", "S40/4"]
    assert [f"{'A' if a else 'S'}{t}/{q}" for a, t, q, _ in got] == order
    assert got[1][3] == b'{"object_id":"A","x":1.0}'
    assert got[3][3] == b'{"object_id":"A","x":2.5}'
