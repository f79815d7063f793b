"""The rows of an artifact, for people and pipes (the library behind ``deformctl inspect --rows``).

Every table deformctl writes (catalog, coefficients, lift results, index table, predictions, a
sweep's dataset directory) and a lift log's attempts can be shown as rows. :func:`artifact_rows`
reads them through the same validating readers the pipeline uses, and returns a :class:`Rows`: the
frame, each column's unit and the kind. :func:`select_rows` picks columns and the first rows;
:func:`rows_records` and :func:`rows_csv` turn them into JSON records and CSV text with every
number at full precision (a float's ``repr``, which reads back to the same double).

A lift log's attempts (:func:`lift_attempt_frame`) are one row per attempt: the grip force, the
outcome, the slip distance, and the L_f its search found (the smallest grip force that lifted,
what ``lift`` reports) on every row of that object.
"""

from __future__ import annotations

import io
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from deformctl.artifacts.dataset import describe_dataset
from deformctl.artifacts.describe import _table_kind_from_columns, sniff_format
from deformctl.artifacts.io import PathArg, display_name, read_input_bytes
from deformctl.artifacts.mcap import KIND_LIFT, lift_attempts_from_contents, load_mcap
from deformctl.artifacts.schema import TABLE_KINDS, load_table_spec
from deformctl.artifacts.tables import (
    PARQUET_MAGIC,
    _frame_from_arrow,
    read_catalog_bytes,
    read_parquet_bytes,
)
from deformctl.errors import InputDataError, SchemaError, UsageError
from deformctl.series import LiftAttempt

#: The kind of the rows :func:`lift_attempt_frame` returns.
KIND_ATTEMPTS = "lift_attempts"
#: Units of the attempt rows' columns (None: no unit).
ATTEMPT_UNITS: dict[str, str | None] = {
    "object_id": None,
    "attempt_index": None,
    "grip_force_n": "N",
    "lifted": None,
    "outcome": None,
    "slip_m": "m",
    "lift_force_n": "N",
}


@dataclass(frozen=True)
class Rows:
    """Rows of one artifact.

    Attributes:
        kind: the table kind (``lift_results``, ...) or ``lift_attempts``.
        frame: the rows, columns in file order.
        units: column → unit text (None: dimensionless or not a number).
        total: rows in the artifact (``frame`` may hold fewer after :func:`select_rows`).
    """

    kind: str
    frame: pd.DataFrame
    units: dict[str, str | None]
    total: int


def table_frame(data: bytes, path: PathArg) -> pd.DataFrame | None:
    """The validated frame of a Parquet table or a catalog CSV; None for any other artifact.

    Raises:
        InputDataError, SchemaError: a damaged or invalid table (exit 65).
    """
    name = display_name(path)
    if data.startswith(PARQUET_MAGIC):
        table, meta = read_parquet_bytes(data, path)
        if meta is not None:
            kind = str(meta["kind"])
        else:
            kind = _table_kind_from_columns(table.column_names, name)
        if kind not in TABLE_KINDS:
            raise SchemaError(f"unknown table kind {kind!r}", path=name, field="kind")
        if kind == "catalog":
            return read_catalog_bytes(data, path)
        return _frame_from_arrow(table, meta, kind, path)
    if sniff_format(data) == "csv":
        return read_catalog_bytes(data, path)
    return None


def dataset_rows(path: str | os.PathLike[str]) -> Rows:
    """The rows of a sweep's dataset directory: the parts written so far, in order (an
    interrupted sweep shows the rows it has).

    Raises:
        InputDataError: not a dataset directory, or an unreadable part (exit 65).
    """
    info = describe_dataset(path)
    parts = sorted(Path(path).glob("part-*.parquet"))
    tables = [_read_part(p) for p in parts]
    frame = pa.concat_tables(tables).to_pandas() if tables else pd.DataFrame()
    units: dict[str, str | None] = {}
    for fld in tables[0].schema if tables else []:
        unit = (fld.metadata or {}).get(b"unit", b"").decode("utf-8", "replace")
        units[fld.name] = unit or None
    kind = str(info.get("kind") or "dataset")
    if kind in TABLE_KINDS:
        spec = load_table_spec(kind)
        for column in frame.columns:
            col = spec.column(str(column))
            if col is not None and units.get(str(column)) is None:
                units[str(column)] = col.unit
    return Rows(kind, frame, {str(c): units.get(str(c)) for c in frame.columns}, len(frame))


def _read_part(path: Path) -> pa.Table:
    try:
        return pq.read_table(path).replace_schema_metadata(None)
    except (OSError, pa.ArrowException) as err:
        text = " ".join(str(err).split())[:160]
        raise InputDataError(f"not a readable Parquet file ({text})", path=path) from None


def attempt_outcome(attempt: LiftAttempt) -> str:
    """An attempt's verdict: ``lifted``, ``slipped``, or ``on table`` when the object slipped
    so far that it never left the table (the simulator's ``off_table`` detail)."""
    out = attempt.outcome
    if out.lifted:
        return "lifted"
    if (out.details or {}).get("off_table") is False:
        return "on table"
    return "slipped"


def lift_attempt_frame(attempts: list[LiftAttempt]) -> pd.DataFrame:
    """One row per attempt (columns of :data:`ATTEMPT_UNITS`), objects in log order.

    ``lift_force_n`` is the object's L_f: the smallest grip force of its attempts that lifted
    (NaN when none did), the value ``lift`` reports as ``lift_force_n``.
    """
    found: dict[str, float] = {}
    for att in attempts:
        if att.outcome.lifted:
            prev = found.get(att.object_id, math.inf)
            found[att.object_id] = min(prev, float(att.outcome.grip_force_n))
    rows = [
        {
            "object_id": att.object_id,
            "attempt_index": int(att.attempt_index),
            "grip_force_n": float(att.outcome.grip_force_n),
            "lifted": bool(att.outcome.lifted),
            "outcome": attempt_outcome(att),
            "slip_m": float(att.outcome.slip_m),
            "lift_force_n": found.get(att.object_id, math.nan),
        }
        for att in attempts
    ]
    frame = pd.DataFrame(rows, columns=list(ATTEMPT_UNITS))
    return frame.astype({"attempt_index": "int64", "lifted": "bool"})


def artifact_rows(path: PathArg, data: bytes | None, *, attempts: bool = False) -> Rows | None:
    """The rows of ``path``: a table, a dataset directory, or (``attempts``) a lift log.

    Args:
        path: the artifact; a directory is read as a sweep's dataset.
        data: the file's bytes when already read (stdin can be read once only).
        attempts: read a lift log's attempts (any other file is refused).

    Returns:
        The rows, or None for an artifact without rows (a squeeze log, a model, a lift log
        without ``attempts``).

    Raises:
        SchemaError: ``attempts`` on a file that is not a lift log (exit 65).
        InputDataError: a damaged or invalid file (exit 65).
    """
    if isinstance(path, str | os.PathLike) and os.path.isdir(path) and data is None:
        if attempts:
            raise SchemaError(
                "is a dataset directory, not a lift log (its attempts are in _logs/part-*.mcap)",
                path=display_name(path),
            )
        return dataset_rows(path)
    raw = read_input_bytes(path) if data is None else data
    name = display_name(path)
    if attempts:
        if sniff_format(raw) != "mcap":
            raise SchemaError(
                f"is not a lift log ({sniff_format(raw)} file); --attempts reads a lift log",
                path=name,
            )
        contents = load_mcap(raw, path)
        if contents.kind != KIND_LIFT:
            what = f"a {contents.kind}" if contents.kind else "not a deformctl log"
            raise SchemaError(f"is {what}, not a lift log; --attempts reads a lift log", path=name)
        frame = lift_attempt_frame(lift_attempts_from_contents(contents))
        return Rows(KIND_ATTEMPTS, frame, dict(ATTEMPT_UNITS), len(frame))
    frame = table_frame(raw, path)
    if frame is None:
        return None
    units = frame.attrs.get("units") or {}
    kind = str(frame.attrs.get("kind", "table"))
    return Rows(kind, frame, {str(c): units.get(str(c)) for c in frame.columns}, len(frame))


def select_rows(rows: Rows, columns: list[str] | None, limit: int | None, name: str) -> Rows:
    """The first ``limit`` rows (None: all) of ``columns`` (None: all, in file order).

    Raises:
        UsageError: a column the artifact does not have; the message lists the real ones.
    """
    frame = rows.frame
    if columns is not None:
        real = [str(c) for c in frame.columns]
        missing = [c for c in columns if c not in real]
        if missing:
            raise UsageError(
                f"--columns: {name} has no column {missing[0]!r}; its columns: {', '.join(real)}"
            )
        frame = frame[columns]
    if limit is not None:
        frame = frame.iloc[:limit]
    units = {str(c): rows.units.get(str(c)) for c in frame.columns}
    return Rows(rows.kind, frame.reset_index(drop=True), units, rows.total)


def _json_value(value: Any) -> Any:
    """A cell as JSON: numpy scalars as Python, NaN / missing as None, floats at full precision."""
    if value is None or value is pd.NA or value is pd.NaT:
        return None
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def rows_records(rows: Rows) -> list[dict[str, Any]]:
    """The rows as JSON-safe records (NaN → None; numbers keep every digit)."""
    columns = [str(c) for c in rows.frame.columns]
    return [
        {c: _json_value(v) for c, v in zip(columns, values, strict=True)}
        for values in rows.frame.itertuples(index=False, name=None)
    ]


def _csv_cell(value: Any) -> Any:
    value = _json_value(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return value


def rows_csv(rows: Rows) -> str:
    """The rows as CSV text with a header: floats as ``repr`` (they read back bit for bit),
    booleans ``true``/``false``, missing values empty."""
    import csv

    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow([str(c) for c in rows.frame.columns])
    for values in rows.frame.itertuples(index=False, name=None):
        writer.writerow(["" if (c := _csv_cell(v)) is None else c for v in values])
    return buffer.getvalue()
