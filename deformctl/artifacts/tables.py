"""Parquet tables and the object catalog: read with validation, write atomically with provenance.

A table written by deformctl carries, in its Arrow schema:

* per field, metadata ``unit`` and ``description`` from the column spec;
* the schema metadata key ``deformctl``: JSON with ``kind``, ``schema``, ``schema_version``,
  ``provenance`` (see :class:`~deformctl.artifacts.provenance.Provenance`) and
  ``content_sha256``, a digest of the columns (names, types, field metadata, values) and of the
  rest of that JSON. Parquet has no checksum of its own that pyarrow verifies, so the digest is
  what turns a flipped byte in a data page or in the metadata into a refused file instead of
  silently different numbers.

Readers return a :class:`pandas.DataFrame` normalised by
:func:`~deformctl.artifacts.schema.validate_frame`, with ``df.attrs``:
``kind``, ``schema_version``, ``units`` (column → unit) and ``provenance`` (or None for tables
written by other tools, which are accepted when their columns match the spec).
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import struct
from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from deformctl import jsonsafe
from deformctl.artifacts.io import (
    PathArg,
    atomic_output,
    display_name,
    forget_inputs,
    is_stdio,
    read_input_bytes,
)
from deformctl.artifacts.provenance import Provenance, to_json
from deformctl.artifacts.schema import TABLE_KINDS, load_table_spec, validate_frame
from deformctl.errors import InputDataError, SchemaError

META_KEY = b"deformctl"
#: Arrow type of each column-spec dtype.
PARQUET_MAGIC = b"PAR1"
ARROW_TYPES = {
    "string": pa.string(),
    "float64": pa.float64(),
    "int64": pa.int64(),
    "bool": pa.bool_(),
}

#: Exceptions that decoding a damaged Parquet file can raise inside pyarrow / pandas.
_DECODE_ERRORS = (
    pa.ArrowException,
    OSError,
    ValueError,
    TypeError,
    KeyError,
    IndexError,
    OverflowError,
    EOFError,
    struct.error,
    MemoryError,
    UnicodeDecodeError,
)


def _content_digest(table: pa.Table, meta: dict[str, Any]) -> str:
    """sha256 over ``meta`` (without the digest) and every column's name, type and values."""
    h = hashlib.sha256()
    h.update(to_json({k: v for k, v in meta.items() if k != "content_sha256"}).encode())
    for i, fld in enumerate(table.schema):
        fmeta = sorted((fld.metadata or {}).items())
        h.update(repr((fld.name, str(fld.type), fmeta)).encode())
        col = table.column(i)
        h.update(np.asarray(col.is_null().to_numpy(zero_copy_only=False), dtype=bool).tobytes())
        if pa.types.is_floating(fld.type) or pa.types.is_integer(fld.type):
            values = col.fill_null(0).to_numpy(zero_copy_only=False)
            h.update(np.ascontiguousarray(values).tobytes())
        elif pa.types.is_boolean(fld.type):
            values = col.fill_null(False).to_numpy(zero_copy_only=False)
            h.update(np.asarray(values, dtype=bool).tobytes())
        else:
            h.update(json.dumps(col.to_pylist(), default=str).encode())
    return h.hexdigest()


def _to_arrow(df: pd.DataFrame, kind: str) -> pa.Table:
    """Build the Arrow table with spec types and per-field unit/description metadata."""
    spec = load_table_spec(kind)
    arrays = []
    fields = []
    for name in df.columns:
        col = spec.column(str(name))
        if col is None:
            arr = pa.array(df[name].to_numpy(), from_pandas=True)
            fields.append(pa.field(str(name), arr.type))
        else:
            typ = ARROW_TYPES[col.dtype]
            values = df[name].to_numpy()
            arr = pa.array(list(values) if col.dtype == "string" else values, type=typ)
            meta = {"unit": col.unit or "", "description": col.description}
            fields.append(pa.field(col.name, typ, metadata=meta))
        arrays.append(arr)
    return pa.Table.from_arrays(arrays, schema=pa.schema(fields))


def table_schema(kind: str) -> pa.Schema:
    """The Arrow schema of a table kind's spec columns, in spec order, with unit metadata."""
    spec = load_table_spec(kind)
    return pa.schema(
        [
            pa.field(
                col.name,
                ARROW_TYPES[col.dtype],
                metadata={"unit": col.unit or "", "description": col.description},
            )
            for col in spec.columns
        ]
    )


def table_metadata(kind: str, provenance: Provenance | None) -> dict[str, Any]:
    """The JSON stored under the Parquet schema metadata key ``deformctl`` (without digest)."""
    spec = load_table_spec(kind)
    return {
        "kind": kind,
        "schema": spec.name,
        "schema_version": spec.version,
        "provenance": None if provenance is None else provenance.to_dict(),
    }


def write_table(
    df: pd.DataFrame,
    path: PathArg,
    kind: str,
    *,
    provenance: Provenance | None,
    force: bool = False,
) -> pd.DataFrame:
    """Validate ``df`` against the spec of ``kind`` and write it as Parquet, atomically.

    Args:
        df: one row per record; spec columns plus any extra columns.
        path: destination ``.parquet`` file, or ``-`` for stdout (the Parquet bytes).
        kind: a table kind from :data:`~deformctl.artifacts.schema.TABLE_KINDS`.
        provenance: where the data came from (stored in the file); None only for tests and
            tools that truly have none.
        force: overwrite an existing file.

    Returns:
        The normalised frame that was written.

    Raises:
        SchemaError: ``df`` does not match the spec (nothing is written).
        OutputExistsError: ``path`` exists and ``force`` is false.
    """
    if kind not in TABLE_KINDS:
        raise ValueError(f"unknown table kind {kind!r}")
    norm = validate_frame(df, kind, path=path)
    table = _to_arrow(norm, kind)
    meta = table_metadata(kind, provenance)
    meta["content_sha256"] = _content_digest(table, meta)
    table = table.replace_schema_metadata({META_KEY: to_json(meta).encode()})
    with atomic_output(path, force=force) as tmp:
        pq.write_table(table, tmp)
    return norm


def _parse_meta(raw: bytes | None, path: PathArg) -> dict[str, Any] | None:
    if raw is None:
        return None
    try:
        meta = jsonsafe.loads(raw, allow_nan=True)
    except ValueError as err:
        raise SchemaError(
            f"metadata is not valid JSON ({err})", path=path, field="deformctl"
        ) from None
    if not isinstance(meta, dict) or not isinstance(meta.get("kind"), str):
        raise SchemaError("metadata has no 'kind'", path=path, field="deformctl")
    return meta


#: The most columns a catalog or a table may have: the widest spec (coefficients) has 68, and a
#: catalog's extra columns are a user's notes. A header of 10,010 columns in a 79 kB catalog took
#: ``inspect`` over 120 s and 2.2 GB; it is refused before any row is parsed.
MAX_COLUMNS = 1000


def _check_column_count(count: int, name: str) -> None:
    """Refuse a file with more than :data:`MAX_COLUMNS` columns (exit 65)."""
    if count > MAX_COLUMNS:
        raise InputDataError(
            f"{count} columns, more than the {MAX_COLUMNS} a catalog or table may have", path=name
        )


def read_parquet_bytes(data: bytes, path: PathArg) -> tuple[pa.Table, dict[str, Any] | None]:
    """Decode Parquet bytes and verify the deformctl digest when present.

    Returns:
        The Arrow table and the ``deformctl`` metadata (None for tables from other tools).

    Raises:
        InputDataError: the bytes are not a readable Parquet file.
        SchemaError: the digest or the metadata does not match.
    """
    name = display_name(path)
    if not data:
        raise InputDataError(
            "empty input: no table on stdin (did the command before the pipe fail?)"
            if is_stdio(path)
            else "empty file: not a Parquet table",
            path=name,
        )
    if len(data) < 12 or data[:4] != PARQUET_MAGIC or data[-4:] != PARQUET_MAGIC:
        raise InputDataError("not a Parquet file (bad magic bytes)", path=name)
    try:
        # An Arrow buffer, never a Python file object: Arrow's I/O threads read a Python file
        # through the GIL (PyReadableFile::ReadAt), and a read still queued when the interpreter
        # exits after an error takes the GIL during finalization, which ends that std::thread with
        # pthread_exit and aborts the process ("terminate called without an active exception",
        # exit -6). A BufferReader is read without the interpreter. And on this thread only
        # (use_threads=False): the buffer wraps the Python bytes (arrow::py::PyBuffer), and a
        # CPU-pool worker dropping the last reference to it after the read takes the GIL in
        # ~PyBuffer, the same abort when that happens during finalization (found in a core dump
        # of `predict MODEL bad_meta.parquet --catalog objects.csv`, about 1 run in 15).
        pf = pq.ParquetFile(pa.BufferReader(data))
        _check_column_count(pf.metadata.num_columns, name)
        created_by = str(pf.metadata.created_by or "")
        kv_keys = set((pf.metadata.metadata or {}).keys())
        table = pf.read(use_threads=False)
    except _DECODE_ERRORS as err:
        raise InputDataError(f"not a readable Parquet file ({_short(err)})", path=name) from None
    if (not created_by or created_by.startswith("parquet-cpp-arrow") or _garbled(created_by)) and (
        b"ARROW:schema" not in kv_keys
    ):
        # pyarrow always stores its schema (and every writer names itself); without them the
        # footer's key/value metadata was lost.
        raise SchemaError(
            "damaged table: written by Arrow but its schema metadata is missing",
            path=name,
            field="ARROW:schema",
        )
    schema_meta = table.schema.metadata or {}
    raw = schema_meta.get(META_KEY)
    if raw is None and _looks_like_ours(table):
        raise SchemaError(
            "damaged table: deformctl column metadata without the 'deformctl' table metadata",
            path=name,
            field="deformctl",
        )
    meta = _parse_meta(raw, name)
    if meta is not None:
        expected = meta.get("content_sha256")
        try:
            actual = _content_digest(table, meta)
        except _DECODE_ERRORS as err:
            raise InputDataError(f"cannot decode columns ({_short(err)})", path=name) from None
        if expected != actual:
            raise SchemaError(
                "content checksum mismatch: the file is damaged or was edited",
                path=name,
                field="content_sha256",
            )
    return table, meta


#: The longest writer name a Parquet footer's ``created_by`` plausibly holds ("parquet-mr version
#: 1.13.1 (build db4183109d5b734ec5930d870cdae161e408ddba)" is 65 characters).
MAX_CREATED_BY_CHARS = 200


def _garbled(created_by: str) -> bool:
    """True when ``created_by`` is not a writer's name but other footer bytes read in its place.

    One flipped byte in a footer's field header shifts the Thrift decoder, which then reads the
    key/value metadata's values (the base64 Arrow schema, several kB) as ``created_by`` and the
    key/value list as absent (found by tests/artifacts/test_corruption.py).
    """
    return len(created_by) > MAX_CREATED_BY_CHARS or not created_by.isprintable()


def _looks_like_ours(table: pa.Table) -> bool:
    """True for a table that has deformctl's traces but lost its ``deformctl`` key.

    A flipped byte in the key's name would otherwise turn a deformctl table into an anonymous
    one that is read without its provenance and digest.
    """
    if any(fld.metadata and b"unit" in fld.metadata for fld in table.schema):
        return True
    keys = (table.schema.metadata or {}).keys()
    return any(
        len(k) == len(META_KEY) and sum(a != b for a, b in zip(k, META_KEY, strict=True)) <= 1
        for k in keys
    )


def _short(err: BaseException) -> str:
    text = " ".join(str(err).split()) or type(err).__name__
    return text if len(text) <= 160 else text[:157] + "..."


def _frame_from_arrow(
    table: pa.Table, meta: dict[str, Any] | None, kind: str, path: PathArg
) -> pd.DataFrame:
    """Validate an Arrow table as ``kind`` and attach kind/units/provenance as ``df.attrs``."""
    name = display_name(path)
    _refuse_duplicates(table.column_names, name)
    spec = load_table_spec(kind)
    provenance = None
    if meta is not None:
        if meta["kind"] != kind:
            raise SchemaError(
                f"is a {meta['kind']} table, expected {kind}", path=name, field="deformctl"
            )
        version = meta.get("schema_version")
        if not isinstance(version, int) or version > spec.version or version < 1:
            raise SchemaError(
                f"schema version {version!r} not supported (this deformctl reads {kind} "
                f"v{spec.version})",
                path=name,
                field="schema_version",
            )
        if meta.get("provenance") is not None:
            provenance = Provenance.from_dict(meta["provenance"], path=name)
    units: dict[str, str | None] = {}
    for fld in table.schema:
        file_unit = (fld.metadata or {}).get(b"unit")
        col = spec.column(fld.name)
        if (
            col is not None
            and file_unit is not None
            and file_unit.decode("utf-8", "replace") != (col.unit or "")
        ):
            raise SchemaError(
                f"unit {file_unit.decode('utf-8', 'replace')!r} differs from the spec's "
                f"{col.unit!r}",
                path=name,
                field=fld.name,
            )
        if col is not None:
            units[fld.name] = col.unit
        elif file_unit:
            units[fld.name] = file_unit.decode("utf-8", "replace")
        else:
            units[fld.name] = None
    try:
        df = table.to_pandas()
    except _DECODE_ERRORS as err:
        raise InputDataError(f"cannot convert columns ({_short(err)})", path=name) from None
    df = validate_frame(df, kind, path=name)
    df.attrs = {
        "kind": kind,
        "schema_version": spec.version if meta is None else meta["schema_version"],
        "units": {c: units.get(str(c)) for c in df.columns},
        "provenance": provenance,
    }
    return df


def read_table(
    path: PathArg, kind: str | None = None, *, refuse_foreign: str | None = None
) -> pd.DataFrame:
    """Read and validate a Parquet table.

    Args:
        path: the ``.parquet`` file, or ``-`` for stdin.
        kind: the expected table kind; None accepts whatever kind the file's metadata names.
        refuse_foreign: when given, a table without the ``deformctl`` metadata (one written by
            another tool, whatever its columns) is refused; the text says how to make one.

    Returns:
        The validated, normalised frame; ``df.attrs`` holds ``kind``, ``schema_version``,
        ``units`` and ``provenance``.

    Raises:
        MissingInputError: ``path`` does not exist (exit 66).
        InputDataError: not a Parquet file, or damaged (exit 65).
        SchemaError: wrong kind, missing column, wrong dtype, bad values (exit 65).
    """
    if kind is not None and kind not in TABLE_KINDS:
        raise ValueError(f"unknown table kind {kind!r}")
    data = read_input_bytes(path)
    table, meta = read_parquet_bytes(data, path)
    if refuse_foreign is not None and meta is None:
        raise SchemaError(
            f"not a deformctl {kind or 'table'} (no 'deformctl' metadata): {refuse_foreign}",
            path=display_name(path),
        )
    if kind is None:
        if meta is None:
            raise SchemaError(
                "not a deformctl table (no 'deformctl' metadata); its kind is unknown",
                path=display_name(path),
            )
        kind = str(meta["kind"])
        if kind not in TABLE_KINDS:
            raise SchemaError(f"unknown table kind {kind!r}", path=display_name(path), field="kind")
    return _frame_from_arrow(table, meta, kind, path)


def read_catalog_bytes(data: bytes, path: PathArg) -> pd.DataFrame:
    """Parse and validate a catalog from CSV or Parquet bytes (see :func:`read_catalog`)."""
    name = display_name(path)
    if data[:4] == PARQUET_MAGIC:
        table, meta = read_parquet_bytes(data, path)
        if table.num_rows == 0:
            raise InputDataError("empty catalog: no objects", path=name)
        df = _frame_from_arrow(table, meta, "catalog", path)
    else:
        df = _parse_catalog_csv(data, name)
    if len(df) == 0:
        raise InputDataError("empty catalog: no objects", path=name)
    return df


def _refuse_duplicates(columns: Sequence[str], name: str) -> None:
    """A column named twice is refused, never silently renamed (pandas reads ``x.1``)."""
    seen: set[str] = set()
    for column in columns:
        key = str(column).strip()
        if key in seen:
            raise SchemaError("column named twice in the header", path=name, field=key)
        seen.add(key)


def _parse_catalog_csv(data: bytes, name: str) -> pd.DataFrame:
    if not data.strip():
        raise InputDataError("empty catalog: the file is empty", path=name)
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        raise InputDataError(f"not UTF-8 text (byte {err.start})", path=name) from None
    if "\x00" in text:
        raise InputDataError("not a CSV file (contains NUL bytes)", path=name)
    try:
        rows = csv.reader(io.StringIO(text))
        header = next(rows, [])
        _check_column_count(len(header), name)
        for row in rows:  # a short or long row is refused, never padded with NaN
            if row and len(row) != len(header) and any(cell.strip() for cell in row):
                raise InputDataError(
                    f"line {rows.line_num}: {len(row)} fields, the header has {len(header)}",
                    path=name,
                )
    except csv.Error as err:
        raise InputDataError(f"not a valid CSV catalog ({_short(err)})", path=name) from None
    _refuse_duplicates(header, name)
    try:
        raw = pd.read_csv(
            io.StringIO(text),
            dtype={"object_id": str},
            skipinitialspace=True,
            keep_default_na=True,
        )
    except (pd.errors.ParserError, pd.errors.EmptyDataError, ValueError, TypeError) as err:
        raise InputDataError(f"not a valid CSV catalog ({_short(err)})", path=name) from None
    raw.columns = [str(c).strip() for c in raw.columns]
    if len(raw) == 0:
        raise InputDataError("empty catalog: no objects", path=name)
    unnamed = [c for c in raw.columns if c.startswith("Unnamed:")]
    if unnamed:
        raise SchemaError("header has an empty column name", path=name, field=unnamed[0])
    df = validate_frame(raw, "catalog", path=name)
    df.attrs = {
        "kind": "catalog",
        "schema_version": load_table_spec("catalog").version,
        "units": {c: load_table_spec("catalog").units.get(str(c)) for c in df.columns},
        "provenance": None,
    }
    return df


def read_catalog(path: PathArg) -> pd.DataFrame:
    """Read the object catalog from CSV or Parquet (sniffed from the bytes), with validation.

    Checks, beyond the column spec (``schemas/catalog.columns.json``): at least one object;
    ``object_id`` unique; ``weight_n`` and the sizes finite and > 0; ``friction_mu`` finite and
    >= 0 (a lift additionally needs it > 0, checked there).

    Args:
        path: ``objects.csv`` / ``objects.parquet``, or ``-`` for stdin.

    Returns:
        The validated catalog, one row per object (``df.attrs`` as for :func:`read_table`).

    Raises:
        MissingInputError: ``path`` does not exist (exit 66).
        InputDataError, SchemaError: the file is not a valid catalog (exit 65).
    """
    return read_catalog_bytes(read_input_bytes(path), path)


def write_catalog(
    df: pd.DataFrame,
    path: PathArg,
    *,
    provenance: Provenance | None = None,
    force: bool = False,
) -> pd.DataFrame:
    """Write a catalog: CSV when ``path`` ends in ``.csv`` (no provenance), Parquet otherwise.

    Raises:
        SchemaError: ``df`` is not a valid catalog (nothing is written).
        OutputExistsError: ``path`` exists and ``force`` is false.
    """
    if str(path).lower().endswith(".csv"):
        norm = validate_frame(df, "catalog", path=path)
        if len(norm) == 0:
            raise InputDataError("empty catalog: no objects", path=path)
        with atomic_output(path, force=force) as tmp:
            norm.to_csv(tmp, index=False)
        return norm
    if len(df) == 0:
        raise InputDataError("empty catalog: no objects", path=path)
    return write_table(df, path, "catalog", provenance=provenance, force=force)


def append_catalog_row(
    path: PathArg, row: dict[str, object], existing: pd.DataFrame, *, provenance: Provenance | None
) -> int:
    """Rewrite the catalog at ``path`` with ``row`` added, atomically, in the file's own format.

    Args:
        path: the catalog file (CSV or Parquet, sniffed from its bytes).
        row: the new row (catalog columns; others are kept as extra columns).
        existing: the catalog as read (:func:`read_catalog`), extra columns kept.
        provenance: stored when the catalog is Parquet.

    Returns:
        The number of rows written.

    Raises:
        SchemaError: the new catalog is not valid (e.g. a repeated ``object_id``); nothing is
            written.
    """
    table = pd.concat([existing, pd.DataFrame([dict(row)])], ignore_index=True)
    table.attrs = {}
    forget_inputs(path)  # updated in place on purpose
    with open(path, "rb") as fh:
        parquet = fh.read(4) == PARQUET_MAGIC
    if parquet:
        return len(write_table(table, path, "catalog", provenance=provenance, force=True))
    norm = validate_frame(table, "catalog", path=path)
    with atomic_output(path, force=True) as tmp:
        norm.to_csv(tmp, index=False)
    return len(norm)
