"""``deformctl predict``: the minimum lifting force of new objects from a trained model."""

from __future__ import annotations

import pandas as pd
import typer

from deformctl.artifacts import (
    Provenance,
    check_output_path,
    detect_kind,
    read_catalog,
    read_table,
    write_table,
)
from deformctl.artifacts.io import is_stdio
from deformctl.cli._common import translate_errors
from deformctl.cli._options import Force
from deformctl.errors import SchemaError, UsageError, error_context
from deformctl.quantities import DAMPING_NS_PER_CM, STIFFNESS_N_PER_CM, WEIGHT_N

#: Table kinds ``predict`` reads features from.
INPUT_KINDS = ("coefficients", "index_table", "predictions")

#: Each flag's quantity (its rule, :mod:`deformctl.quantities`).
QUANTITIES = {
    "weight_n": WEIGHT_N,
    "deformability_n_per_cm": STIFFNESS_N_PER_CM,
    "damping_ns_per_cm": DAMPING_NS_PER_CM,
}
FLAGS = {
    "weight_n": "--weight-n",
    "deformability_n_per_cm": "--deformability-n-per-cm",
    "damping_ns_per_cm": "--damping-ns-per-cm",
}


def _read_features(path: str, catalog: str | None) -> pd.DataFrame:
    """Features from a coefficients / index / predictions table, weights joined from a catalog."""
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


@translate_errors
def predict(
    model_path: str = typer.Argument(..., metavar="MODEL", help="A model file from `train`."),
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
    catalog: str | None = typer.Option(
        None,
        "--catalog",
        help="Object catalog (CSV/Parquet) whose weight_n is joined by object_id, for a "
        "coefficients table without weights.",
    ),
    output: str | None = typer.Option(
        None, "-o", "--output", help="Write a predictions table (Parquet; - for stdout)."
    ),
    force: Force = False,
) -> None:
    """Predict the minimum lifting force L_f (N) from weight, deformability and damping.

    The objects come either from a table (COEFFICIENTS: a coefficients table plus --catalog for
    the weights, or any table that has weight_n, deformability_n_per_cm and damping_ns_per_cm,
    such as an index table) or from the three flags for one object. Without -o the predictions
    are printed as CSV on stdout. An input outside the model's training range is predicted
    anyway, with a warning on stderr and outside_training_range = true.

    Example:

    \b
      deformctl predict model.skops coefficients.parquet --catalog objects.csv -o pred.parquet
      deformctl predict model.skops --weight-n 40 --deformability-n-per-cm 40 \\
          --damping-ns-per-cm 5
    """
    flags = {
        "weight_n": weight_n,
        "deformability_n_per_cm": deformability_n_per_cm,
        "damping_ns_per_cm": damping_ns_per_cm,
    }
    given = [FLAGS[k] for k, v in flags.items() if v is not None]
    if features is not None and given:
        raise UsageError(f"give either a COEFFICIENTS table or the flags, not both ({given[0]})")
    if features is None and not given:
        raise UsageError(
            "nothing to predict: give a COEFFICIENTS table or --weight-n, "
            "--deformability-n-per-cm and --damping-ns-per-cm"
        )
    if given and len(given) < len(FLAGS):
        missing = [FLAGS[k] for k, v in flags.items() if v is None]
        raise UsageError(f"one object needs all three flags; missing {', '.join(missing)}")
    if catalog is not None and features is None:
        raise UsageError("--catalog joins weights to a COEFFICIENTS table; give the table")
    for key, value in flags.items():
        QUANTITIES[key].check_optional(value)
    if output is not None:
        check_output_path(output, force)  # fail before any work

    from deformctl.artifacts.model import load_model  # deferred: skops, scikit-learn
    from deformctl.train import FEATURES
    from deformctl.train import predict as predict_lift_force

    model, metadata = load_model(model_path)
    if features is None:
        frame = pd.DataFrame({k: [float(v)] for k, v in flags.items() if v is not None})
        inputs = [model_path]
    else:
        frame = _read_features(features, catalog)
        inputs = [model_path, features, *([catalog] if catalog else [])]
    with error_context(features if features is not None else "command line"):
        result = predict_lift_force(
            model, frame[[c for c in ("object_id", *FEATURES) if c in frame]]
        )
    for line in result.warnings:
        typer.echo(f"warning: {line}", err=True)

    if output is None:
        typer.echo(result.frame.to_csv(index=False, float_format="%.6g"), nl=False)
        return
    provenance = Provenance.from_invocation(
        inputs,
        seed=metadata.get("seed") if isinstance(metadata.get("seed"), int) else None,
        settings={"model_format": str(metadata.get("format"))},
    )
    write_table(result.frame, output, "predictions", provenance=provenance, force=force)
    if not is_stdio(output):
        typer.echo(f"wrote {output}: {len(result.frame)} prediction(s)", err=True)
