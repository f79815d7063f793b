"""A lift log's samples are parsed and checked as columns, and refused as message by message.

Reading a lift log parses its many sample messages at once (``jsonsafe.loads_objects``) and
checks them in one pass (``schema.message_columns``) instead of one JSON Schema check each; a
log these do not vouch for is read message by message, so what is read, and the first bad
message an error names, are the same either way.
"""

from __future__ import annotations

import io
import json
from typing import Any

import pytest
from mcap.writer import Writer

from deformctl.artifacts.mcap import contents as mcap_contents
from deformctl.artifacts.mcap import lift_attempts_from_contents, load_mcap
from deformctl.artifacts.schema import json_schema_bytes
from deformctl.errors import DeformctlError

BASE = {"object_id": "A", "attempt_index": 0, "grip_force_n": 1.0, "normal_force_n": 1.0}
FIELDS = ("palm_z_m", "object_com_z_m", "slip_m", "friction_force_n")


def _sample(i: int, **edits: Any) -> bytes:
    return json.dumps({**BASE, "time_s": 0.01 * i, **dict.fromkeys(FIELDS, 0.001 * i), **edits})


def _log(samples: list[bytes | str]) -> bytes:
    """A lift log of one attempt of object A with ``samples`` and its result."""
    result = {k: BASE[k] for k in ("object_id", "attempt_index", "grip_force_n")}
    result |= {"lifted": True, "slip_m": 0.0, "details": {}}
    buffer = io.BytesIO()
    w = Writer(buffer, enable_data_crcs=True)
    w.start()
    w.add_metadata("deformctl", {"kind": "lift_log", "format_version": "1"})
    for name, topic, payloads in (
        ("lift_attempt_sample", "/lift/attempt_sample", samples),
        ("lift_attempt_result", "/lift/attempt_result", [json.dumps(result)]),
    ):
        title = "".join(p.title() for p in name.split("_"))
        sid = w.register_schema(f"deformctl.{title}", "jsonschema", json_schema_bytes(name))
        cid = w.register_channel(topic, "json", sid)
        for i, m in enumerate(payloads):
            w.add_message(cid, i, m.encode() if isinstance(m, str) else m, i)
    w.finish()
    return buffer.getvalue()


def _read(raw: bytes) -> tuple[str, Any]:
    """``("ok", samples read)`` or ``("error", its message)``."""
    try:
        (attempt,) = lift_attempts_from_contents(load_mcap(raw, "l.mcap"))
    except DeformctlError as err:
        return "error", str(err)
    series = attempt.outcome.series
    assert series is not None
    return "ok", [list(series.time_s), list(series.slip_m)]


GOOD = [_sample(i) for i in range(6)]
LOGS = {
    "clean": GOOD,
    "a bound, then bad JSON": [*GOOD[:2], _sample(2, slip_m=-1e9), GOOD[3], "{not json", GOOD[5]],
    "bad JSON, then a bound": [GOOD[0], "{not json", GOOD[2], _sample(3, slip_m=-1e9)],
    "an unknown key": [*GOOD[:3], _sample(3, extra=1.0)],
    "a missing key": [*GOOD[:4], json.dumps({k: v for k, v in BASE.items() if k != "object_id"})],
    "a text for a number": [GOOD[0], _sample(1, palm_z_m="0.1")],
    "not an object": [GOOD[0], "[1, 2]"],
    "a NaN": [GOOD[0], _sample(1, slip_m=float("nan")), GOOD[2]],
    "a number no float holds": [GOOD[0], _sample(1).replace('"slip_m": 0.001', '"slip_m": 1e999')],
    "a nested object": [GOOD[0], _sample(1, slip_m={"m": 0.0})],
    "two objects in one": [GOOD[0], _sample(1) + _sample(2)],
}


@pytest.mark.parametrize("name", LOGS)
def test_a_lift_log_reads_as_message_by_message(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    raw = _log(LOGS[name])
    fast = _read(raw)
    monkeypatch.setattr(mcap_contents, "message_columns", lambda *_: None)  # one by one
    monkeypatch.setattr(mcap_contents.jsonsafe, "loads_objects", lambda *_: None)
    assert fast == _read(raw)
    assert (fast[0] == "ok") == (name == "clean")  # the bad logs are refused
    if name == "a bound, then bad JSON":
        assert "message 2 on /lift/attempt_sample" in fast[1]


def test_a_clean_log_checks_no_sample_one_by_one(monkeypatch: pytest.MonkeyPatch) -> None:
    checked: list[str] = []
    real = mcap_contents.validate_message
    monkeypatch.setattr(
        mcap_contents,
        "validate_message",
        lambda name, *a, **k: checked.append(name) or real(name, *a, **k),
    )
    parses: list[object] = []
    loads = mcap_contents.jsonsafe.loads
    contents = load_mcap(_log(GOOD), "l.mcap")
    monkeypatch.setattr(
        mcap_contents.jsonsafe, "loads", lambda *a, **k: parses.append(a) or loads(*a, **k)
    )
    assert len(lift_attempts_from_contents(contents)) == 1
    assert "lift_attempt_sample" not in checked
    assert len(parses) < len(GOOD)  # the samples were parsed at once
    assert checked == ["lift_attempt_result"]  # not a flat schema: checked one by one
