"""The text of a CSV export: its encoding, delimiter, decimal mark, preamble, header and numbers.

A testing machine or a gripper writes its export in its own dialect: a metadata preamble before
the header (``Speed (mm/min): 10;``), a units row under the names (``(s),(mm),(kN)``), ``;`` and
a decimal comma, quoted values with thousands separators, a byte-order mark, a GBK header. This
module finds each of these in the file itself, unless the :class:`CsvDialect` says it:

1. **Text.** The first :data:`HEAD_BYTES` are decoded in the dialect's encoding (a UTF-8 or
   UTF-16 byte-order mark wins); a byte that does not decode is an error that names
   ``--encoding`` and an encoding the bytes do decode in (:func:`guess_encoding`).
2. **Delimiter and numbers.** Each delimiter (``,`` ``;`` tab) and decimal mark is tried on
   the rows; the pair under which most rows are numbers, of one width, wins. A thousands
   separator is taken when the numbers hold digit groups (``1,234.5``). A comma that could be
   either mark (every comma cell reads ``1,234``) is refused: exit 2, pass ``--decimal``.
3. **Header.** The header is the last row of text cells above the first run of numeric rows
   (``--skip-rows N``: the line after N lines); a row of units right under it (``(s)``,
   ``[kN]``) is the units row. The lines above the header are the preamble; its
   ``key: value`` (and ``key,value``) lines are kept (:attr:`CsvLayout.preamble`).
4. **Numbers.** The columns asked for are read by pandas' C parser from the first data line on
   (:func:`read_columns`), so a file of millions of rows costs its numbers, not its text. A row
   that does not parse is found again line by line and named (:func:`_diagnose`).
"""

from __future__ import annotations

import codecs
import csv
import io
import re
import sys
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import IO, Any

import numpy as np

from deformctl.artifacts.io import check_input_path
from deformctl.errors import InputDataError, UsageError
from deformctl.measure.csv.options import DELIMITER_NAMES, DELIMITERS, THOUSANDS, CsvDialect
from deformctl.series import FloatArray
from deformctl.units import parse_unit

#: The sniffing reads at most this many bytes and lines from the start of the file.
HEAD_BYTES = 256 * 1024
HEAD_LINES = 2000
#: The dialect and the header are looked for in the first this many lines (all the head's when
#: no data is found there).
SNIFF_LINES = 200
#: The first run of numeric rows must be this long (or the rest of the file) to start the data.
DATA_RUN = 3
#: Encodings a file that does not decode is tried in, for the hint (first that decodes wins;
#: the CJK ones only when they give CJK characters).
GUESS_ENCODINGS: tuple[str, ...] = ("utf-8", "gb2312", "shift_jis", "cp1252")
#: The encoding a guess names: GB2312 holds the common Chinese characters (a Latin-1 byte before
#: ASCII never decodes in it, unlike in GBK), GBK is the superset to read the file with.
_GUESS_NAME = {"gb2312": "gbk"}
#: A thousands separator is taken when this share of the cells holding it has digit groups
#: (the others are then named as bad cells, rather than hiding the separator).
GROUPED_SHARE = 0.9
#: Preamble values longer than this are cut (a log's metadata stays small).
MAX_PREAMBLE_VALUE = 200
MAX_PREAMBLE_LINES = 100

_NUMBER = re.compile(r"^[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?$")


@dataclass(frozen=True)
class CsvSource:
    """Where a CSV export's bytes come from: a file, or stdin read into memory (``-``)."""

    name: str
    path: Path | None = None
    data: bytes | None = None

    @classmethod
    def open(cls, path: str | PathLike[str]) -> CsvSource:
        """The file ``path``, or stdin for ``-`` (read whole).

        Raises:
            MissingInputError: no such file, a directory, or no permission to read (exit 66).
        """
        checked = check_input_path(path)
        if isinstance(checked, str):
            return cls("<stdin>", data=sys.stdin.buffer.read())
        return cls(str(checked), path=checked)

    @property
    def size(self) -> int:
        """Bytes in the source."""
        return len(self.data) if self.data is not None else self.path.stat().st_size  # type: ignore[union-attr]

    def head(self, n: int) -> bytes:
        """The first ``n`` bytes."""
        if self.data is not None:
            return self.data[:n]
        with self.path.open("rb") as fh:  # type: ignore[union-attr]
            return fh.read(n)

    def tail(self, n: int) -> bytes:
        """The last ``n`` bytes."""
        if self.data is not None:
            return self.data[-n:]
        with self.path.open("rb") as fh:  # type: ignore[union-attr]
            fh.seek(max(self.size - n, 0))
            return fh.read(n)

    def stream(self, offset: int) -> IO[bytes]:
        """A binary stream from byte ``offset`` on (the caller closes it)."""
        if self.data is not None:
            return io.BytesIO(self.data[offset:])
        fh = self.path.open("rb")  # type: ignore[union-attr]
        fh.seek(offset)
        return fh


@dataclass(frozen=True)
class CsvLayout:
    """What was found in (or given for) a CSV export's text.

    Attributes:
        encoding: the codec the text was read with (after a byte-order mark).
        delimiter, decimal, thousands: the dialect (thousands None: none).
        header_line: the header's line, 1-based.
        units_line: the units row's line, or None.
        data_line: the first data line, 1-based.
        data_offset: the byte offset of the first data line.
        names: the header's cells (``column 3`` for an empty one), one per column.
        units_row: the units row's cells (empty strings when there is none).
        width: the number of columns of the data rows.
        preamble: the preamble's ``key: value`` lines.
        preamble_lines: the preamble's other lines.
        sniffed: which of ``delimiter``, ``decimal``, ``thousands``, ``header`` were found
            in the file rather than given.
        rows_estimate: the data rows, estimated from the file size and the first rows.
    """

    encoding: str
    delimiter: str
    decimal: str
    thousands: str | None
    header_line: int
    units_line: int | None
    data_line: int
    data_offset: int
    names: tuple[str, ...]
    units_row: tuple[str, ...]
    width: int
    preamble: dict[str, str] = field(default_factory=dict)
    preamble_lines: tuple[str, ...] = ()
    sniffed: tuple[str, ...] = ()
    rows_estimate: int = 0

    def describe_header(self) -> str:
        """``line 8: 'Time (s)', 'Compression (mm)', ...`` for messages."""
        return f"line {self.header_line}: " + ", ".join(repr(n) for n in self.names)

    def as_dict(self) -> dict[str, Any]:
        """What the squeeze log records of the file's layout."""
        return {
            "encoding": self.encoding,
            "delimiter": DELIMITER_NAMES[self.delimiter],
            "decimal": self.decimal,
            "thousands": self.thousands,
            "header_line": self.header_line,
            "units_line": self.units_line,
            "data_line": self.data_line,
            "sniffed": list(self.sniffed),
        }


# ---------------------------------------------------------------------------- text


_BOMS: tuple[tuple[bytes, str], ...] = (
    (codecs.BOM_UTF8, "utf-8"),
    (codecs.BOM_UTF16_LE, "utf-16-le"),
    (codecs.BOM_UTF16_BE, "utf-16-be"),
)


def _bom(head: bytes, encoding: str) -> tuple[int, str]:
    """(bytes of a byte-order mark, the codec to read the rest with)."""
    for bom, codec in _BOMS:
        if head.startswith(bom):
            return len(bom), codec
    name = codecs.lookup(encoding).name
    return 0, {"utf-8-sig": "utf-8", "utf-16": "utf-16-le"}.get(name, name)


def guess_encoding(raw: bytes) -> tuple[str, str] | None:
    """An encoding ``raw`` decodes in, and the first non-ASCII text it gives; None if none.

    The CJK encodings count only when they give CJK characters (GBK decodes most byte
    strings, as mojibake).
    """
    for enc in GUESS_ENCODINGS:
        try:
            text = codecs.getincrementaldecoder(enc)(errors="strict").decode(raw, final=False)
        except UnicodeError:
            continue
        odd = [c for c in text if ord(c) > 127]
        if enc in ("gb2312", "shift_jis") and not any("\u3040" <= c <= "\u9fff" for c in odd):
            continue
        line = next((w for w in text.splitlines() if any(ord(c) > 127 for c in w)), "")
        return _GUESS_NAME.get(enc, enc), line.strip()[:40]
    return None


def spelled(encoding: str) -> str:
    """An encoding as messages spell it: ``UTF-8``, ``gbk``."""
    return encoding.upper() if encoding.lower().startswith("utf") else encoding


def _decode_error(raw: bytes, err: UnicodeDecodeError, encoding: str, name: str) -> InputDataError:
    line = raw[: err.start].count(b"\n") + 1
    byte = raw[err.start : err.start + 1].hex()
    guess = guess_encoding(raw)
    hint = "pass --encoding (e.g. gbk, cp1252, latin-1)"
    if guess is not None and guess[0] != encoding:
        seen = f" (it reads as {guess[0]}: {guess[1]!r})" if guess[1] else ""
        hint = f"pass --encoding {guess[0]}{seen}"
    return InputDataError(
        f"not {spelled(encoding)} text: byte 0x{byte} on line {line} does not decode; {hint}",
        path=name,
    )


def _head_text(source: CsvSource, encoding: str) -> tuple[str, int, str, bool]:
    """(the decoded head, the BOM's bytes, the codec, whether the head is the whole file)."""
    raw = source.head(HEAD_BYTES)
    skip, codec = _bom(raw, encoding)
    whole = len(raw) < HEAD_BYTES
    try:
        text = codecs.getincrementaldecoder(codec)(errors="strict").decode(raw[skip:], final=whole)
    except UnicodeDecodeError as err:
        raise _decode_error(raw[skip:], err, codec, source.name) from None
    return text, skip, codec, whole


# ---------------------------------------------------------------------------- cells


def _split(line: str, delimiter: str) -> list[str]:
    """The cells of one line (quotes removed, blanks stripped, trailing empty cells dropped)."""
    try:
        cells = next(csv.reader([line], delimiter=delimiter, skipinitialspace=True), [])
    except csv.Error:  # a cell over the csv module's field limit (128 KiB), or a stray quote
        cells = line.split(delimiter)
    cells = [c.strip() for c in cells]
    while cells and not cells[-1]:
        cells.pop()
    return cells


def _normalise(cell: str, decimal: str, thousands: str | None) -> str:
    text = cell.replace(thousands, "") if thousands else cell
    return text.replace(decimal, ".") if decimal != "." else text


def is_number(cell: str, decimal: str = ".", thousands: str | None = None) -> bool:
    """Whether ``cell`` is a plain number under the decimal mark and thousands separator."""
    if thousands and thousands in cell and not _grouped(cell, decimal, thousands):
        return False
    if decimal == "," and "." in cell and thousands != ".":
        return False
    return bool(_NUMBER.match(_normalise(cell, decimal, thousands)))


def _grouped(cell: str, decimal: str, thousands: str) -> bool:
    """Whether ``cell`` is a number with correct digit groups: ``1,234.5``, ``-12.345,6``."""
    sep, dec = re.escape(thousands), re.escape(decimal)
    return bool(re.match(rf"^[+-]?[1-9]\d{{0,2}}(?:{sep}\d{{3}})+(?:{dec}\d*)?$", cell))


def _numeric_row(cells: Sequence[str], decimal: str, thousands: str | None) -> bool:
    """Two or more cells, more than half of the non-empty ones numbers."""
    filled = [c for c in cells if c]
    if len(filled) < 2:
        return False
    return sum(is_number(c, decimal, thousands) for c in filled) * 2 > len(filled)


def _text_row(cells: Sequence[str], decimal: str, thousands: str | None) -> bool:
    """At least one text cell, and at most half of the non-empty cells numbers."""
    filled = [c for c in cells if c]
    if not filled:
        return False
    return sum(is_number(c, decimal, thousands) for c in filled) * 2 <= len(filled)


def _units_row(cells: Sequence[str]) -> bool:
    """Whether a row states units: at least half its non-empty cells a unit or ``(…)``/``[…]``."""
    filled = [c for c in cells if c]
    if not filled:
        return False
    unitish = sum(
        parse_unit(c) is not None or bool(re.match(r"^[(\[].*[)\]]$", c)) or c in ("-", "1")
        for c in filled
    )
    return unitish * 2 >= len(filled)


# ---------------------------------------------------------------------------- sniffing


def _detect_thousands(cells: Sequence[str], decimal: str, delimiter: str) -> str | None:
    """The thousands separator the numbers use (every cell holding it has digit groups)."""
    for sep in THOUSANDS:  # a cell holds the delimiter only when quoted: "1,234.5"
        if sep == decimal:
            continue
        holding = [c for c in cells if sep in c and re.search(r"\d", c)]
        grouped = sum(_grouped(c, decimal, sep) for c in holding)
        if holding and grouped >= GROUPED_SHARE * len(holding):
            return sep
    return None


def _score(
    rows: Sequence[Sequence[str]], decimal: str, thousands: str | None, lenient: bool = False
) -> tuple[int, int]:
    """(rows that are all numbers, of the commonest width; that width). ``lenient``: rows of
    mostly numbers count too (an export with a text column: a step name, a comment)."""
    widths = Counter(
        len(r)
        for r in rows
        if len(r) >= 2
        and (
            _numeric_row(r, decimal, thousands)
            if lenient
            else all(is_number(c, decimal, thousands) for c in r if c)
        )
    )
    if not widths:
        return 0, 0
    width, count = widths.most_common(1)[0]
    return count, width


@dataclass(frozen=True)
class _Dialect:
    delimiter: str
    decimal: str
    thousands: str | None
    width: int


def _sniff_dialect(lines: Sequence[str], dialect: CsvDialect, name: str) -> _Dialect:
    """The delimiter, decimal mark and thousands separator under which the rows are numbers."""
    delimiters = (dialect.delimiter,) if dialect.delimiter else DELIMITERS
    candidates = _candidates(lines, dialect, delimiters, lenient=False)
    if not candidates:  # no row of numbers only: an export with a text column?
        candidates = _candidates(lines, dialect, delimiters, lenient=True)
    return _finish_sniff(lines, dialect, delimiters, candidates, name)


def _candidates(
    lines: Sequence[str], dialect: CsvDialect, delimiters: Sequence[str], *, lenient: bool
) -> list[tuple[int, int, int, _Dialect]]:
    """(numeric rows, width, -rank of the delimiter, the dialect) of each dialect that finds
    numeric rows (:func:`_score`)."""
    candidates: list[tuple[int, int, int, _Dialect]] = []
    for rank, delim in enumerate(delimiters):
        rows = [_split(line, delim) for line in lines]
        cells = [c for r in rows for c in r]
        decimals = (
            (dialect.decimal,) if dialect.decimal else ((".",) if delim == "," else (".", ","))
        )
        for decimal in decimals:
            if decimal == delim:
                continue
            thousands = dialect.thousands
            if thousands is None:
                thousands = _detect_thousands(cells, decimal, delim)
            if thousands == decimal:
                continue
            count, width = _score(rows, decimal, thousands, lenient)
            if count:
                candidates.append((count, width, -rank, _Dialect(delim, decimal, thousands, width)))
    return candidates


def _finish_sniff(
    lines: Sequence[str],
    dialect: CsvDialect,
    delimiters: Sequence[str],
    candidates: list[tuple[int, int, int, _Dialect]],
    name: str,
) -> _Dialect:
    if not candidates:
        tried = ", ".join(DELIMITER_NAMES[d] for d in delimiters)
        raise InputDataError(
            f"no rows of numbers in the first {len(lines)} lines (delimiters tried: {tried}); "
            "is this a CSV export?",
            path=name,
        )
    # most numeric rows, then the widest, then the delimiter's rank, then '.' before ','
    candidates.sort(key=lambda c: (c[0], c[1], c[2], c[3].decimal == "."), reverse=True)
    best = candidates[0]
    if dialect.decimal is None and dialect.thousands is None:
        rival = next(
            (
                c
                for c in candidates[1:]
                if c[3].delimiter == best[3].delimiter
                and c[0] == best[0]
                and c[3].decimal != best[3].decimal
            ),
            None,
        )
        commas = [c for line in lines for c in _split(line, best[3].delimiter) if "," in c]
        if rival is not None and any(
            is_number(c, d.decimal, d.thousands) for c in commas for d in (best[3], rival[3])
        ):
            raise UsageError(
                "cannot tell whether ',' is the decimal mark or the thousands separator (every "
                "number with a comma reads as digit groups, e.g. 1,234); pass --decimal , or "
                "--thousands ,",
                path=name,
            )
    return best[3]


def _data_start(rows: Sequence[Sequence[str]], sniff: _Dialect, first: int = 0) -> int | None:
    """The first row (from ``first``) of a run of :data:`DATA_RUN` numeric rows (fewer at the
    end of the file)."""
    numeric = [bool(r) and _numeric_row(r, sniff.decimal, sniff.thousands) for r in rows]
    filled = [i for i, r in enumerate(rows) if r]
    for k, i in enumerate(filled):
        if i < first or not numeric[i]:
            continue
        run = filled[k : k + DATA_RUN]
        if all(numeric[j] for j in run):
            return i
    return None


def _preamble(lines: Sequence[str], delimiter: str) -> tuple[dict[str, str], tuple[str, ...]]:
    """The ``key: value`` (``key = value``, ``key,value``) lines, and the others."""
    found: dict[str, str] = {}
    other: list[str] = []
    for raw in lines[:MAX_PREAMBLE_LINES]:
        line = raw.strip().strip(";,\t").strip()
        if not line:
            continue
        m = re.match(r"^([^:=]{1,80}?)\s*[:=]\s*(.*)$", line)
        cells = _split(raw, delimiter)
        if m and m.group(1).strip():
            key, value = m.group(1).strip(), m.group(2).strip().strip(";,").strip()
        elif len(cells) == 2 and not is_number(cells[0]):
            key, value = cells
        else:
            other.append(line[:MAX_PREAMBLE_VALUE])
            continue
        found[key] = value[:MAX_PREAMBLE_VALUE]
    return found, tuple(other)


_LINE_END = re.compile(r"\r\n|\r|\n")


def split_lines(text: str) -> tuple[list[str], list[str]]:
    """The lines of ``text`` without their ends, and each line's end (``\\r\\n``, ``\\r``,
    ``\\n``; ``""`` after the last line): Windows, old-Mac and Unix files alike."""
    lines: list[str] = []
    ends: list[str] = []
    at = 0
    for m in _LINE_END.finditer(text):
        lines.append(text[at : m.start()])
        ends.append(m.group())
        at = m.end()
    lines.append(text[at:])
    ends.append("")
    return lines, ends


def _line_offsets(lines: Sequence[str], ends: Sequence[str], codec: str, bom: int) -> list[int]:
    """The byte offset of every line's start (``lines`` kept without their ``ends``)."""
    offsets = [bom]
    for line, end in zip(lines, ends, strict=True):
        offsets.append(offsets[-1] + len((line + end).encode(codec)))
    return offsets


def read_layout(source: CsvSource, dialect: CsvDialect) -> CsvLayout:
    """Find the encoding, dialect, preamble, header and units row of a CSV export.

    Raises:
        InputDataError: an empty file, text that does not decode (names ``--encoding`` and a
            guess), no rows of numbers, no header above them, a ``--skip-rows`` line that is
            not a header, or rows of two delimiters (exit 65).
        UsageError: a comma that could be the decimal mark or the thousands separator (exit 2).
    """
    name = source.name
    if source.size == 0:
        raise InputDataError("empty file (0 bytes)", path=name)
    text, bom, codec, whole = _head_text(source, dialect.encoding)
    if not whole and text.endswith("\r"):
        text = text[:-1]  # its "\n" may lie beyond the head
    lines, ends = split_lines(text)
    if not whole and len(lines) > 1:
        lines, ends = lines[:-1], ends[:-1]  # the last line of the head may be cut
    lines, ends = lines[:HEAD_LINES], ends[:HEAD_LINES]
    if not any(line.strip() for line in lines):
        raise InputDataError("no text: the file holds only blank lines", path=name)
    skip = dialect.skip_rows
    if skip is not None and skip >= len(lines):
        raise InputDataError(
            f"--skip-rows {skip}: the file has only {len(lines)} line(s) in its first "
            f"{HEAD_BYTES // 1024} KiB",
            path=name,
        )
    body_from = 0 if skip is None else skip + 1
    try:
        sniff = _sniff_dialect(lines[body_from : body_from + SNIFF_LINES], dialect, name)
    except InputDataError:
        if len(lines) <= body_from + SNIFF_LINES:
            raise
        sniff = _sniff_dialect(lines[body_from:], dialect, name)
    rows = [_split(line, sniff.delimiter) for line in lines[: body_from + SNIFF_LINES]]
    if _data_start(rows, sniff, body_from) is None:
        rows = [_split(line, sniff.delimiter) for line in lines]
    first = next(
        (
            i
            for i in range(body_from, len(rows))
            if _numeric_row(rows[i], sniff.decimal, sniff.thousands)
        ),
        len(rows),
    )
    _check_width(lines, first, sniff, name)
    sniffed = tuple(
        what
        for what, given in (
            ("delimiter", dialect.delimiter),
            ("decimal", dialect.decimal),
            ("thousands", dialect.thousands),
            ("header", skip),
        )
        if given is None
    )
    if skip is not None:
        header_i = skip
        if not rows[header_i]:
            raise InputDataError(
                f"--skip-rows {skip}: line {skip + 1} is blank, not a header", path=name
            )
        if len(rows[header_i]) < min(2, sniff.width):
            raise InputDataError(
                f"--skip-rows {skip}: line {skip + 1} has {len(rows[header_i])} cell(s) where the "
                f"data rows have {sniff.width}: it is not the header; count the lines above it",
                path=name,
            )
        if not _text_row(rows[header_i], sniff.decimal, sniff.thousands):
            raise InputDataError(
                f"--skip-rows {skip}: line {skip + 1} holds numbers, not column names; count the "
                "lines above the header",
                path=name,
            )
        below = header_i + 1
        units_i: int | None = below
        if below >= len(rows) or not (
            rows[below]
            and _text_row(rows[below], sniff.decimal, sniff.thousands)
            and _units_row(rows[below])
        ):
            units_i = None
        start = _data_start(rows, sniff, (units_i or header_i) + 1)
        if start is None:
            raise InputDataError(f"no data rows under the header (line {header_i + 1})", path=name)
    else:
        start = _data_start(rows, sniff)
        if start is None:
            raise InputDataError("no rows of numbers found", path=name)
        above = [i for i in range(start) if rows[i]]
        block: list[int] = []
        for i in reversed(above):
            r = rows[i]
            if len(r) < 2 or not _text_row(r, sniff.decimal, sniff.thousands):
                break
            block.insert(0, i)
        if not block:
            pre = (
                f"lines 1-{start} hold no row of column names"
                if start
                else "it starts with numbers"
            )
            raise InputDataError(
                f"no header row: the numbers start at line {start + 1} and {pre}; add a header "
                "line naming the columns (time, force, compression, ...) or pass --skip-rows N "
                "(the lines before the header)",
                path=name,
            )
        if len(block) >= 2 and _units_row(rows[block[-1]]):
            header_i, units_i = block[-2], block[-1]
        else:
            header_i, units_i = block[-1], None
    header = rows[header_i]
    width = sniff.width
    names = tuple(
        (header[i] if i < len(header) and header[i] else f"column {i + 1}") for i in range(width)
    )
    units_cells = rows[units_i] if units_i is not None else []
    units_row = tuple(units_cells[i] if i < len(units_cells) else "" for i in range(width))
    preamble, other = _preamble(lines[:header_i], sniff.delimiter)
    offsets = _line_offsets(lines, ends, codec, bom)
    data_bytes = offsets[-1] - offsets[start]
    data_rows = sum(1 for line in lines[start:] if line.strip())
    estimate = data_rows if whole else _rows_estimate(source, offsets[start], data_bytes, data_rows)
    return CsvLayout(
        encoding=codec,
        delimiter=sniff.delimiter,
        decimal=sniff.decimal,
        thousands=sniff.thousands,
        header_line=header_i + 1,
        units_line=None if units_i is None else units_i + 1,
        data_line=start + 1,
        data_offset=offsets[start],
        names=names,
        units_row=units_row,
        width=width,
        preamble=preamble,
        preamble_lines=other,
        sniffed=sniffed,
        rows_estimate=estimate,
    )


def _rows_estimate(source: CsvSource, start: int, head_bytes: int, head_rows: int) -> int:
    """The data rows of a file larger than its head: its size over the mean row length of the
    head's rows and of the last :data:`HEAD_BYTES` (numbers grow longer down a file)."""
    tail = source.tail(HEAD_BYTES)
    newline = b"\n" if b"\n" in tail else b"\r"  # an old-Mac file ends its lines with CR
    tail = tail[tail.find(newline) + 1 :]  # the tail's first line may be cut
    per_tail_row = len(tail) / max(tail.count(newline), 1)
    per_row = 0.5 * (head_bytes / max(head_rows, 1) + per_tail_row)
    return int((source.size - start) / max(per_row, 1.0))


def _other_delimiter(line: str, sniff: _Dialect) -> str | None:
    """Another delimiter that splits ``line`` into the data's width (a mixed-delimiter row)."""
    for other in DELIMITERS:
        if other != sniff.delimiter and len(_split(line, other)) == sniff.width:
            return other
    return None


def _check_width(lines: Sequence[str], start: int, sniff: _Dialect, name: str) -> None:
    """Refuse a data row of the head that another delimiter splits into the data's width."""
    for i in range(start, len(lines)):
        if lines[i].count(sniff.delimiter) + 1 >= sniff.width:
            continue  # wide enough at the delimiter (the common case, without a csv parse)
        cells = _split(lines[i], sniff.delimiter)
        if not cells or len(cells) == sniff.width:
            continue
        other = _other_delimiter(lines[i], sniff)
        if other is not None:
            raise InputDataError(mixed_message(i + 1, len(cells), other, sniff), path=name)


def mixed_message(line: int, cells: int, other: str, sniff: _Dialect) -> str:
    """The one line of a mixed-delimiter file."""
    d, o = DELIMITER_NAMES[sniff.delimiter], DELIMITER_NAMES[other]
    return (
        f"mixed delimiters: line {line} splits into {sniff.width} cells at {o!r}, not at {d!r} "
        f"({cells} cell(s)) like the rows above it; write the file with one delimiter"
    )


# ---------------------------------------------------------------------------- numbers


def read_columns(
    source: CsvSource, layout: CsvLayout, columns: Sequence[int]
) -> dict[int, FloatArray]:
    """The numbers of ``columns`` (0-based) from the first data line to the end of the file.

    pandas' C parser reads them (blank lines skipped, quotes, the decimal mark and thousands
    separator of ``layout``); a cell that is not a number, an empty cell or a short row in one
    of ``columns`` is found again line by line and named.

    Raises:
        InputDataError: such a cell or row (its line, column and text), text that does not
            decode (names ``--encoding``), or no data rows (exit 65).
    """
    import pandas as pd

    wanted = sorted(set(columns))
    try:
        with source.stream(layout.data_offset) as fh:
            frame = pd.read_csv(
                fh,
                sep=layout.delimiter,
                header=None,
                names=list(range(max(layout.width, wanted[-1] + 1))),
                usecols=wanted,
                index_col=False,
                decimal=layout.decimal,
                thousands=layout.thousands,
                dtype=np.float64,
                engine="c",
                encoding=layout.encoding,
                skipinitialspace=True,
                skip_blank_lines=True,
                quotechar='"',
            )
    except UnicodeDecodeError:
        raise _diagnose_encoding(source, layout) from None
    except (ValueError, pd.errors.ParserError):
        raise _diagnose(source, layout, wanted) from None
    out = {c: frame[c].to_numpy(dtype=np.float64) for c in wanted}
    for c in wanted:
        if np.isnan(out[c]).any():
            raise _diagnose(source, layout, wanted)
    return out


def _diagnose_encoding(source: CsvSource, layout: CsvLayout) -> InputDataError:
    """The decode error of a byte beyond the head, found by decoding the file in blocks."""
    decoder = codecs.getincrementaldecoder(layout.encoding)(errors="strict")
    line = 1
    with source.stream(0) as fh:
        while block := fh.read(1 << 20):
            try:
                decoder.decode(block)
            except UnicodeDecodeError as err:
                line += block[: max(err.start, 0)].count(b"\n")
                guess = guess_encoding(block[max(err.start - 200, 0) : err.start + 200])
                hint = f" {guess[0]}" if guess else " (e.g. gbk, cp1252, latin-1)"
                byte = block[err.start : err.start + 1].hex()
                return InputDataError(
                    f"not {spelled(layout.encoding)} text: byte 0x{byte} on line {line} does not "
                    "decode; "
                    f"pass --encoding{hint}",
                    path=source.name,
                )
            line += block.count(b"\n")
    return InputDataError(f"not {spelled(layout.encoding)} text; pass --encoding", path=source.name)


def _diagnose(source: CsvSource, layout: CsvLayout, wanted: Sequence[int]) -> InputDataError:
    """The first data line whose cells in ``wanted`` are not all numbers, named."""
    sniff = _Dialect(layout.delimiter, layout.decimal, layout.thousands, layout.width)
    with source.stream(layout.data_offset) as fh:
        text = io.TextIOWrapper(fh, encoding=layout.encoding, newline="")
        for k, raw in enumerate(text):
            line = raw.rstrip("\r\n")
            number = layout.data_line + k
            if not line.strip():
                continue
            cells = _split(line, layout.delimiter)
            other = _other_delimiter(line, sniff)
            if len(cells) != layout.width and other is not None:
                return InputDataError(
                    mixed_message(number, len(cells), other, sniff), path=source.name
                )
            for c in wanted:
                cell = cells[c] if c < len(cells) else None
                if cell is None:
                    return InputDataError(
                        f"line {number}: {len(cells)} cell(s), no cell for column "
                        f"{layout.names[c]!r} (the data rows have {layout.width})",
                        path=source.name,
                    )
                if not cell:
                    return InputDataError(
                        f"line {number}: empty cell in column {layout.names[c]!r}",
                        path=source.name,
                    )
                if not is_number(cell, layout.decimal, layout.thousands):
                    return InputDataError(
                        f"line {number}: {cell[:40]!r} in column {layout.names[c]!r} is not a "
                        f"number{_number_hint(cell, layout)}",
                        path=source.name,
                    )
    return InputDataError("a data row could not be read", path=source.name)


def _number_hint(cell: str, layout: CsvLayout) -> str:
    """Why a number-looking cell was not read: the decimal mark or a separator."""
    for decimal in (".", ","):
        for thousands in (None, *THOUSANDS):
            if (decimal, thousands) == (layout.decimal, layout.thousands):
                continue
            if thousands not in (decimal, layout.delimiter) and is_number(cell, decimal, thousands):
                given = f"--decimal {decimal}" + (
                    f" --thousands {thousands!r}" if thousands else ""
                )
                return f" with decimal mark {layout.decimal!r}; pass {given}?"
    return ""
