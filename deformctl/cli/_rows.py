"""``inspect``'s rows as an aligned text table: units in the headers, long text cut to the width.

Numbers are shown to 6 significant digits here (``--json`` and ``--csv`` keep every digit), text
is left-aligned and numbers right-aligned. A table wider than the terminal is split into blocks
of columns that fit, each repeating the first column (the object id), as pandas prints a wide
frame; a text cell that alone would not fit is cut with ``…``.
"""

from __future__ import annotations

import math
import os
import shutil
import sys
from typing import Any

import numpy as np
import pandas as pd

from deformctl.artifacts.rows import KIND_ATTEMPTS, Rows

GAP = "  "  #: between two columns
MIN_TEXT = 8  #: a cut text cell keeps at least this many characters


def output_width() -> int | None:
    """The width to fit: ``COLUMNS`` when set, else the terminal's; None when stdout is not a
    terminal (a pipe gets whole cells)."""
    columns = os.environ.get("COLUMNS", "")
    if columns.isdigit() and int(columns) > 0:
        return int(columns)
    if sys.stdout.isatty():
        return shutil.get_terminal_size().columns
    return None


def _cell(value: Any) -> str:
    """The text of one value."""
    if isinstance(value, np.generic):
        value = value.item()
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return format(value, ".6g")
    return " ".join(str(value).split())


def _is_number_column(column: pd.Series) -> bool:
    """Right-aligned: integer and float columns (not booleans)."""
    return bool(pd.api.types.is_numeric_dtype(column) and not pd.api.types.is_bool_dtype(column))


def _cut(text: str, width: int) -> str:
    return text if len(text) <= width else text[: max(width - 1, 0)] + "…"


def render_rows(rows: Rows, width: int | None) -> str:
    """``rows`` as an aligned table (no trailing newline); ``width``: the line length to fit."""
    names = [str(c) for c in rows.frame.columns]
    if not names:
        return "(no columns)"
    headers = [f"{n} [{rows.units[n]}]" if rows.units.get(n) else n for n in names]
    frame = rows.frame.copy(deep=False)
    frame.attrs = {}  # pandas deep-copies attrs into every column it hands out: quadratic
    texts = [[_cell(v) for v in values] for values in frame.itertuples(index=False, name=None)]
    numeric = [_is_number_column(frame[c]) for c in frame.columns]
    widths = [max([len(headers[j])] + [len(r[j]) for r in texts]) for j in range(len(names))]
    if width is not None:
        first = widths[0] + len(GAP)
        for j in range(len(names)):
            room = max(MIN_TEXT, width - (first if j else 0))
            if not numeric[j] and widths[j] > room:
                for r in texts:
                    r[j] = _cut(r[j], room)
                headers[j] = _cut(headers[j], room)
                widths[j] = room
    blocks = _blocks(widths, width)
    out: list[str] = []
    for k, block in enumerate(blocks):
        if k:
            out.append("")
        out.append(_line([headers[j] for j in block], [widths[j] for j in block], numeric, block))
        for r in texts:
            out.append(_line([r[j] for j in block], [widths[j] for j in block], numeric, block))
    return "\n".join(out)


def _line(values: list[str], widths: list[int], numeric: list[bool], block: list[int]) -> str:
    parts = [
        v.rjust(w) if numeric[j] else v.ljust(w)
        for v, w, j in zip(values, widths, block, strict=True)
    ]
    return GAP.join(parts).rstrip()


def _blocks(widths: list[int], width: int | None) -> list[list[int]]:
    """Column indices per block: all in one without a width, else as many as fit, each block
    after the first starting with column 0."""
    if width is None or len(widths) == 1:
        return [list(range(len(widths)))]
    blocks: list[list[int]] = []
    current = [0]
    used = widths[0]
    for j in range(1, len(widths)):
        need = len(GAP) + widths[j]
        if used + need > width and len(current) > 1:
            blocks.append(current)
            current = [0]
            used = widths[0]
        current.append(j)
        used += need
    blocks.append(current)
    return blocks


def rows_footer(rows: Rows) -> str | None:
    """The note under a cut table: ``20 of 73 rows shown (--rows all for every row)``."""
    shown = len(rows.frame)
    if shown >= rows.total:
        return None
    return f"{shown} of {rows.total} rows shown (--rows N or --rows all for more)"


def _lift_force_lines(rows: Rows) -> list[str]:
    """Per object of an attempts table: the L_f found, attempts made and how many lifted."""
    frame = rows.frame
    if "object_id" not in frame.columns:
        return []
    out = []
    for oid, group in frame.groupby("object_id", sort=False):
        found = group["lift_force_n"].iloc[0] if "lift_force_n" in group else math.nan
        lifted = int(group["lifted"].sum()) if "lifted" in group else 0
        lf = "not found (nothing lifted)" if math.isnan(found) else f"{found:.6g} N"
        out.append(f"  {oid}: L_f = {lf}; {len(group)} attempt(s) shown, {lifted} lifted")
    return out


def rows_text(rows: Rows | None, summary_text: str, *, summary: bool) -> str:
    """What text-mode ``inspect`` prints: the summary (when ``summary``) and the rows."""
    if rows is None:
        return summary_text
    parts = [summary_text] if summary else []
    if summary and len(rows.frame) == 0 and rows.total > 0:
        return summary_text
    label = "attempts" if rows.kind == KIND_ATTEMPTS else "rows"
    if summary:
        parts.append(f"{label} (first {len(rows.frame)} of {rows.total}):")
    parts.append(render_rows(rows, output_width()))
    if rows.kind == KIND_ATTEMPTS and "lift_force_n" in rows.frame.columns:
        parts.append("lifting force found (the smallest grip force that lifted):")
        parts.extend(_lift_force_lines(rows))
    return "\n".join(parts)
