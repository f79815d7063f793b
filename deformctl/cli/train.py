"""``deformctl train``: fit the lifting-force model on an index table, save it, report metrics."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from deformctl.artifacts.io import committed_together, is_stdio
from deformctl.cli._common import translate_errors
from deformctl.cli._options import Force
from deformctl.cli._summary import Quiet, RunClock
from deformctl.errors import UsageError
from deformctl.population_options import PAPER_TRAIN_SIZE as DEFAULT_TRAIN_SIZE

if TYPE_CHECKING:  # pragma: no cover - rich loads when the command runs
    from rich.table import Table

#: Row labels of the printed table, keyed by the metrics entries of :func:`train_model`.
PREDICTORS = (
    ("model", "model"),
    ("baseline_nearest", "nearest entry"),
    ("baseline_f_w", "F_w alone"),
    ("baseline_constant_ratio", "median L_f/F_w x F_w"),
)


def _pct(value: Any) -> str:
    return "n/a" if value is None else f"{100.0 * value:.2f} %"


def _num(value: Any, fmt: str) -> str:
    return "n/a" if value is None else format(value, fmt)


def metrics_table(report: dict[str, Any]) -> Table:
    """The rich table of max / median relative error, MAE and R² per predictor and split."""
    from rich.table import Table

    hp = report["hyperparameters"]
    form = report.get("form", "paper")
    calibration = report.get("n_calibration") or 0
    sizes = f"{report['n_train']} train / " + (
        f"{calibration} calibration / " if calibration else ""
    )
    title = (
        f"lifting-force model ({form}: {', '.join(report['features'])}): hidden "
        f"{','.join(str(h) for h in hp['hidden'])}, seed {report['seed']}, "
        f"{sizes}{report['n_test']} test"
    )
    out = Table(
        title=title,
        caption="nearest entry on train rows is leave-one-out; F_w = W / (2 mu)",
    )
    for name, justify in (
        ("predictor", "left"),
        ("set", "left"),
        ("max rel err", "right"),
        ("median rel err", "right"),
        ("MAE (N)", "right"),
        ("R²", "right"),
    ):
        out.add_column(name, justify=justify)  # type: ignore[arg-type]
    for key, label in PREDICTORS:
        entry = report.get(key)
        for split in ("train", "test"):
            m = None if entry is None else entry[split]
            out.add_row(
                label,
                split,
                _pct(None if m is None else m["max_rel_error"]),
                _pct(None if m is None else m["median_rel_error"]),
                _num(None if m is None else m["mae_n"], ".3f"),
                _num(None if m is None else m["r2"], ".4f"),
            )
    return out


def coverage_lines(report: dict[str, Any]) -> list[str]:
    """One line per coverage P: the bound's margin, empirical coverage and mean margin on the
    test rows (empty without calibration rows)."""
    lines = []
    for p, entry in (report.get("conformal") or {}).items():
        if entry["coverage"] is None:
            lines.append(
                f"upper bound P = {p}: no finite bound from {entry['n_calibration']} "
                f"calibration rows (rank {entry['rank']})"
            )
            continue
        lines.append(
            f"upper bound P = {p}: margin {entry['margin']:+.2%} over the prediction "
            f"({entry['n_calibration']} calibration rows); on the {entry['n_test']} test rows "
            f"coverage {entry['coverage']:.3f}, mean margin (upper / L_f - 1) "
            f"{entry['mean_margin']:.2%}"
        )
    return lines


@translate_errors
def train(
    index: str = typer.Argument(..., help="The index table (Parquet) written by `table`."),
    output: str = typer.Option(..., "-o", "--output", help="The model file to write (.skops)."),
    hidden: str | None = typer.Option(
        None,
        "--hidden",
        help="Hidden layer sizes: 2 or a list such as 8,8 [default: 2, the paper's 3-2-1 "
        "network, for a table with one μ; 8,8 for the grip model, when μ varies].",
    ),
    train_size: int = typer.Option(
        DEFAULT_TRAIN_SIZE,
        "--train-size",
        help="Training rows; the rest (after the calibration rows) is the test set.",
    ),
    calibration_size: int = typer.Option(
        0,
        "--calibration-size",
        help="Rows held out to calibrate the split-conformal upper bound (predict --coverage); "
        "0: no bound.",
    ),
    note: Annotated[
        list[str] | None,
        typer.Option(
            "--note",
            metavar="KEY=VALUE",
            help="Record a fact about the data in the model's metadata (repeatable), e.g. "
            "--note sim_preset=paper.",
        ),
    ] = None,
    seed: int = typer.Option(0, "--seed", help="Seeds the split and the initial weights."),
    laws: str | None = typer.Option(
        None, "--laws", metavar="COEFFICIENTS", help="Per material law: a table of model (law)."
    ),
    law_train_size: int | None = typer.Option(
        None,
        "--law-train-size",
        help="With --laws: at most this many rows train each other law's network (a law with "
        "fewer rows trains on every row not calibrating) [default: --train-size].",
    ),
    metrics: str | None = typer.Option(
        None, "--metrics", help="Also write the metrics as JSON here (- for stdout)."
    ),
    max_parameters: int = typer.Option(
        100_000, "--max-parameters", min=1, help="Refuse a network with more weights than this."
    ),
    force: Force = False,
    quiet: Quiet = False,
) -> None:
    """Train Pipeline(StandardScaler, MLPRegressor) on an index table and save it with skops.

    When the table has one friction μ (the paper's population), the model is the paper's
    network on (W, D, λ): it learns L_f / W and scales back by W. When friction_mu varies, it is
    the grip model: inputs (W, D, λ, μ), the network learns log(L_f / F_w) with F_w = W / (2 μ)
    from the damping ratio ζ and the natural frequency ω_n (docs/explanation/model.md). The best
    of 8 seeded restarts is picked on the training rows. A seeded permutation splits the rows
    into --train-size training rows, --calibration-size calibration rows (their relative
    errors calibrate the upper bound of predict --coverage) and the test rows. Prints max and
    median relative error, MAE and R² on train and test for the model and for three baselines
    on the same split: the nearest index-table entry (grip model: its L_f / F_w times F_w),
    F_w = W / (2 μ) alone, and the constant ratio (the training rows' median L_f / F_w times
    F_w); with calibration rows, the bound's empirical coverage and mean margin on the test
    rows for P = 0.9 and 0.95. The model file's metadata records the seed, form, features,
    hyper-parameters, training ranges, split ids, metrics, the calibration scores and a numpy
    export of the network (what predict evaluates); the same seed gives identical predictions.

    Example:

    \b
      deformctl train index.parquet -o model.skops --seed 0 --metrics metrics.json
      deformctl train grip-index.parquet -o grip.skops --train-size 250 \\
          --calibration-size 150 --note sim_preset=paper
    """
    clock = RunClock("train")
    # deferred: scikit-learn and skops take seconds to import and only training needs them
    from deformctl.artifacts import Provenance, atomic_output, check_output_path, read_table
    from deformctl.artifacts.model import save_model
    from deformctl.model import TrainOptions
    from deformctl.table import flagged_rows
    from deformctl.train import model_metadata, parse_hidden, parse_notes, train_with_laws

    sizes = None if hidden is None else parse_hidden(hidden, max_parameters=max_parameters)
    options = TrainOptions(
        hidden=sizes,
        train_size=train_size,
        calibration_size=calibration_size,
        seed=seed,
        law_train_size=law_train_size,
    )
    notes = parse_notes(note)
    if is_stdio(output):
        raise UsageError("the model file cannot be stdout; give a file name with -o")
    if metrics is not None and not is_stdio(metrics) and Path(metrics) == Path(output):
        raise UsageError(f"-o and --metrics name the same file: {output}")
    check_output_path(output, force)  # fail before training, and leave nothing behind
    if metrics is not None:
        check_output_path(metrics, force, binary=False)

    table = read_table(index, "index_table")
    result, section, report = train_with_laws(
        table, None if laws is None else read_table(laws), options
    )
    settings = {
        "hidden": report["hyperparameters"]["hidden"],
        "train_size": train_size,
        "calibration_size": calibration_size,
        **({} if law_train_size is None else {"law_train_size": law_train_size}),
    }
    provenance = Provenance.from_invocation([index], seed=seed, settings=settings)
    report["provenance"] = provenance.to_dict()
    report["notes"] = notes
    metadata = {**model_metadata(result), "provenance": report["provenance"], "notes": notes}
    metadata |= {} if section is None else {"laws": section}

    with committed_together():  # the model and the metrics file: both or neither
        save_model(output, result.model, metadata=metadata, force=force)
        if metrics is not None:
            with atomic_output(metrics, force=force, binary=False) as tmp:
                tmp.write_text(json.dumps(report, indent=2, allow_nan=False) + "\n")

    print_report(report, metrics)
    written = [output, *([metrics] if metrics and not is_stdio(metrics) else [])]
    clock.finish(done=len(table), flagged=flagged_rows(table), failed=0, quiet=quiet,
                 output=", ".join(written))  # fmt: skip


def print_report(report: dict[str, Any], metrics: str | None) -> None:
    """The metrics table, the coverage lines and the warning of a network that did not
    converge; with ``--metrics -`` the JSON owns stdout and these go to stderr."""
    from rich.console import Console

    console = Console(
        file=sys.stderr if metrics is not None and is_stdio(metrics) else sys.stdout,
        highlight=False,
    )
    console.print(metrics_table(report))
    for line in coverage_lines(report):  # unwrapped: one line per coverage
        typer.echo(line, err=console.file is sys.stderr)
    if not report["converged"]:
        typer.echo(
            "warning: the chosen network stopped at max_iter before converging; "
            "the metrics above are what it reached",
            err=True,
        )
    from deformctl.grip.lawtrain import law_lines

    for line in law_lines(report):
        typer.echo(line, err=console.file is sys.stderr)
