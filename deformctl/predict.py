"""The ``predict`` stage: a model's predictions for objects from a table or from one set of values.

Every model is evaluated by :class:`deformctl.grip.fast.Predictor` (numpy only):
:func:`load_predictor` opens a model file (or a bundled name such as ``grip``) through its numpy
export, or an older file without one through skops' allow-list. :func:`read_prediction_inputs`
reads the objects from a coefficients, index or predictions table or dataset directory (weights
and μ joined from a catalog; the safe force from a rupture or yield force, less the margin of
:func:`deformctl.squeeze.rupture.safe_force_n`; ``characterize``'s quality),
:func:`predict_objects` predicts them (with the bound at a coverage, the flags and the warnings),
:func:`output_columns` / :func:`csv_text` lay out the predictions table, and
:func:`quality_warnings` / :func:`strict_problems` say which rows a robot should not act on.

Importing this module imports numpy and the predictor only: pandas, pyarrow and scikit-learn are
imported by the functions that need them (a table, an older model file), so one object given by
values costs a fraction of a second from the command line.
"""

from __future__ import annotations

import contextlib
import csv
import io
import math
import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from deformctl.errors import InputDataError, SchemaError, UsageError, error_context
from deformctl.grip.fast import Estimates, NoNumpyExportError, Predictor, resolve_model_path

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

    from deformctl.grip.lawpredict import LawPrediction

__all__ = [
    "INPUT_KINDS",
    "OBJECT_COLUMNS",
    "SAFE_FORCE_COLUMNS",
    "assume_damping",
    "csv_text",
    "frame_inputs",
    "load_predictor",
    "output_columns",
    "predict_objects",
    "predict_objects_with_laws",
    "prediction_inputs",
    "quality_warnings",
    "read_prediction_inputs",
    "strict_problems",
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


def read_prediction_inputs(
    path: str, catalog: str | None, warnings: list[str] | None = None
) -> pd.DataFrame:
    """:func:`prediction_inputs` of a coefficients / index / predictions table file (``-``:
    stdin, as from ``characterize - -o -``); lines about values the catalog overrides go to
    ``warnings``.

    Raises:
        SchemaError: another kind of file, or a column missing (naming ``path``; 65).
        InputDataError: see :func:`prediction_inputs`.
    """
    from deformctl.artifacts import detect_kind, read_catalog, read_table
    from deformctl.artifacts.io import display_name, is_stdio

    if not is_stdio(path) and os.path.isdir(path):
        table = _read_dataset_dir(path, warnings)
    else:
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
        frame = prediction_inputs(table, cat, warnings=warnings, catalog_name=str(catalog))
        frame.attrs["failed_objects"] = table.attrs.get("failed_objects", [])
        return frame
    except SchemaError as err:
        raise SchemaError(err.message, path=path) from None
    except InputDataError as err:
        if err.path is not None or catalog is not None:  # (a catalog's message names the ids)
            raise
        raise InputDataError(err.message, path=display_name(path)) from None


def _read_dataset_dir(path: str, warnings: list[str] | None) -> pd.DataFrame:
    """The rows of a dataset directory of one of :data:`INPUT_KINDS` (``characterize -o DIR/``),
    with its failed objects in ``attrs["failed_objects"]`` (``(id, message)``) and one line
    each in ``warnings``.

    Raises:
        SchemaError: a directory of another kind (65).
        InputDataError: not a dataset directory, or an incomplete or damaged one (65).
    """
    from deformctl.artifacts.dataset import describe_dataset, read_failures, read_table_any

    kind = describe_dataset(path).get("kind")
    if kind not in INPUT_KINDS:
        raise SchemaError(
            f"is a {kind} dataset; predict reads {', '.join(INPUT_KINDS)} tables", path=path
        )
    table = read_table_any(path, str(kind))
    failures = read_failures(path)
    id_col = str(failures.columns[0]) if len(failures.columns) else "object_id"
    failed = [
        (str(row[id_col]), str(row.get("error_message", ""))) for row in failures.to_dict("records")
    ]
    table.attrs["failed_objects"] = failed
    if warnings is not None:
        warnings.extend(f"{i}: no prediction: {kind} failed on it ({msg})" for i, msg in failed)
    return table


#: λ values tried over the model's training range for an object whose λ is unknown.
_DAMPING_GRID = 65


def assume_damping(
    predictor: Predictor, inputs: Mapping[str, Any], names: Sequence[str] | None = None
) -> tuple[dict[str, Any], np.ndarray, list[str]]:
    """Give every object whose λ is unknown (NaN: ``characterize`` cannot identify λ from a
    test at one speed, ``damping_unidentifiable``) the λ of the model's training range at which
    its predicted L_f is largest, so that its force and bound are the most conservative the model
    gives for a λ in that range (in the grip model damping lowers L_f: that is λ = 0).

    Returns:
        The inputs with those λ filled in, ``[n]`` True where λ was assumed, and one warning
        line per such object (no ``warning:`` prefix). Other inputs are returned unchanged.
    """
    lam = np.asarray(inputs["damping_ns_per_cm"], dtype=np.float64).reshape(-1)
    unknown = np.isnan(lam)
    if not unknown.any():
        return dict(inputs), unknown, []
    lo, hi = predictor.ranges.get("damping_ns_per_cm", (0.0, 0.0))
    grid = np.linspace(float(lo), float(hi), _DAMPING_GRID)
    filled = lam.copy()
    lines = []
    for i in np.flatnonzero(unknown):
        row = {
            k: np.full(grid.size, float(np.asarray(inputs[k], dtype=np.float64).reshape(-1)[i]))
            for k in ("weight_n", "deformability_n_per_cm")
        }
        mu = inputs.get("friction_mu")
        mu_row = None if mu is None else np.full(grid.size, float(np.asarray(mu)[i]))
        try:
            est = predictor.predict_many(
                row["weight_n"], row["deformability_n_per_cm"], grid, mu_row
            )
        except InputDataError:  # another input is bad: predict_many names it below
            continue
        filled[i] = float(grid[int(np.argmax(est.lift_force_n))])
        label = names[int(i)] if names is not None else f"row {i}"
        lines.append(
            f"{label}: damping_ns_per_cm unknown (λ was not identifiable); predicted at "
            f"λ = {filled[i]:g} N·s/cm, the largest L_f over the model's λ range "
            f"[{float(lo):g}, {float(hi):g}] (damping_assumed = true)"
        )
    return {**inputs, "damping_ns_per_cm": filled}, unknown, lines


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
        est = predictor.predict_many(
            inputs["weight_n"],
            inputs["deformability_n_per_cm"],
            inputs["damping_ns_per_cm"],
            inputs.get("friction_mu"),
            coverage=coverage,
            max_safe_force_n=inputs.get("max_safe_force_n"),
            names=names,
        )
        _refuse_non_forces(est)
        return est


def predict_objects_with_laws(
    predictor: Predictor,
    inputs: Mapping[str, Any],
    *,
    coverage: float | None = None,
    names: Sequence[str] | None = None,
    source: str | None = None,
) -> LawPrediction:
    """:func:`predict_objects` of rows that state their material law (``inputs["model"]``, a
    coefficients table's column) with the model's law networks
    (:func:`deformctl.grip.lawpredict.predict_laws`); without that column, every row is
    Kelvin–Voigt.

    Raises:
        InputDataError: an unknown law (naming the column and the known laws), a row of
            another law than Kelvin–Voigt and a model file without a law mix (65); as
            :func:`predict_objects`.
    """
    from deformctl.grip.lawpredict import LawPrediction, predict_laws
    from deformctl.grip.laws import LAW_COLUMN, read_laws

    n = len(np.atleast_1d(np.asarray(inputs["weight_n"])))
    labels = list(names) if names is not None else [f"row {i}" for i in range(n)]
    if inputs.get(LAW_COLUMN) is None:
        est = predict_objects(predictor, inputs, coverage=coverage, names=names, source=source)
        kv = np.array(["kv"] * n, dtype=object)
        none = np.zeros(n, dtype=bool)
        return LawPrediction(est, kv, none, none, none)
    with error_context(source) if source else contextlib.nullcontext():
        laws = read_laws(list(inputs[LAW_COLUMN]), labels)
    if predictor.needs_friction and inputs.get("friction_mu") is None:
        predict_objects(predictor, inputs, coverage=coverage, names=names)  # its usage error
    if coverage is not None:
        predictor.margin(coverage)
    with error_context(source) if source else contextlib.nullcontext():
        out = predict_laws(predictor, inputs, laws, coverage=coverage, names=labels)
        _refuse_non_forces(out.estimates)
    return out


def _refuse_non_forces(est: Estimates) -> None:
    """A predicted lifting force that is not a positive finite force is never printed (a robot
    would act on it): the objects are named, exit 65."""
    not_force = ~(np.isfinite(est.lift_force_n) & (est.lift_force_n > 0))
    if not_force.any():
        first = int(np.flatnonzero(not_force)[0])
        raise InputDataError(
            f"the model predicts {float(est.lift_force_n[first])!r} N for "
            f"{', '.join(map(str, est.names[not_force][:5]))}: not a force (refused)"
        )


def output_columns(
    est: Estimates,
    inputs: Mapping[str, Any],
    *,
    object_ids: Sequence[str] | None = None,
    damping_assumed: Any = None,
    laws: LawPrediction | None = None,
) -> dict[str, Any]:
    """The predictions table's columns, in order (optional ones only when they say something):
    the inputs, ``friction_mu`` and ``f_w_n`` (when μ is an input), ``predicted_lift_force_n``,
    the bound's ``lift_force_upper_n``, ``coverage`` and ``bound_guaranteed`` (with a coverage),
    ``max_safe_force_n`` and ``window_ok`` (when the input has safe forces: null where the
    object's is unknown), ``outside_training_range``, ``prediction_implausible`` when a
    prediction is not a lifting force (:mod:`deformctl.grip.sanity`), ``damping_assumed`` (when
    some λ was unknown, :func:`assume_damping`, or a law parameter,
    :mod:`deformctl.grip.lawpredict`), ``quality`` (``characterize``'s flags, when the input
    carries them), ``material_law`` (the law whose network predicted the row) when the rows
    state their law, and ``law_assumed`` when some row's law was unknown."""
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
    if est.prediction_implausible is not None and est.prediction_implausible.any():
        cols["prediction_implausible"] = est.prediction_implausible
    if laws is not None:
        assumed = laws.parameters_assumed
        damping_assumed = assumed if damping_assumed is None else assumed | damping_assumed
    if damping_assumed is not None and np.any(damping_assumed):
        cols["damping_assumed"] = np.asarray(damping_assumed, dtype=bool)
    if laws is not None and inputs.get("model") is not None:
        cols["material_law"] = [str(v) for v in laws.law_used]
        if np.any(laws.law_assumed):
            cols["law_assumed"] = np.asarray(laws.law_assumed, dtype=bool)
        if np.any(laws.shape_assumed):
            cols["shape_assumed"] = np.asarray(laws.shape_assumed, dtype=bool)
    if inputs.get("quality") is not None:
        cols["quality"] = list(inputs["quality"])
    return cols


def frame_inputs(
    frame: pd.DataFrame,
) -> tuple[dict[str, Any], list[str] | None, list[str]]:
    """The model's inputs from :func:`read_prediction_inputs`' frame: the columns as arrays
    (``quality`` and the law, ``model``, as objects, the others as floats), the object ids
    (None without them) and the ids of the objects the input's dataset failed on."""
    inputs = {
        c: frame[c].to_numpy(dtype=object if c in ("quality", "model") else float)
        for c in frame.columns
        if c != "object_id"
    }
    ids = frame["object_id"].astype(str).tolist() if "object_id" in frame.columns else None
    return inputs, ids, [str(i) for i, _ in frame.attrs.get("failed_objects", [])]


def quality_warnings(names: Sequence[str], quality: Sequence[str | None] | None) -> list[str]:
    """One line per object that ``characterize`` flagged (its ``quality`` is not ``ok``), naming
    the flags (no ``warning:`` prefix)."""
    if quality is None:
        return []
    return [
        f"{name}: characterize flagged it: {q or 'no quality recorded'} (quality); its "
        "prediction is only as good as its coefficients"
        for name, q in zip(names, quality, strict=True)
        if q != "ok"
    ]


def strict_problems(columns: Mapping[str, Any], failed: Sequence[str] = ()) -> list[str]:
    """What ``predict --strict`` refuses: ``object (causes)`` for every row that is not
    window-ok (``window_ok`` true: a safe force known and L_f and its bound below it), not
    guaranteed (``bound_guaranteed`` true: a ``--coverage`` bound inside the training range) or
    not quality-ok (``quality`` ok, where the input carries characterize's flags), and for every
    object the input's dataset failed on (``failed``)."""
    n = len(columns["predicted_lift_force_n"])
    names = columns.get("object_id") or [f"row {i}" for i in range(n)]
    window = columns.get("window_ok")
    bound = columns.get("bound_guaranteed")
    quality = columns.get("quality")
    out = [f"{name} (not characterized)" for name in failed]
    for i in range(n):
        causes = []
        if window is None or window[i] is None:
            causes.append("no safe force known")
        elif not window[i]:
            causes.append("window_ok false")
        if bound is None:
            causes.append("no --coverage bound")
        elif not bound[i]:
            causes.append("bound not guaranteed")
        if quality is not None and quality[i] != "ok":
            causes.append(f"quality {quality[i]}")
        if causes:
            out.append(f"{names[i]} ({', '.join(causes)})")
    return out


def csv_text(columns: Mapping[str, Any]) -> str:
    """The columns as CSV (floats as ``%.6g`` like pandas' ``float_format``, booleans as
    True/False, NaN empty)."""

    def cell(value: Any) -> str:
        if value is None:
            return ""
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


def _law_columns() -> tuple[str, ...]:
    """The material law column and every law's parameter columns (a coefficients table's)."""
    from deformctl.grip.laws import LAW_COLUMN, LAW_PARAMETER_COLUMNS

    return (LAW_COLUMN, *(c for cols in LAW_PARAMETER_COLUMNS.values() for c in cols))


#: Coefficients-table columns that bound the grip force (the smallest finite one is the object's
#: safe force, ``max_safe_force_n``): ``characterize``'s rupture force, and a yield force.
SAFE_FORCE_COLUMNS: tuple[str, ...] = ("rupture_force_n", "yield_force_n")


def _join_catalog_column(
    frame: pd.DataFrame,
    catalog: pd.DataFrame,
    column: str,
    ids: pd.Series,
    warnings: list[str] | None,
    catalog_name: str,
) -> np.ndarray:
    """``column`` of the catalog row of each id: the catalog wins over the table's value, and a
    value that differs (relative 1e-6) is one line in ``warnings`` naming the objects."""
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
    if column in frame.columns and warnings is not None:
        own = pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=np.float64)
        bad = np.isfinite(own) & ~np.isclose(own, joined, rtol=1e-6, atol=0.0, equal_nan=True)
        if bad.any():
            shown = [
                f"{i} ({a:g} vs {b:g})"
                for i, a, b in zip(ids[bad], own[bad], joined[bad], strict=True)
            ]
            warnings.append(
                f"{column} differs between the table and {catalog_name} for "
                f"{format_ids(shown)}; using the catalog's"
            )
    return joined


def _check_object_values(frame: pd.DataFrame, catalog: pd.DataFrame | None) -> pd.DataFrame:
    """Refuse a weight the table does not have (an older coefficients table, or a squeeze log
    without ``--weight-n``), naming ``--catalog``. In a coefficients table (whose object values
    are NaN where the log had none) a ``friction_mu`` column without any value is dropped (a
    μ-aware model then asks for μ by name) and one with some values missing is refused.
    """
    from deformctl.table import format_ids

    if catalog is not None:
        return frame
    if "weight_n" not in frame.columns:
        raise SchemaError(
            "the table has no weight_n column (a coefficients table from before weights were "
            "copied, or from a log without --weight-n); pass --catalog OBJECTS to join the "
            "weights by object_id",
            field="weight_n",
        )
    if frame.attrs.get("kind") != "coefficients":  # (a NaN elsewhere is a bad value, not unknown)
        return frame
    for col, flag in (("weight_n", "--weight-n"), ("friction_mu", "--friction-mu")):
        if col not in frame.columns:
            continue
        values = frame[col].astype("float64").to_numpy()
        missing = ~np.isfinite(values)
        if col == "friction_mu" and missing.all():
            return frame.drop(columns=[col])
        if missing.any():
            ids = frame["object_id"][missing] if "object_id" in frame.columns else []
            raise InputDataError(
                f"{col} is missing for {format_ids(ids) or 'some rows'} (measure without "
                f"{flag}); pass --catalog OBJECTS to join it by object_id"
            )
    return frame


def prediction_inputs(
    table: pd.DataFrame,
    catalog: pd.DataFrame | None = None,
    *,
    warnings: list[str] | None = None,
    catalog_name: str = "the catalog",
) -> pd.DataFrame:
    """The model's inputs per object from a table, taking ``weight_n`` and ``friction_mu`` from
    ``catalog``.

    The table (an index table, a predictions table or a coefficients table) must have
    ``deformability_n_per_cm`` and ``damping_ns_per_cm``; ``weight_n`` and ``friction_mu`` come
    from the table itself (a coefficients table carries the squeeze log's) or, when ``catalog``
    is given, from the catalog row with the same ``object_id``: the catalog wins, and a value
    that differs from the table's (relative 1e-6) is a line in ``warnings``.

    Args:
        table: ``[n]`` rows, with ``object_id`` when a catalog is to be joined.
        catalog: a validated object catalog (:func:`deformctl.artifacts.read_catalog`), or None.
        warnings: where the lines about differing values go (no ``warning:`` prefix).
        catalog_name: the catalog's file name, for those lines.

    Returns:
        ``[n]`` rows in the table's order: ``object_id`` (when the table has it),
        :data:`OBJECT_COLUMNS`, ``friction_mu`` (when known), ``max_safe_force_n`` (the
        smallest of :data:`SAFE_FORCE_COLUMNS` the table has less the margin
        :data:`deformctl.squeeze.rupture.SAFE_FORCE_MARGIN`, NaN where none is finite;
        only when the table has one of them) and ``quality`` (``characterize``'s flags, when
        the table has them).

    Raises:
        SchemaError: a feature column is missing and cannot be joined; ``object_id`` missing
            when a catalog is given.
        SchemaError: no ``weight_n`` column and no catalog (naming ``--catalog``).
        InputDataError: a table without rows; an object missing from the catalog; without a
            catalog, a weight (or some but not all μ) missing for some objects (the messages
            name the ids and ``--catalog``).
    """
    import pandas as pd

    from deformctl.catalog import SIZE_COLUMNS, catalog_weights
    from deformctl.table import format_ids

    frame = table.copy()
    if len(frame) == 0:  # before any column is asked for: "needs friction" would mislead
        raise InputDataError("the table has no rows: no object to predict")
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
        for col in ("weight_n", "friction_mu", *SIZE_COLUMNS):  # sizes: the hc network's
            if col in catalog.columns:
                frame[col] = _join_catalog_column(frame, catalog, col, ids, warnings, catalog_name)
    frame = _check_object_values(frame, catalog)
    for col in _FEATURES:
        if col not in frame.columns:
            hint = " (pass --catalog to join weights by object_id)" if col == "weight_n" else ""
            raise SchemaError(f"the input has no column {col!r}{hint}", field=col)
    keep = ["object_id"] if "object_id" in frame.columns else []
    keep += [*_FEATURES, *(["friction_mu"] if "friction_mu" in frame.columns else [])]
    keep += [c for c in _law_columns() if c in frame.columns and "model" in frame.columns]
    out = frame[keep].reset_index(drop=True)
    safe_cols = [c for c in SAFE_FORCE_COLUMNS if c in frame.columns]
    if safe_cols:
        from deformctl.squeeze.rupture import safe_force_n

        safe = frame[safe_cols].apply(pd.to_numeric, errors="coerce").to_numpy(dtype=np.float64)
        safe = np.where(np.isfinite(safe) & (safe > 0), safe, np.inf).min(axis=1)
        out["max_safe_force_n"] = safe_force_n(np.where(np.isfinite(safe), safe, np.nan))
    if "quality" in frame.columns:
        out["quality"] = [None if pd.isna(q) else str(q) for q in frame["quality"]]
    return out
