"""What ``inspect --rows N --columns a,b`` asks for, parsed without reading a table (apart from
:mod:`deformctl.artifacts.rows`, which reads them with pandas and pyarrow, so that ``deformctl
inspect --help`` states the default without importing either)."""

from __future__ import annotations

from deformctl.errors import UsageError

#: Rows shown when the count is not given.
DEFAULT_ROWS = 20


def parse_row_count(text: str | None, *, default: int | None = DEFAULT_ROWS) -> int | None:
    """``--rows``: a whole number >= 1, or ``all`` (None); not given: ``default``
    (:data:`DEFAULT_ROWS` for the text table; None, every row, for ``--json`` and ``--csv``).

    Raises:
        UsageError: zero, a negative or a non-numeric count (exit 2).
    """
    if text is None:
        return default
    value = text.strip().lower()
    if value == "all":
        return None
    if not value.isdigit() or int(value) < 1:
        raise UsageError(f"--rows must be a whole number >= 1 or 'all', got {text!r}")
    return int(value)


def parse_column_list(text: str | None) -> list[str] | None:
    """``--columns a,b,c`` → ``["a", "b", "c"]`` (None when not given).

    Raises:
        UsageError: an empty name or a name given twice (exit 2).
    """
    if text is None:
        return None
    names = [c.strip() for c in text.split(",")]
    if any(not c for c in names):
        raise UsageError(f"--columns: expected name[,name...], got {text!r}")
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise UsageError(f"--columns: {name!r} given twice")
        seen.add(name)
    return names


__all__ = ["DEFAULT_ROWS", "parse_column_list", "parse_row_count"]
