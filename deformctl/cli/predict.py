"""``deformctl predict``: the minimum lifting force of new objects, its bound and the force window.

Every model is evaluated by :class:`deformctl.grip.fast.Predictor` (numpy only). One object given
by flags and printed to stdout needs neither pandas nor scikit-learn: the imports of a table, of
an older model file (loaded through skops) and of a Parquet output are made only when needed.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np
import typer

from deformctl.cli._common import translate_errors
from deformctl.cli._options import Force
from deformctl.errors import SchemaError, UsageError, error_context

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

    from deformctl.grip.fast import Estimates, Predictor

#: Table kinds ``predict`` reads features from.
INPUT_KINDS = ("coefficients", "index_table", "predictions")

FLAGS = {
    "weight_n": "--weight-n",
    "deformability_n_per_cm": "--deformability-n-per-cm",
    "damping_ns_per_cm": "--damping-ns-per-cm",
    "friction_mu": "--friction-mu",
}
#: The flags one object needs (μ too for a μ-aware model).
OBJECT_FLAGS = ("weight_n", "deformability_n_per_cm", "damping_ns_per_cm")


def _read_features(path: str, catalog: str | None) -> pd.DataFrame:
    """Features (and μ, safe force) from a coefficients / index / predictions table."""
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
        from deformctl.train import prediction_inputs  # deferred: scikit-learn

        return prediction_inputs(table, cat)
    except SchemaError as err:
        raise SchemaError(err.message, path=path) from None


def load_predictor(model: str) -> Predictor:
    """The numpy predictor of MODEL (a bundled name or a file); an older model file without a
    numpy export is loaded through skops' allow-list and exported."""
    from deformctl.grip.fast import NoNumpyExportError, Predictor, resolve_model_path

    try:
        return Predictor.load(model)
    except NoNumpyExportError:
        from deformctl.artifacts.model import load_predictor as load_through_skops

        predictor: Predictor = load_through_skops(resolve_model_path(model))
        return predictor


def output_columns(
    est: Estimates, inputs: Mapping[str, Any], *, object_ids: Any = None
) -> dict[str, Any]:
    """The predictions table's columns, in order (optional ones only when they say something)."""
    cols: dict[str, Any] = {}
    if object_ids is not None:
        cols["object_id"] = list(object_ids)
    for key in OBJECT_FLAGS:
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
    """The columns as CSV (floats as ``%.6g``, booleans as True/False, NaN empty)."""

    def cell(value: Any) -> str:
        if isinstance(value, str):
            return value
        if isinstance(value, bool | np.bool_):
            return str(bool(value))
        number = float(value)
        return "" if math.isnan(number) else "%.6g" % number  # noqa: UP031 - pandas' float_format

    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(list(columns))
    for row in zip(*columns.values(), strict=True):
        writer.writerow([cell(v) for v in row])
    return buffer.getvalue()


def _check_flags(flags: dict[str, float | None], coverage: float | None) -> None:
    """Exit 2 naming the flag for a value no object can have (the rule of
    :func:`deformctl.grip.fast.input_problem`) and for a coverage outside (0, 1)."""
    from deformctl.grip.fast import input_problem, input_rule

    for key, value in flags.items():
        if value is None:
            continue
        if not math.isfinite(value):
            raise UsageError(f"{FLAGS[key]} must be a finite number, got {value}")
        if input_problem(key, float(value), "the command line") is not None:
            raise UsageError(f"{FLAGS[key]} {input_rule(key)}, got {value:g}")
    if coverage is not None and not (math.isfinite(coverage) and 0.0 < coverage < 1.0):
        raise UsageError(f"--coverage must be a number in (0, 1), got {coverage:g}")


@translate_errors
def predict(
    model_path: str = typer.Argument(
        ...,
        metavar="MODEL",
        help="A model file from `train`, or `grip`: the bundled model for robots.",
    ),
    features: str | None = typer.Argument(
        None,
        metavar="[COEFFICIENTS]",
        help="A coefficients, index or predictions table (Parquet) with the objects to predict.",
    ),
    weight_n: float | None = typer.Option(None, "--weight-n", help="W of one object, N."),
    deformability_n_per_cm: float | None = typer.Option(
        None, "--deformability-n-per-cm", help="D of one object, N/cm."
    ),
    damping_ns_per_cm: float | None = typer.Option(
        None, "--damping-ns-per-cm", help="λ of one object, N·s/cm."
    ),
    friction_mu: float | None = typer.Option(
        None,
        "--friction-mu",
        help="μ of one object (0 < μ <= 3); a μ-aware model such as grip needs it.",
    ),
    coverage: float | None = typer.Option(
        None,
        "--coverage",
        metavar="P",
        help="Add lift_force_upper_n: an upper bound that at least P (0 < P < 1) of the true "
        "L_f lie below, for objects drawn like the model's training objects.",
    ),
    catalog: str | None = typer.Option(
        None,
        "--catalog",
        help="Object catalog (CSV/Parquet) whose weight_n and friction_mu are joined by "
        "object_id, for a coefficients table without them.",
    ),
    output: str | None = typer.Option(
        None, "-o", "--output", help="Write a predictions table (Parquet; - for stdout)."
    ),
    force: Force = False,
) -> None:
    """Predict the minimum lifting force L_f (N) from weight, deformability, damping (and μ).

    The objects come either from a table (COEFFICIENTS: a coefficients table plus --catalog for
    the weights and μ, or any table that has weight_n, deformability_n_per_cm,
    damping_ns_per_cm and friction_mu, such as an index table) or from the flags for one
    object. MODEL `grip` is the bundled model for robots (W 0.5-80 N, D 5-60 N/cm, λ 0-15 N·s/cm,
    μ 0.2-1.0); it needs μ. Without -o the predictions are printed as CSV on stdout.

    --coverage P adds lift_force_upper_n, a split-conformal upper bound (the model's calibration
    rows' relative errors): at least P of the true L_f lie below it for objects drawn like the
    training ones; bound_guaranteed is false outside the training ranges. When the table has a
    rupture or yield force (rupture_force_n from characterize), max_safe_force_n and window_ok
    are added: window_ok is false when L_f or its bound exceeds the safe force. Every flag set
    (outside_training_range, window_ok = false, a μ other than a single-μ model's) also prints
    a warning line on stderr naming the object.

    Example:

    \b
      deformctl predict grip --weight-n 2.9 --deformability-n-per-cm 30 \\
          --damping-ns-per-cm 0.47 --friction-mu 0.5 --coverage 0.9
      deformctl predict model.skops coefficients.parquet --catalog objects.csv -o pred.parquet
    """
    flags = {
        "weight_n": weight_n,
        "deformability_n_per_cm": deformability_n_per_cm,
        "damping_ns_per_cm": damping_ns_per_cm,
        "friction_mu": friction_mu,
    }
    given = [FLAGS[k] for k, v in flags.items() if v is not None]
    if features is not None and given:
        raise UsageError(f"give either a COEFFICIENTS table or the flags, not both ({given[0]})")
    if features is None and not given:
        raise UsageError(
            "nothing to predict: give a COEFFICIENTS table or --weight-n, "
            "--deformability-n-per-cm and --damping-ns-per-cm"
        )
    missing = [FLAGS[k] for k in OBJECT_FLAGS if flags[k] is None]
    if given and missing:
        raise UsageError(f"one object needs all three flags; missing {', '.join(missing)}")
    if catalog is not None and features is None:
        raise UsageError("--catalog joins weights to a COEFFICIENTS table; give the table")
    _check_flags(flags, coverage)
    if output is not None:
        from deformctl.artifacts import check_output_path

        check_output_path(output, force)  # fail before any work

    predictor = load_predictor(model_path)
    if features is None:
        if predictor.needs_friction and friction_mu is None:
            raise UsageError(
                "the model needs the object's friction: give --friction-mu MU (a table gives it "
                "in its friction_mu column)"
            )
        inputs: dict[str, Any] = {k: [float(v)] for k, v in flags.items() if v is not None}
        inputs.setdefault("friction_mu", None)
        object_ids = None
        names = None
        where = "command line"
    else:
        frame = _read_features(features, catalog)
        if predictor.needs_friction and "friction_mu" not in frame.columns:
            raise UsageError(
                "the model needs each object's friction: the table has no friction_mu column; "
                "give --catalog with one (--friction-mu is for one object given by flags)"
            )
        inputs = {c: frame[c].to_numpy(dtype=float) for c in OBJECT_FLAGS}
        inputs["friction_mu"] = (
            frame["friction_mu"].to_numpy(dtype=float) if "friction_mu" in frame.columns else None
        )
        if "max_safe_force_n" in frame.columns:
            inputs["max_safe_force_n"] = frame["max_safe_force_n"].to_numpy(dtype=float)
        object_ids = (
            frame["object_id"].astype(str).tolist() if "object_id" in frame.columns else None
        )
        names = object_ids
        where = features
    if coverage is not None:
        predictor.margin(coverage)  # exit 65 naming the model file: no (or too few) scores
    with error_context(where):
        est = predictor.predict_many(
            inputs["weight_n"],
            inputs["deformability_n_per_cm"],
            inputs["damping_ns_per_cm"],
            inputs["friction_mu"],
            coverage=coverage,
            max_safe_force_n=inputs.get("max_safe_force_n"),
            names=names,
        )
    for line in est.warnings:
        typer.echo(f"warning: {line}", err=True)
    columns = output_columns(est, inputs, object_ids=object_ids)

    if output is None:
        typer.echo(csv_text(columns), nl=False)
        return
    import pandas as pd

    from deformctl.artifacts import Provenance, write_table
    from deformctl.artifacts.io import is_stdio

    seed = predictor.metadata.get("seed")
    provenance = Provenance.from_invocation(
        [str(predictor.path), *([features] if features else []), *([catalog] if catalog else [])],
        seed=seed if isinstance(seed, int) else None,
        settings={
            "model_format": str(predictor.metadata.get("format")),
            "model": model_path,
            "coverage": coverage,
        },
    )
    write_table(pd.DataFrame(columns), output, "predictions", provenance=provenance, force=force)
    if not is_stdio(output):
        typer.echo(f"wrote {output}: {len(est.lift_force_n)} prediction(s)", err=True)
