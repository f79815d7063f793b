"""deformctl.jsonsafe: ordinary documents come back as the standard parser reads them, and the
limits sit exactly where they are stated (hostile documents: tests/fuzz/test_hostile_json.py)."""

from __future__ import annotations

import json
import math

import pytest

from deformctl.jsonsafe import MAX_JSON_DEPTH, loads, loads_objects

DOC = {
    "object_id": "Würfel ✓",
    "weight_n": 0.1 + 0.2,  # a float that needs all 17 digits to round-trip
    "squeezes": [{"i": 0, "ok": True, "f": [1e-300, -2.5e300, 0.0]}, {"i": 1, "ok": None}],
    "big": 2**62,
}


@pytest.mark.parametrize("kind", [str, bytes, bytearray])
def test_an_ordinary_document_round_trips(kind: type) -> None:
    text = json.dumps(DOC)
    data = text if kind is str else kind(text.encode("utf-8"))
    assert loads(data) == DOC
    assert loads(data)["weight_n"] == 0.30000000000000004


def test_nan_and_infinity_only_where_allowed() -> None:
    with pytest.raises(ValueError, match="non-standard JSON constant NaN"):
        loads('{"x": NaN}')
    got = loads("[NaN, Infinity, -Infinity]", allow_nan=True)
    assert math.isnan(got[0])
    assert got[1:] == [math.inf, -math.inf]


def test_the_depth_limit_is_exact() -> None:
    assert loads("[[1]]", max_depth=2) == [[1]]
    with pytest.raises(ValueError, match="nested 3 levels deep, above the limit of 2"):
        loads("[[[1]]]", max_depth=2)
    assert loads('{"a": "[[[[[["}', max_depth=1) == {"a": "[[[[[["}  # brackets in strings
    assert MAX_JSON_DEPTH == 64


def test_the_number_limits_are_the_float_range() -> None:
    assert loads("9" * 308) == int("9" * 308)  # fits a float (1e308 < max)
    with pytest.raises(ValueError, match="309 digits"):
        loads("1" + "0" * 308)
    assert loads("[1e-999]") == [0.0]  # underflow is zero, not an error
    assert loads("1.7976931348623157e308") == 1.7976931348623157e308
    with pytest.raises(ValueError, match="float range"):
        loads("-1.8e308")
    with pytest.raises(json.JSONDecodeError):
        loads("{'single': 'quotes'}")  # not JSON


def test_loads_objects_parses_flat_objects_and_declines_the_rest() -> None:
    texts = [b'{"t": 0.0, "f": 1.5}', b'{"t": 0.001, "f": 2}', b"{}"]
    assert loads_objects(texts) == [{"t": 0.0, "f": 1.5}, {"t": 0.001, "f": 2}, {}]
    assert loads_objects([]) == []
    for declined in (
        [b'{"a": [1]}'],  # a container inside
        [b'{"a": 1}', b"2"],  # not an object
        [b'{"a": NaN}'],  # a constant: loads says what is wrong
        [b'{"a": 1e999}'],
        [b'{"a": "}{"}'],  # braces in a string could span texts
        [b'{"a": 1', b"}"],
    ):
        assert loads_objects(declined) is None, declined
