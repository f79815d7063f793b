"""Short reprs: a result that holds arrays, tables or many attempts prints on a few lines.

A dataclass's generated ``repr`` prints every array and table it holds in full (a squeeze log's
result ran to pages). Classes that hold such data define ``__repr__ = short_repr``: the fields as
usual, but an array as ``array[3753]``, a table as ``DataFrame[73 x 22]``, a long sequence as
``[24 items]``, a nested result by its own short repr, and numbers to six significant digits.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

#: Sequences and mappings up to this many items are shown item by item.
MAX_ITEMS = 3
#: Strings longer than this are cut.
MAX_TEXT = 60


def short(value: Any, depth: int = 0) -> str:
    """One value, short: see the module docstring."""
    shape = getattr(value, "shape", None)
    kind = type(value).__name__
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, bool | int | type(None)):
        return repr(value)
    if isinstance(value, str):
        return repr(value if len(value) <= MAX_TEXT else value[: MAX_TEXT - 3] + "...")
    if shape is not None and kind in ("DataFrame", "Series", "Table"):  # before the numpy
        dims = " x ".join(str(n) for n in shape) if isinstance(shape, tuple) else str(shape)
        return f"{kind}[{dims}]"  # branch: a Series has a dtype too
    if shape is not None and hasattr(value, "dtype"):  # numpy arrays and scalars
        if shape == ():
            return repr(value.item())
        return f"array[{' x '.join(str(n) for n in shape)}]"
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return _fields(value, depth + 1) if depth < 1 else f"{kind}(...)"
    if isinstance(value, Mapping):
        if len(value) > MAX_ITEMS:
            return f"{{{len(value)} keys}}"
        items = ", ".join(f"{k!r}: {short(v, depth + 1)}" for k, v in value.items())
        return f"{{{items}}}"
    if isinstance(value, list | tuple):
        open_, close = ("[", "]") if isinstance(value, list) else ("(", ")")
        if len(value) > MAX_ITEMS:
            return f"{open_}{len(value)} items{close}"
        return open_ + ", ".join(short(v, depth + 1) for v in value) + close
    text = repr(value)
    return text if len(text) <= MAX_TEXT and "\n" not in text else f"{kind}(...)"


def short_repr(self: Any) -> str:
    """``Class(field=value, ...)`` with each value :func:`short` (use as ``__repr__``)."""
    return _fields(self, 0)


def _fields(obj: Any, depth: int) -> str:
    """``Class(field=value, ...)`` of a dataclass whose fields sit ``depth`` levels down: a
    dataclass in a field shows its own fields, one in those shows as ``Class(...)``."""
    fields = (f for f in dataclasses.fields(obj) if f.repr)
    body = ", ".join(f"{f.name}={short(getattr(obj, f.name), depth)}" for f in fields)
    return f"{type(obj).__name__}({body})"
