"""``deformctl predict``: the minimum lifting force of new objects, its bound and the force window.

A thin layer over :mod:`deformctl.predict`. One object given by flags and printed to stdout
imports neither pandas nor scikit-learn (a table, an older model file and a Parquet output do).
"""

from __future__ import annotations

from typing import Any

import typer

from deformctl.cli._common import translate_errors
from deformctl.cli._options import Force
from deformctl.errors import UsageError
from deformctl.quantities import (
    COVERAGE,
    DAMPING_NS_PER_CM,
    FRICTION_MU,
    STIFFNESS_N_PER_CM,
    WEIGHT_N,
    Quantity,
)

#: Each flag's quantity (its one rule, :mod:`deformctl.quantities`).
QUANTITIES: dict[str, Quantity] = {
    "weight_n": WEIGHT_N,
    "deformability_n_per_cm": STIFFNESS_N_PER_CM,
    "damping_ns_per_cm": DAMPING_NS_PER_CM,
    "friction_mu": FRICTION_MU,
}


def _check_flags(flags: dict[str, float | None], coverage: float | None) -> None:
    """Exit 2 naming the flag for a value outside its quantity's rule
    (:mod:`deformctl.quantities`, the rule every command uses) and for a coverage outside
    (0, 1)."""
    for key, value in flags.items():
        QUANTITIES[key].check_optional(value)
    COVERAGE.check_optional(coverage)


def _check_usage(flags: dict[str, float | None], features: str | None, catalog: str | None) -> None:
    given = [QUANTITIES[k].flag for k, v in flags.items() if v is not None]
    if features is not None and given:
        raise UsageError(f"give either a COEFFICIENTS table or the flags, not both ({given[0]})")
    if features is None and not given:
        raise UsageError(
            "nothing to predict: give a COEFFICIENTS table or --weight-n, "
            "--deformability-n-per-cm and --damping-ns-per-cm"
        )
    missing = [QUANTITIES[k].flag for k in list(QUANTITIES)[:3] if flags[k] is None]
    if given and missing:
        raise UsageError(f"one object needs all three flags; missing {', '.join(missing)}")
    if catalog is not None and features is None:
        raise UsageError("--catalog joins weights to a COEFFICIENTS table; give the table")


@translate_errors
def predict(
    model_path: str = typer.Argument(
        ..., metavar="MODEL", help="A model file from `train`, or `grip`: the bundled model."
    ),
    features: str | None = typer.Argument(
        None,
        metavar="[COEFFICIENTS]",
        help="A coefficients, index or predictions table (Parquet), or a dataset directory "
        "(characterize LOGS/ -o DIR/), with the objects to predict; - for stdin "
        "(characterize - -o - | predict grip -).",
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
        help=f"μ of one object ({FRICTION_MU.rule}); a μ-aware model needs it.",
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
        "object_id; it wins over the table's values (a warning names each one that differs).",
    ),
    strict: bool = typer.Option(
        False,
        "--strict",
        help="Exit 1 (after writing the predictions) when any object is not safe to act on: "
        "window_ok not true, bound_guaranteed not true (needs --coverage), quality not ok, or "
        "not characterized (a dataset directory's _failures); one line names them.",
    ),
    output: str | None = typer.Option(
        None, "-o", "--output", help="Write a predictions table (Parquet; - for stdout)."
    ),
    as_json: bool = typer.Option(
        False,
        "--json",
        help="Print the predictions as one JSON document: every column in every mode, null "
        "where a run has no value (schemas/predict.schema.json); not with -o.",
    ),
    force: Force = False,
) -> None:
    """Predict the minimum lifting force L_f (N) from weight, deformability, damping (and μ).

    The objects come either from a table (COEFFICIENTS: a coefficients table, which carries the
    weight and μ the squeeze log recorded, or any table that has weight_n,
    deformability_n_per_cm, damping_ns_per_cm and friction_mu, such as an index table; - reads
    it from stdin) or from the flags for one object. --catalog joins the weights and μ by
    object_id instead (for a table without them); where the table has another value, the
    catalog's is used and a warning names the object.

    MODEL `grip` is the bundled model for robots (its training range: `deformctl inspect
    grip`); it needs μ. Without -o the predictions are printed as CSV on stdout; --json prints
    them as one JSON document instead, with the same columns whether the objects come from
    flags or a table (null where a run has no value).

    --coverage P adds lift_force_upper_n, a split-conformal upper bound (from the model's
    calibration rows): at least P of the true L_f lie below it for objects drawn like the
    training ones; bound_guaranteed is false outside the training ranges. A rupture or yield
    force column in the table (rupture_force_n from characterize) adds max_safe_force_n (the
    smallest of them less a 15 % margin) and window_ok: true only when the safe force is known
    and L_f and its bound lie below it, false when either exceeds it, empty (null) when the
    object has no safe force. characterize's quality flags are carried into a quality column.
    Every flag set (outside_training_range, window_ok false or null, quality not ok, another μ
    than a single-μ model's) prints a warning naming the object; --strict makes any of them,
    or a row without a guaranteed bound, exit 1.
    An object whose λ is unknown (NaN: characterize could not identify it, as from a test at one
    speed) is predicted at the λ of the model's range with the largest L_f, flagged
    damping_assumed, with a warning.

    Example:

    \b
      deformctl predict grip --weight-n 2.9 --deformability-n-per-cm 30 \\
          --damping-ns-per-cm 0.47 --friction-mu 0.5 --coverage 0.9
      deformctl predict model.skops coefficients.parquet --catalog objects.csv -o pred.parquet
      deformctl measure csv f.csv --weight-n 2.9 --friction-mu 0.6 -o - \\
          | deformctl characterize - -o - | deformctl predict grip - --coverage 0.9
    """
    from deformctl.predict import (
        assume_damping,
        csv_text,
        frame_inputs,
        load_predictor,
        output_columns,
        predict_objects_with_laws,
        quality_warnings,
        read_prediction_inputs,
    )

    flags = {
        "weight_n": weight_n,
        "deformability_n_per_cm": deformability_n_per_cm,
        "damping_ns_per_cm": damping_ns_per_cm,
        "friction_mu": friction_mu,
    }
    _check_usage(flags, features, catalog)
    if as_json and output is not None:
        raise UsageError("give --json or -o, not both (--json prints to stdout)")
    _check_flags(flags, coverage)
    if output is not None:
        from deformctl.artifacts import check_output_path

        check_output_path(output, force)  # fail before any work
    predictor = load_predictor(model_path)
    inputs: dict[str, Any] = {k: None if v is None else [v] for k, v in flags.items()}
    ids: list[str] | None = None
    failed: list[str] = []
    if features is not None:
        joined: list[str] = []
        frame = read_prediction_inputs(features, catalog, joined)
        for line in joined:
            typer.echo(f"warning: {features if features != '-' else 'stdin'}: {line}", err=True)
        inputs, ids, failed = frame_inputs(frame)
    inputs, assumed, lines = assume_damping(predictor, inputs, ids)
    for line in lines:
        typer.echo(f"warning: {line}", err=True)
    laws = predict_objects_with_laws(
        predictor, inputs, coverage=coverage, names=ids, source=features or "command line"
    )
    est = laws.estimates
    for line in [*est.warnings, *quality_warnings(est.names.tolist(), inputs.get("quality"))]:
        typer.echo(f"warning: {line}", err=True)
    columns = output_columns(est, inputs, object_ids=ids, damping_assumed=assumed, laws=laws)
    if as_json:
        from deformctl.predict_json import json_text

        typer.echo(json_text(columns), nl=False)
    elif output is None:
        typer.echo(csv_text(columns), nl=False)
    else:
        _write(columns, output, predictor, [model_path, features, catalog], coverage, force)
    if strict:
        _strict(columns, failed)


def _strict(columns: dict[str, Any], failed: list[str]) -> None:
    """``--strict``: exit 1 with one line naming every object not safe to act on."""
    from deformctl.predict import strict_problems

    problems = strict_problems(columns, failed)
    if problems:
        more = f"; … {len(problems) - 5} more" if len(problems) > 5 else ""
        typer.echo(
            f"error: predict --strict: {len(problems)} object(s) not safe to act on: "
            f"{'; '.join(problems[:5])}{more}",
            err=True,
        )
        raise typer.Exit(1)


def _write(
    columns: dict[str, Any],
    output: str,
    predictor: Any,
    args: list[str | None],
    coverage: float | None,
    force: bool,
) -> None:
    import pandas as pd

    from deformctl.artifacts import Provenance, write_table
    from deformctl.artifacts.io import is_stdio

    seed = predictor.metadata.get("seed")
    provenance = Provenance.from_invocation(
        [str(predictor.path), *(a for a in args[1:] if a)],
        seed=seed if isinstance(seed, int) else None,
        settings={
            "model_format": str(predictor.metadata.get("format")),
            "model": args[0],
            "coverage": coverage,
        },
    )
    write_table(pd.DataFrame(columns), output, "predictions", provenance=provenance, force=force)
    if not is_stdio(output):
        n = len(columns["predicted_lift_force_n"])
        typer.echo(f"wrote {output}: {n} prediction(s)", err=True)
