"""``deformctl adapt``: a grip model corrected with the rig's own lifts (:mod:`deformctl.adapt`)."""

from __future__ import annotations

import math

import typer

from deformctl.cli._common import translate_errors
from deformctl.cli._options import Force


@translate_errors
def adapt(
    model: str = typer.Argument(
        ..., metavar="MODEL", help="A grip model file from `train`, or `grip`: the bundled model."
    ),
    rig_index: str = typer.Argument(
        ...,
        metavar="RIG_INDEX",
        help="An index table (`table`) with the rig's lifts: its rows with source = rig (all "
        "rows when it has no source column), at least 3, each converged.",
    ),
    output: str = typer.Option(..., "-o", "--output", help="The adapted model file (.skops)."),
    force: Force = False,
) -> None:
    """Correct a simulation-trained grip model with a handful of lifts from the rig.

    Fits a linear correction of log(L_f / F_w) in the model's scaled inputs (the dimensionless
    groups), shrunk toward no correction by a ridge penalty chosen by leave-one-out, so that it
    stays sane with 3-20 rows. The conformal bound is recalibrated on the rig rows'
    leave-one-out scores: at coverage P it needs n >= P / (1 - P) rows (9 at P = 0.9); with
    fewer it is their largest score, flagged bound_guaranteed = false. The metadata records the
    base model, the rows, the correction and the rules (`inspect adapted.skops`). Use it like any
    model: `predict adapted.skops ...`, `lift rig --start-model adapted.skops ...`.

    Example: deformctl adapt grip rig_index.parquet -o adapted.skops
    """
    from deformctl.adapt import adapt_model, describe_rows, write_adapted
    from deformctl.artifacts import check_output_path, read_table

    check_output_path(output, force)
    index = read_table(rig_index, "index_table")
    result = adapt_model(model, index, index_path=rig_index)
    write_adapted(result, model, output, force=force)
    for line in describe_rows(result.metadata["adapted"]["rows"]):
        typer.echo(f"  {line}", err=True)
    alpha = "inf (no correction)" if math.isinf(result.alpha) else f"{result.alpha:.3g}"
    typer.echo(
        f"wrote {output}: {len(result.metadata['adapted']['rows'])} rig rows, ridge alpha "
        f"{alpha}; leave-one-out median error {100 * result.loo_median_rel_error:.1f} % "
        f"(the base model's {100 * result.base_median_rel_error:.1f} %)",
        err=True,
    )
