"""``deformctl characterize``: deformability D and damping λ per object from a squeeze log."""

from __future__ import annotations

import math
from typing import Annotated

import pandas as pd
import typer

from deformctl.artifacts.io import is_stdio
from deformctl.characterize import (
    DEFAULT_WINDOW_S,
    CharacterizeTask,
    FitOptions,
    LogCoefficients,
    QualityPolicy,
    characterize_file,
    characterize_sweep,
    check_method,
    check_preload,
    sweep_warnings,
)
from deformctl.characterize.options import DEFAULT_MODEL, MODELS, check_model
from deformctl.characterize.quality import thresholds_help
from deformctl.cli import _options as opt
from deformctl.cli._common import finish_sweep, translate_errors
from deformctl.parallel import SweepOptions

Preload = Annotated[
    str | None,
    typer.Option(
        "--preload",
        metavar="fit|zero",
        help="lsq: fit a contact preload (f = F0 + D d + λ d') or assume none [default: fit for "
        "rig recordings (measure --bag/--csv), zero for simulated squeezes].",
    ),
]
ConstrainDamping = Annotated[
    bool,
    typer.Option(
        "--constrain-damping",
        help="lsq: fit with λ >= 0 (bounded least squares); the row says when the bound held.",
    ),
]
Strict = Annotated[
    bool,
    typer.Option(
        "--strict",
        help="Exit 65 (nothing written) if any object is flagged. " + thresholds_help(),
    ),
]
Model = Annotated[
    str,
    typer.Option(
        "--model",
        metavar="|".join(MODELS),
        help="The material model: kv, Kelvin-Voigt, f = D d + λ d' (+ F0 with a preload).",
    ),
]
AllowFlagged = Annotated[
    bool,
    typer.Option(
        "--allow-flagged", help="Write objects with negative D (flagged) instead of exit 65."
    ),
]


def _pm(value: float, se: float, digits: int) -> str:
    text = f"{value:.{digits}f}"
    return f"{text} ± {se:.{digits}f}" if math.isfinite(se) else text


def render_summary(result: LogCoefficients) -> str:
    """A short plain-text table of the coefficients: one line per object."""
    df: pd.DataFrame = result.table
    rows = [
        ("object", "D (N/cm)", "λ (N·s/cm)", "R²", "samples", "squeezes", "quality", "window (s)")
    ]
    for rec in df.to_dict("records"):
        oid = str(rec["object_id"])
        rows.append(
            (
                oid,
                _pm(rec["deformability_n_per_cm"], rec["deformability_se_n_per_cm"], 3),
                _pm(rec["damping_ns_per_cm"], rec["damping_se_ns_per_cm"], 3),
                f"{rec['r2']:.4f}",
                str(rec["n_samples"]),
                str(rec["n_squeezes"]),
                str(rec.get("quality", "")),
                f"{result.window_s[oid]:.3g}",
            )
        )
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    return "\n".join(
        "  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip() for r in rows
    )


@translate_errors
@opt.with_sweep_options
def characterize(
    log: Annotated[str, typer.Argument(metavar="SQUEEZE.mcap", help="A squeeze log; - for stdin.")],
    output: Annotated[
        str,
        typer.Option(
            "-o", "--output", metavar="coefficients.parquet", help="Table to write; - for stdout."
        ),
    ],
    method: Annotated[
        str,
        typer.Option(
            "--method",
            metavar="lsq|paper",
            help="lsq: joint least-squares fit of f = D d + λ d' with standard errors; "
            "paper: the paper's per-sample ratios.",
        ),
    ] = "lsq",
    window_s: Annotated[
        float | None,
        typer.Option(
            "--window-s",
            metavar="S",
            help="Savitzky-Golay window for d and d', s (default: from the log's position sample "
            f"rate, {DEFAULT_WINDOW_S:g} s at >= 1 kHz, 0.43 s at 100 Hz).",
        ),
    ] = None,
    model: Model = DEFAULT_MODEL,
    preload: Preload = None,
    constrain_damping: ConstrainDamping = False,
    strict: Strict = False,
    allow_flagged: AllowFlagged = False,
    force: opt.Force = False,
    sweep: SweepOptions = opt.NO_SWEEP,
) -> None:
    """Estimate each object's deformability D (N/cm) and damping λ (N·s/cm) from a squeeze log.

    The squeezes are grouped by object and fitted to f = D·d + λ·d', with d the total
    compression between the palms. The table goes to the output; a summary goes to stdout, or
    to stderr when the table itself goes to stdout (-o -).

    Every row carries the fit's diagnostics and a quality column, ok or the flags (see
    --strict and the README's "When the numbers are doubtful"); each flagged object gives one
    warning line on stderr.

    SQUEEZE.mcap may also be a directory written by measure --sim -o DIR/ (its _logs/part-*.mcap
    logs, in order). With a dataset directory output (-o DIR/) the objects are fitted in
    parallel (--workers, --scheduler; --resume) into DIR/part-*.parquet; an object that cannot
    be fitted is recorded in DIR/_failures/ and the others go on.

    Example: deformctl characterize squeeze.mcap -o coefficients.parquet --method lsq
    """
    fit = FitOptions(
        method=check_method(method), window_s=window_s,
        preload=None if preload is None else check_preload(preload),
        constrain_damping=constrain_damping, model=check_model(model),
    )  # fmt: skip
    policy = QualityPolicy(strict=strict, allow_flagged=allow_flagged)
    if sweep.check(output):
        task = CharacterizeTask(fit=fit, policy=policy)
        summary = characterize_sweep(log, task, output=output, sweep=sweep, force=force)
        for line in sweep_warnings(summary.out_dir):
            typer.echo(f"warning: {line}", err=True)
        finish_sweep(summary, "characterize")
        return
    result = characterize_file(log, fit, policy, output=output, force=force)
    for line in result.warnings:
        typer.echo(f"warning: {line}", err=True)
    typer.echo(render_summary(result), err=is_stdio(output))
