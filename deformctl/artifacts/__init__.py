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

import sys
import types
from typing import TYPE_CHECKING, Any

from deformctl.lazy import lazy_exports

if TYPE_CHECKING:  # the names below, for type checkers; at run time they load on first use
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

#: Public name -> the submodule that defines it. Importing this package imports none of them,
#: so a command that needs one module (``predict``: the atomic writes of ``io``) does not pay
#: for pandas, pyarrow and the MCAP readers the others bring.
_EXPORTS: dict[str, str] = {
    "describe": "deformctl.artifacts.describe",
    "detect_kind": "deformctl.artifacts.describe",
    "atomic_output": "deformctl.artifacts.io",
    "check_input_path": "deformctl.artifacts.io",
    "check_output_path": "deformctl.artifacts.io",
    "read_input_bytes": "deformctl.artifacts.io",
    "read_lift_log": "deformctl.artifacts.mcap",
    "read_squeeze_log": "deformctl.artifacts.mcap",
    "write_lift_log": "deformctl.artifacts.mcap",
    "write_squeeze_log": "deformctl.artifacts.mcap",
    "Provenance": "deformctl.artifacts.provenance",
    "sha256_file": "deformctl.artifacts.provenance",
    "TABLE_KINDS": "deformctl.artifacts.schema",
    "json_validator": "deformctl.artifacts.schema",
    "load_json_schema": "deformctl.artifacts.schema",
    "load_table_spec": "deformctl.artifacts.schema",
    "validate_frame": "deformctl.artifacts.schema",
    "validate_message": "deformctl.artifacts.schema",
    "read_catalog": "deformctl.artifacts.tables",
    "read_table": "deformctl.artifacts.tables",
    "write_catalog": "deformctl.artifacts.tables",
    "write_table": "deformctl.artifacts.tables",
    "LiftAttempt": "deformctl.series",
}


__getattr__, __dir__ = lazy_exports(globals(), _EXPORTS)


class _Package(types.ModuleType):
    """This package's module type. ``describe`` is both a public function and the submodule that
    defines it; importing the submodule (``from deformctl.artifacts.describe import ...``) would
    make the package attribute the module, so ``from deformctl.artifacts import describe``
    depended on import order. The function keeps the name, as it did when this package imported
    everything eagerly."""

    def __setattr__(self, name: str, value: Any) -> None:
        if name in _EXPORTS and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


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
