"""``deformctl train``: fit the lifting-force model on an index table, save it, report metrics."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import typer
from rich.console import Console
from rich.table import Table

from deformctl.artifacts import Provenance, atomic_output, check_output_path, read_table
from deformctl.artifacts.io import committed_together, is_stdio
from deformctl.cli._common import translate_errors
from deformctl.cli._options import Force
from deformctl.errors import UsageError
from deformctl.population import PAPER_TRAIN_SIZE as DEFAULT_TRAIN_SIZE

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
    hp = report["hyperparameters"]
    title = (
        f"lifting-force model: hidden {','.join(str(h) for h in hp['hidden'])}, "
        f"seed {report['seed']}, {report['n_train']} train / {report['n_test']} test"
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


@translate_errors
def train(
    index: str = typer.Argument(..., help="The index table (Parquet) written by `table`."),
    output: str = typer.Option(..., "-o", "--output", help="The model file to write (.skops)."),
    hidden: str = typer.Option(
        "2", "--hidden", help="Hidden layer sizes: 2 (the paper's 3-2-1 network) or a list: 8,4."
    ),
    train_size: int = typer.Option(
        DEFAULT_TRAIN_SIZE, "--train-size", help="Training rows; the rest is the test set."
    ),
    seed: int = typer.Option(0, "--seed", help="Seeds the split and the initial weights.", min=0),
    metrics: str | None = typer.Option(
        None, "--metrics", help="Also write the metrics as JSON here (- for stdout)."
    ),
    max_parameters: int = typer.Option(
        100_000, "--max-parameters", min=1, help="Refuse a network with more weights than this."
    ),
    force: Force = False,
) -> None:
    """Train Pipeline(StandardScaler, MLPRegressor) on (W, D, λ) -> L_f and save it with skops.

    The network learns L_f / W and its output is scaled back by W (inputs stay (W, D, λ)); the
    best of 8 seeded restarts is picked on the training rows. The rows are split by a seeded
    permutation into --train-size training rows and a test set. Prints max and median
    relative error, MAE and R² on train and test for the model and for
    three baselines on the same split: the nearest index-table entry, F_w = W / (2 μ) alone, and
    the constant ratio (the training rows' median L_f / F_w times F_w).
    The model file's metadata records the seed, features, hyper-parameters, training ranges,
    split ids and metrics; the same seed gives identical predictions.

    Example:

    \b
      deformctl train index.parquet -o model.skops --seed 0 --metrics metrics.json
    """
    # deferred: scikit-learn and skops take seconds to import and only training needs them
    from deformctl.artifacts.model import save_model
    from deformctl.train import parse_hidden, train_model, train_report

    sizes = parse_hidden(hidden, max_parameters=max_parameters)
    if is_stdio(output):
        raise UsageError("the model file cannot be stdout; give a file name with -o")
    if metrics is not None and not is_stdio(metrics) and Path(metrics) == Path(output):
        raise UsageError(f"-o and --metrics name the same file: {output}")
    check_output_path(output, force)  # fail before training, and leave nothing behind
    if metrics is not None:
        check_output_path(metrics, force, binary=False)

    table = read_table(index, "index_table")
    result = train_model(table, hidden=sizes, train_size=train_size, seed=seed)
    report = train_report(result)
    provenance = Provenance.from_invocation(
        [index], seed=seed, settings={"hidden": list(sizes), "train_size": train_size}
    )
    report["provenance"] = provenance.to_dict()
    metadata = {k: v for k, v in report.items() if k != "predictions"}

    with committed_together():  # the model and the metrics file: both or neither
        save_model(output, result.model, metadata=metadata, force=force)
        if metrics is not None:
            with atomic_output(metrics, force=force, binary=False) as tmp:
                tmp.write_text(json.dumps(report, indent=2, allow_nan=False) + "\n")

    # With --metrics - the JSON owns stdout; the table goes to stderr.
    console = Console(
        file=sys.stderr if metrics is not None and is_stdio(metrics) else sys.stdout,
        highlight=False,
    )
    console.print(metrics_table(report))
    if not report["converged"]:
        typer.echo(
            "warning: the chosen network stopped at max_iter before converging; "
            "the metrics above are what it reached",
            err=True,
        )
    typer.echo(
        f"wrote {output}" + (f" and {metrics}" if metrics and not is_stdio(metrics) else ""),
        err=True,
    )
