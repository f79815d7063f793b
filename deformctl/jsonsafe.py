"""JSON from files and processes deformctl did not write itself: parsed within stated limits.

Every JSON document that comes from outside (an MCAP sample or metadata record, a Parquet
table's or a model file's metadata, a skops ``schema.json``, a rig's answer) goes through
:func:`loads`. It refuses, as a :class:`ValueError` the caller turns into its one-line error
naming the file and the field (exit 65):

- a document larger than :data:`MAX_JSON_BYTES`;
- nesting deeper than :data:`MAX_JSON_DEPTH` (checked on the text before parsing, so 100,000
  nested arrays are an error, not a ``RecursionError`` in the parser or in whatever walks the
  result later);
- ``NaN`` / ``Infinity`` (not JSON; allowed only in metadata, where deformctl's own writers put
  them for a missing value), a number that overflows a float (``1e999``) and an integer
  longer than a float can hold (``10`` followed by 400 zeros, which numpy turns into an
  ``OverflowError``).

Ordinary documents take the fast path: one C-speed scan for brackets and long numbers, then the
standard parser. :func:`loads_objects` parses many small flat objects (a log's samples) in one
call of the parser, with the same limits and results as :func:`loads` on each.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["MAX_JSON_BYTES", "MAX_JSON_DEPTH", "loads", "loads_objects"]

#: The largest JSON document accepted, bytes (a skops ``schema.json`` of the paper's model is
#: about 20 kB, one squeeze sample about 300 B).
MAX_JSON_BYTES = 16 * 2**20

#: The deepest nesting of arrays and objects accepted (a skops ``schema.json`` of a fitted
#: pipeline is 22 levels deep, deformctl's own documents at most 4).
MAX_JSON_DEPTH = 64

_STRING = re.compile(rb'"(?:[^"\\]|\\.)*"', re.DOTALL)
_BRACKETS = re.compile(rb"[\[\]{}]")
#: A number that may not fit a float: an exponent of three digits or more, or 300+ digits. Looked
#: for on the text with every digit made ``0``, ``E`` made ``e`` and the signs deleted (the regular
#: expression ``[eE][+-]?\d{3}|\d{300}`` as substring searches, ten times faster on a long text;
#: deleting the signs can only find more, ``e--000``, which merely takes the careful parse).
_NUMBER_SHAPES = bytes.maketrans(b"123456789E", b"000000000e")
_EXPONENT_SHAPE, _LONG_SHAPE = b"e000", b"0" * 300
_OPENERS = frozenset(b"[{")


def _may_hold_big_number(raw: bytes, longest: int | None = None) -> bool:
    """Whether ``raw`` may hold a number beyond the float range (see :data:`_NUMBER_SHAPES`);
    ``longest``: the longest of the documents joined in ``raw`` (no number spans two)."""
    shapes = raw.translate(_NUMBER_SHAPES, b"+-")
    if _EXPONENT_SHAPE in shapes:
        return True
    return (longest is None or longest >= len(_LONG_SHAPE)) and _LONG_SHAPE in shapes


def _reject_constant(token: str) -> float:
    raise ValueError(f"non-standard JSON constant {token} (only finite numbers are allowed)")


def _constant(token: str) -> float:
    return float(token.replace("Infinity", "inf"))


def _finite_float(token: str) -> float:
    value = float(token)
    if not math.isfinite(value):
        raise ValueError(f"number {token[:24]}... is beyond the float range")
    return value


def _float_sized_int(token: str) -> int:
    if len(token.lstrip("-")) > 308:
        raise ValueError(f"integer of {len(token):,} digits is beyond the float range")
    return int(token)


def _depth(data: bytes) -> int:
    """The deepest nesting of ``[`` / ``{`` in a JSON text (strings ignored), without recursion."""
    brackets = b"".join(_BRACKETS.findall(_STRING.sub(b'""', data)))
    if not brackets:
        return 0
    codes = np.frombuffer(brackets, dtype=np.uint8)
    steps = np.where((codes == ord("[")) | (codes == ord("{")), 1, -1)
    return int(np.cumsum(steps).max())


def loads(
    data: str | bytes | bytearray,
    *,
    max_bytes: int = MAX_JSON_BYTES,
    max_depth: int = MAX_JSON_DEPTH,
    allow_nan: bool = False,
) -> Any:
    """Parse untrusted JSON within the limits above.

    Args:
        data: the document (UTF-8 bytes or text).
        max_bytes: the largest document accepted, bytes.
        max_depth: the deepest nesting of arrays and objects accepted.
        allow_nan: accept the constants ``NaN`` / ``Infinity`` that Python's ``json.dumps``
            writes for a missing or unbounded value in metadata (catalog rows, provenance,
            metrics); measured samples and rig answers never allow them.

    Returns:
        The parsed value; every number in it is finite.

    Raises:
        ValueError: not JSON, or beyond one of the limits; the message says which.
    """
    raw = data.encode("utf-8") if isinstance(data, str) else bytes(data)
    if len(raw) > max_bytes:
        raise ValueError(f"{len(raw):,} bytes of JSON, above the limit of {max_bytes:,}")
    if sum(raw.count(c) for c in _OPENERS) > max_depth:  # only then can it be too deep
        depth = _depth(raw)
        if depth > max_depth:
            raise ValueError(f"nested {depth:,} levels deep, above the limit of {max_depth}")
    constant = _constant if allow_nan else _reject_constant
    try:
        if _may_hold_big_number(raw):
            return json.loads(
                raw,
                parse_constant=constant,
                parse_float=_finite_float,
                parse_int=_float_sized_int,
            )
        return json.loads(raw, parse_constant=constant)
    except RecursionError:  # pragma: no cover - the depth check comes first
        raise ValueError(f"nested deeper than the limit of {max_depth}") from None


_OPEN_BRACE, _CLOSE_BRACE = ord("{"), ord("}")


def loads_objects(texts: Sequence[bytes]) -> list[Any] | None:
    """Parse many flat JSON objects at once: ``[loads(t) for t in texts]``, or None.

    The texts are joined into one JSON array and parsed by one call of the standard parser. That
    is only the same as parsing each text alone when every text is exactly one object, which is
    checked on the bytes first: each text starts with ``{`` and ends with ``}``, and the texts
    hold one ``{``, one ``}`` and no ``[`` / ``]`` each (so no text can end inside a string or a
    container of another: the array then has one object per text, each spanning its text
    exactly). Such a text is one level deep and within :data:`MAX_JSON_BYTES`, and NaN,
    Infinity and numbers no float holds are refused exactly as :func:`loads` refuses them.

    Returns:
        The parsed objects, equal to what :func:`loads` returns for each text; None when the
        texts are not all such objects or one of them is refused (the caller then parses each
        with :func:`loads`, which says what is wrong).
    """
    k = len(texts)
    if k == 0:
        return []
    joined = b",".join(texts)
    if joined.count(b"{") != k or joined.count(b"}") != k or b"[" in joined or b"]" in joined:
        return None
    lengths = np.fromiter(map(len, texts), dtype=np.int64, count=k)
    longest = int(lengths.max())
    if int(lengths.min()) < 2 or longest > MAX_JSON_BYTES:
        return None
    starts = np.zeros(k, dtype=np.int64)
    np.cumsum(lengths[:-1] + 1, out=starts[1:])
    codes = np.frombuffer(joined, dtype=np.uint8)
    if not (
        np.all(codes[starts] == _OPEN_BRACE) and np.all(codes[starts + lengths - 1] == _CLOSE_BRACE)
    ):
        return None
    text = b"[" + joined + b"]"
    try:
        if _may_hold_big_number(joined, longest):
            values = json.loads(
                text,
                parse_constant=_reject_constant,
                parse_float=_finite_float,
                parse_int=_float_sized_int,
            )
        else:
            values = json.loads(text, parse_constant=_reject_constant)
    except ValueError:  # not JSON, a constant, a number beyond the float range
        return None
    if not isinstance(values, list) or len(values) != k or set(map(type, values)) != {dict}:
        return None
    out: list[Any] = values
    return out
