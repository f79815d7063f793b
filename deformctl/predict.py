"""The ``predict`` stage: a model's predictions for objects from a table or from one set of values.

Every model is evaluated by :class:`deformctl.grip.fast.Predictor` (numpy only):
:func:`load_predictor` opens a model file (or a bundled name such as ``grip``) through its numpy
export, or an older file without one through skops' allow-list. :func:`read_prediction_inputs`
reads the objects from a coefficients, index or predictions table (weights and μ joined from a
catalog; the safe force from a rupture or yield force), :func:`predict_objects` predicts them
(with the bound at a coverage, the flags and the warnings) and :func:`output_columns` /
:func:`csv_text` lay out the predictions table.

Importing this module imports numpy and the predictor only: pandas, pyarrow and scikit-learn are
imported by the functions that need them (a table, an older model file), so one object given by
values costs a fraction of a second from the command line.
"""

from __future__ import annotations

import contextlib
import csv
import io
import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from deformctl.errors import InputDataError, SchemaError, UsageError, error_context
from deformctl.grip.fast import Estimates, NoNumpyExportError, Predictor, resolve_model_path

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

__all__ = [
    "INPUT_KINDS",
    "OBJECT_COLUMNS",
    "SAFE_FORCE_COLUMNS",
    "csv_text",
    "load_predictor",
    "output_columns",
    "predict_objects",
    "prediction_inputs",
    "read_prediction_inputs",
]

#: Table kinds predictions are made from.
INPUT_KINDS = ("coefficients", "index_table", "predictions")
#: What one object needs (μ too for a μ-aware model).
OBJECT_COLUMNS = ("weight_n", "deformability_n_per_cm", "damping_ns_per_cm")
_FEATURES = OBJECT_COLUMNS


def load_predictor(model: str) -> Predictor:
    """The numpy predictor of ``model`` (a bundled name or a file); a model file without a
    numpy export (model format 1) is loaded through skops' allow-list and exported.

    Raises:
        MissingInputError: no such file (66).
        InputDataError: not a usable model file (65).
    """
    try:
        return Predictor.load(model)
    except NoNumpyExportError:
        from deformctl.artifacts.model import load_predictor as load_through_skops

        predictor: Predictor = load_through_skops(resolve_model_path(model))
        return predictor


def read_prediction_inputs(path: str, catalog: str | None) -> pd.DataFrame:
    """:func:`prediction_inputs` of a coefficients / index / predictions table file.

    Raises:
        SchemaError: another kind of file, or a column missing (naming ``path``; 65).
        InputDataError: see :func:`prediction_inputs`.
    """
    from deformctl.artifacts import detect_kind, read_catalog, read_table
    from deformctl.artifacts.io import is_stdio

    kind = None if is_stdio(path) else detect_kind(path)
    if kind is not None and kind not in INPUT_KINDS:
        raise SchemaError(
            f"is a {kind} file; predict reads {', '.join(INPUT_KINDS)} tables", path=path
        )
    table = read_table(path, kind)
    if table.attrs.get("kind") not in INPUT_KINDS:
        raise SchemaError(
            f"is a {table.attrs.get('kind')} table; predict reads {', '.join(INPUT_KINDS)} tables",
            path=path,
        )
    cat = None if catalog is None else read_catalog(catalog)
    try:
        return prediction_inputs(table, cat)
    except SchemaError as err:
        raise SchemaError(err.message, path=path) from None


def predict_objects(
    predictor: Predictor,
    inputs: Mapping[str, Any],
    *,
    coverage: float | None = None,
    names: Sequence[str] | None = None,
    source: str | None = None,
) -> Estimates:
    """Predict the objects of ``inputs`` (``weight_n``, ``deformability_n_per_cm``,
    ``damping_ns_per_cm`` arrays; ``friction_mu`` and ``max_safe_force_n`` arrays or None).

    Raises:
        UsageError: a μ-aware model without μ (naming ``--friction-mu`` and the column; exit 2).
        InputDataError: a model without (enough) calibration scores for ``coverage``, naming the
            model file; a bad input value (see :meth:`Predictor.predict_many`), naming
            ``source`` (the table's file; exit 65).
    """
    if predictor.needs_friction and inputs.get("friction_mu") is None:
        raise UsageError(
            "the model needs each object's friction: give --friction-mu MU for one object, or "
            "a friction_mu column (in the table or a --catalog)"
        )
    if coverage is not None:
        predictor.margin(coverage)  # the model file's problem: exit 65 naming it
    with error_context(source) if source else contextlib.nullcontext():  # names the source
        return predictor.predict_many(
            inputs["weight_n"],
            inputs["deformability_n_per_cm"],
            inputs["damping_ns_per_cm"],
            inputs.get("friction_mu"),
            coverage=coverage,
            max_safe_force_n=inputs.get("max_safe_force_n"),
            names=names,
        )


def output_columns(
    est: Estimates, inputs: Mapping[str, Any], *, object_ids: Sequence[str] | None = None
) -> dict[str, Any]:
    """The predictions table's columns, in order (optional ones only when they say something):
    the inputs, ``friction_mu`` and ``f_w_n`` (when μ is an input), ``predicted_lift_force_n``,
    the bound's ``lift_force_upper_n``, ``coverage`` and ``bound_guaranteed`` (with a coverage),
    ``max_safe_force_n`` and ``window_ok`` (with a safe force), ``outside_training_range``."""
    cols: dict[str, Any] = {}
    if object_ids is not None:
        cols["object_id"] = list(object_ids)
    for key in OBJECT_COLUMNS:
        cols[key] = inputs[key]
    if inputs.get("friction_mu") is not None:
        cols["friction_mu"] = inputs["friction_mu"]
        cols["f_w_n"] = est.f_w_n
    cols["predicted_lift_force_n"] = est.lift_force_n
    if est.coverage is not None:
        cols["lift_force_upper_n"] = est.lift_force_upper_n
        cols["coverage"] = [est.coverage] * len(est.lift_force_n)
        cols["bound_guaranteed"] = est.bound_guaranteed
    if inputs.get("max_safe_force_n") is not None:
        cols["max_safe_force_n"] = est.max_safe_force_n
        cols["window_ok"] = est.window_ok
    cols["outside_training_range"] = est.outside_training_range
    return cols


def csv_text(columns: Mapping[str, Any]) -> str:
    """The columns as CSV (floats as ``%.6g`` like pandas' ``float_format``, booleans as
    True/False, NaN empty)."""

    def cell(value: Any) -> str:
        if isinstance(value, str):
            return value
        if isinstance(value, bool | np.bool_):
            return str(bool(value))
        number = float(value)
        return "" if math.isnan(number) else "%.6g" % number  # noqa: UP031

    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(list(columns))
    for row in zip(*columns.values(), strict=True):
        writer.writerow([cell(v) for v in row])
    return buffer.getvalue()


#: Coefficients-table columns that bound the grip force (the smallest finite one is the object's
#: safe force, ``max_safe_force_n``): ``characterize``'s rupture force, and a yield force.
SAFE_FORCE_COLUMNS: tuple[str, ...] = ("rupture_force_n", "yield_force_n")


def _join_catalog_column(
    frame: pd.DataFrame, catalog: pd.DataFrame, column: str, ids: pd.Series
) -> np.ndarray:
    """``column`` of the catalog row of each id; must agree (relative 1e-6) with the table's."""
    import pandas as pd

    from deformctl.table import format_ids

    values = dict(
        zip(
            catalog["object_id"].astype(str),
            pd.to_numeric(catalog[column], errors="coerce").to_numpy(dtype=np.float64).tolist(),
            strict=True,
        )
    )
    joined = ids.map(values).to_numpy(dtype=np.float64)
    if column in frame.columns:
        own = pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=np.float64)
        bad = ~np.isclose(own, joined, rtol=1e-6, atol=0.0, equal_nan=True)
        if bad.any():
            raise InputDataError(
                f"{column} differs between the input and the catalog for {format_ids(ids[bad])}"
            )
    return joined


def prediction_inputs(table: pd.DataFrame, catalog: pd.DataFrame | None = None) -> pd.DataFrame:
    """The model's inputs per object from a table, taking ``weight_n`` and ``friction_mu`` from
    ``catalog``.

    The table (an index table, a predictions table or a coefficients table) must have
    ``deformability_n_per_cm`` and ``damping_ns_per_cm``; ``weight_n`` and ``friction_mu`` come
    from the table itself or, when ``catalog`` is given, from the catalog row with the same
    ``object_id``. When both have a value they must agree (relative 1e-6).

    Args:
        table: ``[n]`` rows, with ``object_id`` when a catalog is to be joined.
        catalog: a validated object catalog (:func:`deformctl.artifacts.read_catalog`), or None.

    Returns:
        ``[n]`` rows in the table's order: ``object_id`` (when the table has it),
        :data:`OBJECT_COLUMNS`, ``friction_mu`` (when known) and ``max_safe_force_n`` (the
        smallest of :data:`SAFE_FORCE_COLUMNS` the table has, NaN where none is finite; only
        when the table has one of them).

    Raises:
        SchemaError: a feature column is missing and cannot be joined; ``object_id`` missing
            when a catalog is given.
        InputDataError: an object missing from the catalog, or a weight or friction that
            differs between the table and the catalog (the messages name the ids).
    """
    import pandas as pd

    from deformctl.catalog import catalog_weights
    from deformctl.table import format_ids

    frame = table.copy()
    if catalog is not None:
        if "object_id" not in frame.columns:
            raise SchemaError("the input has no column 'object_id' to join on", field="object_id")
        ids = frame["object_id"].astype(str)
        weights = catalog_weights(catalog)
        missing = sorted(set(ids) - set(weights))
        if missing:
            raise InputDataError(
                f"{len(missing)} object(s) are not in the catalog: {format_ids(missing)}"
            )
        frame["weight_n"] = _join_catalog_column(frame, catalog, "weight_n", ids)
        if "friction_mu" in catalog.columns:
            frame["friction_mu"] = _join_catalog_column(frame, catalog, "friction_mu", ids)
    for col in _FEATURES:
        if col not in frame.columns:
            hint = " (pass --catalog to join weights by object_id)" if col == "weight_n" else ""
            raise SchemaError(f"the input has no column {col!r}{hint}", field=col)
    keep = ["object_id"] if "object_id" in frame.columns else []
    keep += [*_FEATURES, *(["friction_mu"] if "friction_mu" in frame.columns else [])]
    out = frame[keep].reset_index(drop=True)
    safe_cols = [c for c in SAFE_FORCE_COLUMNS if c in frame.columns]
    if safe_cols:
        safe = frame[safe_cols].apply(pd.to_numeric, errors="coerce").to_numpy(dtype=np.float64)
        safe = np.where(np.isfinite(safe) & (safe > 0), safe, np.inf).min(axis=1)
        out["max_safe_force_n"] = np.where(np.isfinite(safe), safe, np.nan)
    return out
