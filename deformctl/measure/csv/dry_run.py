"""``measure csv --dry-run``: what would be detected in each CSV export, and nothing written.

Each file is read exactly as a real run reads it (:meth:`CsvFileTask.read`: the layout, the
columns, the checks, the force sign, the segmentation), so a file a real run refuses is refused
with the same one line and exit code; nothing is written. :func:`describe` turns one file's
:class:`~deformctl.measure.recording.Recording` into the lines the command prints: the header
row, the preamble lines skipped, the delimiter, decimal mark and encoding, each role's column
with its unit and where each came from, how the position is read, the force sign decision, and
the squeezes a real run would write.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from deformctl.artifacts.io import display_name
from deformctl.measure.csv.batch import CsvBatchResult, CsvFile, CsvFileTask, FileOutcome, _Catching
from deformctl.measure.recording import Recording
from deformctl.parallel import map_in_order
from deformctl.parallel.auto import AUTO, Auto


def dry_run_files(
    files: Sequence[CsvFile], task: CsvFileTask, *, workers: int | Auto = AUTO
) -> CsvBatchResult:
    """Read every file as ``measure csv`` would (each file's error caught and kept, as a
    many-file real run keeps it); write nothing."""
    if len(files) == 1:
        return CsvBatchResult([_Catching(task)(files[0])])
    return CsvBatchResult(map_in_order(_Catching(task), list(files), workers=workers))


def _sniffed(layout: dict[str, Any], key: str) -> str:
    return "found" if key in layout.get("sniffed", ()) else "given"


def _preamble(details: Mapping[str, Any]) -> str:
    layout = details["layout"]
    skipped = int(layout["header_line"]) - 1
    if skipped == 0:
        return "preamble: none (the header is line 1)"
    pairs = len(details.get("preamble", {}))
    kv = f", {pairs} of them 'key: value' lines" if pairs else ""
    return f"preamble: {skipped} line(s) before the header skipped (lines 1-{skipped}{kv})"


def _column(role: str, col: dict[str, Any]) -> str:
    return (
        f"{role}: column {col['column']!r} in {col['unit']} (column by {col['column_from']}, "
        f"unit from {col['unit_from']})"
    )


def _delimiter(name: str) -> str:
    return repr(name) if len(name) == 1 else name


def _sign(sign: dict[str, Any], force_column: str) -> str:
    why = {
        "one_sign": "nearly all of the force has that sign",
        "covariance": "the sign that grows with the compression",
        "option": f"--force-sign {sign['option']}",
    }[sign["by"]]
    action = "flipped to positive" if sign["flipped"] else "kept as it is"
    return (
        f"force sign: compressive force is {sign['compressive']} in column {force_column!r} "
        f"({why}): {action}"
    )


def describe(file: CsvFile, rec: Recording) -> list[str]:
    """The lines ``measure csv --dry-run`` prints of one file read (first line names it)."""
    d = rec.details
    layout = d["layout"]
    columns: dict[str, dict[str, Any]] = d["columns"]
    thousands = layout["thousands"]
    units = (
        f"units row: line {layout['units_line']}"
        if layout["units_line"] is not None
        else "units row: none"
    )
    lines = [
        f"{display_name(file.path)}: object {file.object_id!r}",
        _preamble(d),
        f"header row: line {layout['header_line']} ({_sniffed(layout, 'header')}); {units}; "
        f"data from line {layout['data_line']}",
        f"delimiter: {_delimiter(layout['delimiter'])} ({_sniffed(layout, 'delimiter')}); "
        f"decimal mark: {layout['decimal']!r} ({_sniffed(layout, 'decimal')}); "
        f"thousands separator: "
        f"{'none' if thousands is None else repr(thousands)} ({_sniffed(layout, 'thousands')}); "
        f"encoding: {layout['encoding']}",
        *(_column(role, col) for role, col in columns.items()),
    ]
    reading = d["position_reading"]
    from deformctl.measure.csv.reader import POSITION_RULES

    lines.append(
        f"position: column {reading['column']!r} ({reading['role']}) read as "
        f"{reading['reading']}: {POSITION_RULES[reading['reading']]}"
    )
    lines.append(_sign(d["force_sign"], columns["force"]["column"]))
    samples = sum(len(s.time_s) for s in rec.squeezes)
    duration_s = sum(float(s.time_s[-1]) for s in rec.squeezes)
    flags = ",".join(rec.flags) or "none"
    lines.append(
        f"would read: {len(rec.squeezes)} squeeze(s), {samples} samples, {duration_s:.1f} s at "
        f"{rec.force_rate_hz:.4g} Hz; recording flags: {flags}"
    )
    lines.extend(f"warning: {w}" for w in rec.warnings)  # as a real run warns
    return [lines[0], *(f"  {line}" for line in lines[1:])]


def outcome_lines(outcome: FileOutcome) -> list[str]:
    """:func:`describe` of a file read; its ``error:`` line when it was refused."""
    if outcome.recording is None:
        return [f"error: {outcome.error}"]
    return describe(outcome.file, outcome.recording)
