"""``predict --json``: the predictions as one JSON document with the same columns in every mode.

The predictions table leaves out the optional columns that say nothing for a run (no bound
without ``--coverage``, no ``object_id`` for one object given by flags); a script reading JSON
should not have to guess. Here every column of the predictions contract
(``schemas/predictions.columns.json``) is in every record, in the contract's order, null where
the run has no value; the document's shape is ``schemas/predict.schema.json``. Reads the
contract with :mod:`json` alone (one object given by flags imports neither pandas nor pyarrow).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from functools import cache
from importlib.resources import files
from typing import Any

import numpy as np

#: ``schema`` of the document (and ``x-deformctl.name`` of its JSON Schema).
DOCUMENT_SCHEMA = "predict"
#: Its version: bump on an incompatible change (``schemas/predict.schema.json``).
DOCUMENT_VERSION = 1


#: Flags the table carries only when some row raises them: false here when it is absent.
ABSENT_FALSE: tuple[str, ...] = ("prediction_implausible", "damping_assumed")


@cache
def prediction_columns() -> tuple[tuple[str, str | None], ...]:
    """Every column of the predictions contract, in order, with its unit (None: no unit)."""
    text = files("deformctl.schemas").joinpath("predictions.columns.json").read_text("utf-8")
    return tuple((c["name"], c.get("unit")) for c in json.loads(text)["columns"])


def _value(value: Any) -> Any:
    """A cell as JSON: numpy scalars as Python, NaN and missing as None."""
    if isinstance(value, np.generic):
        value = value.item()
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return None
    return value


def json_document(columns: Mapping[str, Any]) -> dict[str, Any]:
    """The ``predict --json`` document of ``columns`` (:func:`deformctl.predict.output_columns`):
    ``schema``, ``version``, ``units`` (column → unit, null for none) and ``records`` (one object
    per prediction with every contract column, null where the run has no value, false for the
    flags of :data:`ABSENT_FALSE` no row raised; a column outside the contract follows them)."""
    names = [name for name, _ in prediction_columns()]
    extra = [c for c in columns if c not in names]
    n = len(columns["predicted_lift_force_n"])
    cells = {
        c: list(columns[c]) if c in columns else [False if c in ABSENT_FALSE else None] * n
        for c in [*names, *extra]
    }
    units = dict(prediction_columns())
    return {
        "schema": DOCUMENT_SCHEMA,
        "version": DOCUMENT_VERSION,
        "units": {c: units.get(c) for c in cells},
        "records": [{c: _value(cells[c][i]) for c in cells} for i in range(n)],
    }


def json_text(columns: Mapping[str, Any]) -> str:
    """:func:`json_document` as indented JSON text with a final newline (no NaN)."""
    return json.dumps(json_document(columns), indent=2, allow_nan=False) + "\n"


__all__ = [
    "ABSENT_FALSE",
    "DOCUMENT_SCHEMA",
    "DOCUMENT_VERSION",
    "json_document",
    "json_text",
    "prediction_columns",
]
