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
standard parser.
"""

from __future__ import annotations

import json
import math
import re
from typing import Any

import numpy as np

__all__ = ["MAX_JSON_BYTES", "MAX_JSON_DEPTH", "loads"]

#: The largest JSON document accepted, bytes (a skops ``schema.json`` of the paper's model is
#: about 20 kB, one squeeze sample about 300 B).
MAX_JSON_BYTES = 16 * 2**20

#: The deepest nesting of arrays and objects accepted (a skops ``schema.json`` of a fitted
#: pipeline is 22 levels deep, deformctl's own documents at most 4).
MAX_JSON_DEPTH = 64

_STRING = re.compile(rb'"(?:[^"\\]|\\.)*"', re.DOTALL)
_BRACKETS = re.compile(rb"[\[\]{}]")
#: A number that may not fit a float: an exponent of three digits or more, or 300+ digits.
_BIG_NUMBER = re.compile(rb"[eE][+-]?\d{3}|\d{300}")
_OPENERS = frozenset(b"[{")


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
        if _BIG_NUMBER.search(raw) is not None:
            return json.loads(
                raw,
                parse_constant=constant,
                parse_float=_finite_float,
                parse_int=_float_sized_int,
            )
        return json.loads(raw, parse_constant=constant)
    except RecursionError:  # pragma: no cover - the depth check comes first
        raise ValueError(f"nested deeper than the limit of {max_depth}") from None
