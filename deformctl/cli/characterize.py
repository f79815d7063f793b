"""``deformctl characterize``: deformability D and damping λ per object from a squeeze log."""

from __future__ import annotations

import math
import os
from typing import Any

import pandas as pd
import typer

from deformctl.artifacts import Provenance, check_output_path, write_table
from deformctl.artifacts.io import is_stdio
from deformctl.characterize import (
    CharacterizeTask,
    LogCoefficients,
    characterize_dir,
    characterize_sweep,
    read_and_characterize,
)
from deformctl.cli import _sweep, app
from deformctl.cli._common import translate_errors
from deformctl.errors import UsageError
from deformctl.quality import thresholds_help


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


@app.command()
@translate_errors
def characterize(
    log: str = typer.Argument(..., metavar="SQUEEZE.mcap", help="A squeeze log; - for stdin."),
    output: str = typer.Option(
        ..., "-o", "--output", metavar="coefficients.parquet", help="Table to write; - for stdout."
    ),
    method: str = typer.Option(
        "lsq",
        "--method",
        metavar="lsq|paper",
        help="lsq: joint least-squares fit of f = D d + λ d' with standard errors; "
        "paper: the paper's per-sample ratios.",
    ),
    window_s: float | None = typer.Option(
        None,
        "--window-s",
        metavar="S",
        help="Savitzky-Golay window for d and d', s (default: from the log's position sample "
        "rate, 0.2 s at >= 1 kHz, 0.43 s at 100 Hz).",
    ),
    preload: str | None = typer.Option(
        None,
        "--preload",
        metavar="fit|zero",
        help="lsq: fit a contact preload (f = F0 + D d + λ d') or assume none [default: fit for "
        "rig recordings (measure --bag/--csv), zero for simulated squeezes].",
    ),
    constrain_damping: bool = typer.Option(
        False,
        "--constrain-damping",
        help="lsq: fit with λ >= 0 (bounded least squares); the row says when the bound held.",
    ),
    strict: bool = typer.Option(
        False,
        "--strict",
        help="Exit 65 (nothing written) if any object is flagged. " + thresholds_help(),
    ),
    allow_flagged: bool = typer.Option(
        False, "--allow-flagged", help="Write objects with negative D (flagged) instead of exit 65."
    ),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing output."),
    workers: int | None = _sweep.workers_option(),
    scheduler: str | None = _sweep.scheduler_option(),
    connect_timeout: float | None = _sweep.connect_timeout_option(),
    partition_size: int | None = _sweep.partition_size_option(),
    resume: bool = _sweep.resume_option(),
) -> None:
    """Estimate each object's deformability D (N/cm) and damping λ (N·s/cm) from a squeeze log.

    The squeezes are grouped by object and fitted to f = D·d + λ·d', with d the total
    compression between the palms. The table goes to the output; a summary goes to stdout, or
    to stderr when the table itself goes to stdout (-o -).

    Every row carries the fit's diagnostics and a quality column, ok or the flags (see
    --strict and the README's "When the numbers are doubtful"); each flagged object gives one
    warning line on stderr.

    SQUEEZE.mcap may also be a directory written by measure --sim -o DIR/ (its part-*.mcap
    logs, in order). With a dataset directory output (-o DIR/) the objects are fitted in
    parallel (--workers, --scheduler; --resume) into DIR/part-*.parquet; an object that cannot
    be fitted is recorded in DIR/_failures/ and the others go on.

    Example: deformctl characterize squeeze.mcap -o coefficients.parquet --method lsq
    """
    if method not in ("lsq", "paper"):
        raise UsageError(f"--method must be lsq or paper, got {method!r}")
    fit: dict[str, Any] = {"preload": preload, "constrain_damping": constrain_damping}
    policy = {"strict": strict, "allow_flagged": allow_flagged}
    sweep = _sweep.SweepOptions(workers, scheduler, connect_timeout, partition_size, resume)
    if sweep.check(output):
        task = CharacterizeTask(method, window_s, preload, constrain_damping, strict, allow_flagged)
        _sweep.finish(characterize_sweep(log, task, output=output, sweep=sweep, force=force),
                      "characterize")  # fmt: skip
        return
    check_output_path(output, force)
    if os.path.isdir(log):
        result = characterize_dir(log, method, window_s=window_s, **fit, **policy)  # type: ignore[arg-type]
    else:
        result = read_and_characterize(log, method, window_s=window_s, **fit, **policy)  # type: ignore[arg-type]
    provenance = Provenance.from_invocation(
        [log],
        settings={
            "method": method,
            "window_s": result.window_s,
            "window_s_option": window_s,
            "position_rate_hz": result.position_rate_hz,
            "preload": result.preload,
            "preload_option": preload,
            "constrain_damping": constrain_damping,
        },
    )
    write_table(result.table, output, "coefficients", provenance=provenance, force=force)
    for line in result.warnings:
        typer.echo(f"warning: {line}", err=True)
    typer.echo(render_summary(result), err=is_stdio(output))
