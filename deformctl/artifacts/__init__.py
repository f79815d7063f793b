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

from deformctl.lazy import lazy_face

# ruff: noqa: F401 - the imports below are the public names (deformctl.lazy.lazy_face)
if TYPE_CHECKING:  # for type checkers; at run time each loads on first use
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


#: Importing this package imports none of the modules above, so a command that needs one
#: (``predict``: the atomic writes of ``io``) does not pay for the others' pandas, pyarrow and MCAP.
__getattr__, __dir__ = lazy_face(globals())


class _Package(types.ModuleType):
    """This package's module type. ``describe`` is both a public function and the submodule that
    defines it; importing the submodule (``from deformctl.artifacts.describe import ...``) would
    make the package attribute the module, so ``from deformctl.artifacts import describe``
    depended on import order. The function keeps the name, as it did when this package imported
    everything eagerly."""

    def __setattr__(self, name: str, value: Any) -> None:
        if name in self.__all__ and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
