"""The bulk squeeze-log reader is the reference reader, only faster.

``read_squeeze_log`` first tries the bulk reader (its own record loop, the samples parsed as one
JSON array and checked a column at a time) and reads the file the reference way (``load_mcap``,
one JSON document and one JSON-Schema check per sample) whenever the bulk reader cannot vouch
for it. The tests: the bulk reader takes every log deformctl writes and returns the reference
reader's objects and squeezes bit for bit; on generated hostile logs it returns either that or
nothing, never something the reference reader would refuse; and its pieces
(:func:`jsonsafe.loads_objects`, :func:`schema.message_columns`) never accept what the per-item
checks refuse.
"""

from __future__ import annotations

import contextlib
import io
import json
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mcap.writer import CompressionType, Writer

from deformctl import jsonsafe
from deformctl.artifacts.mcap import bulk as mcap_bulk
from deformctl.artifacts.mcap import (
    decode_objects,
    load_mcap,
    read_squeeze_log,
    squeezes_from_contents,
    write_squeeze_log,
)
from deformctl.artifacts.schema import json_schema_bytes, message_columns, validate_message
from deformctl.errors import DeformctlError, SchemaError
from deformctl.series import SqueezeSeries
from tests._helpers.builders import make_provenance, make_squeezes

DATA = Path(__file__).resolve().parents[1] / "data"
FIELDS = ("time_s", "force_n", "compression_m", "commanded_force_n", "palm_left_x_m",
          "palm_right_x_m")  # fmt: skip
FUZZ = settings(
    max_examples=300,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
    database=None,
)


def _reference(data: bytes, name: str) -> tuple[list[dict[str, Any]], list[SqueezeSeries]]:
    contents = load_mcap(data, name)
    squeezes = squeezes_from_contents(contents)
    return decode_objects(contents), squeezes


def _same(
    a: tuple[list[Any], list[SqueezeSeries]], b: tuple[list[Any], list[SqueezeSeries]]
) -> None:
    """The same objects and squeezes, every array bit for bit."""
    assert json.dumps(a[0], sort_keys=True) == json.dumps(b[0], sort_keys=True)  # NaN too
    assert len(a[1]) == len(b[1])
    for x, y in zip(a[1], b[1], strict=True):
        assert (x.object_id, x.squeeze_index, x.start_time_ns) == (
            y.object_id,
            y.squeeze_index,
            y.start_time_ns,
        )
        assert type(x.squeeze_index) is type(y.squeeze_index)
        for key in FIELDS:
            u, v = getattr(x, key), getattr(y, key)
            assert (u is None) == (v is None), key
            if u is not None:
                assert u.dtype == v.dtype == np.float64
                assert u.tobytes() == v.tobytes(), key


def _agree(data: bytes, name: str = "s.mcap") -> bool:
    """The bulk reader returns the reference result or nothing; True when it returned one."""
    bulk = mcap_bulk._bulk_squeeze_log(data, name)
    try:
        ref = _reference(data, name)
    except DeformctlError:
        assert bulk is None, "the bulk reader accepted a log the reference reader refuses"
        return False
    if bulk is not None:
        _same(bulk, ref)
    return bulk is not None


def _written(tmp_path: Path, squeezes: list[SqueezeSeries], objects: list[dict[str, Any]]) -> bytes:
    path = tmp_path / "s.mcap"
    write_squeeze_log(path, objects, squeezes, provenance=make_provenance(), force=True)
    return path.read_bytes()


def test_every_log_deformctl_writes_is_read_in_bulk(tmp_path: Path) -> None:
    data = (DATA / "squeeze_2x2.mcap").read_bytes()  # the golden log: two layouts' worth
    assert _agree(data)
    squeezes = make_squeezes(n=40)  # palm positions on two of the four squeezes only
    objects = [{"object_id": "A", "weight_n": 1.0}, {"object_id": "B", "weight_n": float("nan")}]
    assert _agree(_written(tmp_path, squeezes, objects))
    plain = [SqueezeSeries(s.object_id, s.squeeze_index, s.time_s, s.force_n, s.compression_m)
             for s in squeezes]  # fmt: skip
    assert _agree(_written(tmp_path, plain, objects))


def test_a_simulated_sweep_log_is_read_in_bulk(tmp_path: Path) -> None:
    """The log a ``measure --sim`` sweep writes (via the CLI): bulk, and the reference's result."""
    from typer.testing import CliRunner

    from deformctl.cli import app

    out = tmp_path / "sq"
    result = CliRunner().invoke(
        app,
        ["measure", "sim", str(DATA.parents[1] / "datasets" / "paper" / "objects.csv"),
         "--seed", "0", "-o", f"{out}/", "--workers", "1", "--partition-size", "2"],
    )  # fmt: skip
    assert result.exit_code == 0, result.stderr
    logs = sorted((out / "_logs").glob("part-*.mcap"))
    assert len(logs) == 2
    for log in logs:
        assert _agree(log.read_bytes(), str(log))


def test_the_old_layout_and_other_topics(tmp_path: Path) -> None:
    """Every object on ``/squeeze`` (the first layout), and a topic that is not a sample."""
    buffer = io.BytesIO()
    w = Writer(buffer, compression=CompressionType.ZSTD, enable_data_crcs=True)
    w.start()
    w.add_metadata("deformctl", {"kind": "squeeze_log", "format_version": "1"})
    w.add_metadata("object", {"object_id": '"A"'})
    sid = w.register_schema("deformctl.SqueezeSample", "jsonschema",
                            json_schema_bytes("squeeze_sample"))  # fmt: skip
    cid = w.register_channel("/squeeze", "json", sid)
    other = w.register_channel("/camera/notes", "json", 0)
    for i in range(30):
        msg = {"object_id": "AB"[i % 2], "squeeze_index": 0, "time_s": i // 2 * 0.01,
               "force_n": 0.5 * i, "compression_m": 1e-4 * i}  # fmt: skip
        w.add_message(cid, i, json.dumps(msg).encode(), i)
        w.add_message(other, i, b'{"note": [1, 2]}', i)
    w.finish()
    assert _agree(buffer.getvalue())


def test_refusals_are_the_reference_readers(tmp_path: Path) -> None:
    """A log the bulk reader gives up on is read the reference way: same error, same words."""
    log = tmp_path / "s.mcap"
    buffer = io.BytesIO()
    w = Writer(buffer, enable_data_crcs=True)
    w.start()
    w.add_metadata("deformctl", {"kind": "squeeze_log", "format_version": "1"})
    sid = w.register_schema("deformctl.SqueezeSample", "jsonschema",
                            json_schema_bytes("squeeze_sample"))  # fmt: skip
    cid = w.register_channel("/squeeze/A", "json", sid)
    good = '{"object_id":"A","squeeze_index":0,"time_s":%s,"force_n":1.0,"compression_m":0.0}'
    for i in range(5):
        w.add_message(cid, i, (good % (i * 0.1)).encode(), i)
    w.add_message(cid, 5, (good % "true").encode(), 5)
    w.finish()
    log.write_bytes(buffer.getvalue())
    assert mcap_bulk._bulk_squeeze_log(log.read_bytes(), log) is None
    with pytest.raises(SchemaError) as err:
        read_squeeze_log(log)
    assert "message 5 on /squeeze/A" in str(err.value)
    assert "is not of type 'number'" in str(err.value)


# --- hostile samples: the bulk reader never accepts what the reference refuses ---------------

SAMPLE_KEYS = ("object_id", "squeeze_index", *FIELDS, "force_left_n", "force_right_n", "extra")
VALUES = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False, width=64),
    st.floats(-2e7, 2e7),
    st.floats(-1e3, 1e3),
    st.integers(-5, 5),
    st.integers(-(2**70), 2**70),
    st.booleans(),
    st.none(),
    st.text(max_size=4),
    st.sampled_from(["A", "B", "", "a}", "{", ":", "[1]"]),
    st.lists(st.integers(0, 3), max_size=2),
    st.dictionaries(st.sampled_from(["a", "b"]), st.integers(0, 3), max_size=1),
)
#: Raw texts a hostile writer may put in a message (pieces that join into JSON, constants, ...).
PIECES = st.sampled_from([
    b"", b"{", b"}", b"{}", b"[", b"]", b'{"object_id":"A', b'","squeeze_index":0}',
    b'{"object_id":"A},{","squeeze_index":0,"time_s":0,"force_n":0,"compression_m":0}',
    b"NaN", b"1e999", b"{\"time_s\": Infinity}", b"\x00{}", b"{\"a\":1}\n", b" {}",
    b'{"object_id":"A","squeeze_index":0,"time_s":0,"force_n":0,"compression_m":0,"time_s":-1}',
    "{\"object_id\":\"\u00e9\",\"squeeze_index\":0,\"time_s\":0,\"force_n\":0,\"compression_m\":0}".encode(),
    b'{"object_id":"\\ud800","squeeze_index":0,"time_s":0,"force_n":0,"compression_m":0}',
    b'{"object_id":"A","squeeze_index":0,"time_s":1' + b"0" * 400 + b',"force_n":0}',
])  # fmt: skip


@st.composite
def messages(draw: st.DrawFn) -> list[bytes]:
    oid = draw(st.sampled_from(["A", "B"]))
    commanded = draw(st.booleans())
    out = []
    for i in range(draw(st.integers(1, 8))):
        msg: dict[str, Any] = {"object_id": oid, "squeeze_index": 0, "time_s": i * 0.01,
                               "force_n": 0.1 * i, "compression_m": 0.001 * i}  # fmt: skip
        if commanded:
            msg["commanded_force_n"] = 1.0
        if draw(st.integers(0, 3)) == 0:  # most messages valid, so most logs are read
            msg.update(draw(st.dictionaries(st.sampled_from(SAMPLE_KEYS), VALUES, max_size=2)))
        if draw(st.integers(0, 12)) == 0:
            msg.pop(draw(st.sampled_from(sorted(msg))))
        compact = draw(st.booleans())
        text = json.dumps(msg, separators=(",", ":") if compact else None).encode()
        out.append(draw(PIECES) if draw(st.integers(0, 12)) == 0 else text)
    return out


def _sample_log(texts: list[bytes], topic: str) -> bytes:
    buffer = io.BytesIO()
    w = Writer(buffer, compression=CompressionType.ZSTD, enable_data_crcs=True, chunk_size=256)
    w.start()
    w.add_metadata("deformctl", {"kind": "squeeze_log", "format_version": "1"})
    w.add_metadata("object", {"object_id": '"A"'})
    sid = w.register_schema("deformctl.SqueezeSample", "jsonschema",
                            json_schema_bytes("squeeze_sample"))  # fmt: skip
    cid = w.register_channel(topic, "json", sid)
    for i, text in enumerate(texts):
        w.add_message(cid, i, text, i)
    w.finish()
    return buffer.getvalue()


@FUZZ
@given(texts=messages(), topic=st.sampled_from(["/squeeze", "/squeeze/A"]))
def test_hostile_samples_agree_with_the_reference(texts: list[bytes], topic: str) -> None:
    _agree(_sample_log(texts, topic))


@FUZZ
@given(texts=st.lists(st.one_of(PIECES, messages().map(lambda m: m[0])), min_size=1, max_size=6))
def test_loads_objects_is_loads_on_each(texts: list[bytes]) -> None:
    got = jsonsafe.loads_objects(texts)
    if got is None:
        return
    assert got == [jsonsafe.loads(t) for t in texts]
    for t, value in zip(texts, got, strict=True):
        assert json.dumps(value, sort_keys=True) == json.dumps(jsonsafe.loads(t), sort_keys=True)


def test_loads_objects_refuses_texts_that_only_parse_joined() -> None:
    a = b'{"object_id":"A}'  # not JSON alone ...
    b = b'{","squeeze_index":0}'  # ... nor this, but joined they are one object
    c = b'{"x":1},{"y":2}'  # and this is two
    assert jsonsafe.loads_objects([a, b, c]) is None
    assert jsonsafe.loads_objects([b"{}", b'{"a": 1.5}']) == [{}, {"a": 1.5}]
    assert jsonsafe.loads_objects([b'{"a": 1e999}']) is None
    assert jsonsafe.loads_objects([b'{"a": NaN}']) is None
    assert jsonsafe.loads_objects([]) == []


@FUZZ
@given(batch=st.lists(messages(), min_size=1, max_size=3))
def test_message_columns_accept_only_valid_messages(batch: list[list[bytes]]) -> None:
    decoded = []
    for texts in batch:
        for t in texts:
            with contextlib.suppress(ValueError):
                decoded.append(jsonsafe.loads(t))
    columns = message_columns("squeeze_sample", decoded)
    if columns is None:
        return
    for m in decoded:
        validate_message("squeeze_sample", m)  # raises for an invalid one
    for key, col in columns.items():
        want = [m.get(key) for m in decoded]
        if col is None:
            assert all(v is None for v in want)
        elif isinstance(col, list):
            assert col == want
        elif isinstance(col, np.ma.MaskedArray):  # in some messages only
            assert col.mask.tolist() == [key not in m for m in decoded]
            assert col.compressed().tolist() == [m[key] for m in decoded if key in m]
        else:
            ref = np.fromiter(want, dtype=col.dtype, count=len(want))
            assert col.tobytes() == ref.tobytes()


def test_the_bulk_reader_is_faster(tmp_path: Path) -> None:
    """A generous bound measured in this run: at least 1.25x (about 1.7x on an idle machine; the
    reference path parses flat samples at once too, so what is left is the scan of the file)."""
    rng = np.random.default_rng(1)
    squeezes = []
    for k in range(8):
        t = np.arange(1500) * 1e-3
        d = 0.002 * np.sin(t) + 1e-6 * rng.standard_normal(t.size)
        squeezes.append(SqueezeSeries(f"O{k // 2}", k % 2, t, 40 * d, d, 40 * d, -d / 2, d / 2))
    data = _written(tmp_path, squeezes, [{"object_id": f"O{i}"} for i in range(4)])

    def best(read: Any) -> float:
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            read()
            times.append(time.perf_counter() - t0)
        return min(times)

    bulk = best(lambda: mcap_bulk._bulk_squeeze_log(data, "s.mcap"))
    reference = best(lambda: _reference(data, "s.mcap"))
    assert _agree(data)
    assert reference >= 1.25 * bulk, (reference, bulk)
