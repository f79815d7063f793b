"""Artifacts: every file deformctl reads or writes, validated against ``schemas/``.

* Parquet tables (catalog, coefficients, lift results, index table, predictions):
  :func:`read_table`, :func:`write_table`, :func:`read_catalog` (CSV or Parquet).
* MCAP logs (JSON messages with JSON Schemas, one sample per message):
  :func:`write_squeeze_log` / :func:`read_squeeze_log`, :func:`write_lift_log` /
  :func:`read_lift_log`.
* :class:`Provenance` stored in every file; :func:`atomic_output`, :func:`check_output_path`,
  :func:`check_input_path` for safe paths (``-`` is stdin/stdout).
* :func:`detect_kind` and :func:`describe` (behind ``deformctl inspect``).
"""

from __future__ import annotations

from deformctl.artifacts.describe import describe, detect_kind
from deformctl.artifacts.io import (
    atomic_output,
    check_input_path,
    check_output_path,
    read_input_bytes,
)
from deformctl.artifacts.mcap import (
    read_lift_log,
    read_squeeze_log,
    write_lift_log,
    write_squeeze_log,
)
from deformctl.artifacts.provenance import Provenance, sha256_file
from deformctl.artifacts.schema import (
    TABLE_KINDS,
    json_validator,
    load_json_schema,
    load_table_spec,
    validate_frame,
    validate_message,
)
from deformctl.artifacts.tables import read_catalog, read_table, write_catalog, write_table
from deformctl.series import LiftAttempt

__all__ = [
    "TABLE_KINDS",
    "LiftAttempt",
    "Provenance",
    "atomic_output",
    "check_input_path",
    "check_output_path",
    "describe",
    "detect_kind",
    "json_validator",
    "load_json_schema",
    "load_table_spec",
    "read_catalog",
    "read_input_bytes",
    "read_lift_log",
    "read_squeeze_log",
    "read_table",
    "sha256_file",
    "validate_frame",
    "validate_message",
    "write_catalog",
    "write_lift_log",
    "write_squeeze_log",
    "write_table",
]
