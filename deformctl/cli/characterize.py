"""``deformctl characterize``: deformability D and damping λ per object from a squeeze log."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Annotated

import typer

from deformctl.artifacts.io import is_stdio
from deformctl.characterize.material_options import MODEL_CHOICES, MaterialOptions
from deformctl.characterize.options import (
    FitOptions,
    QualityPolicy,
    check_method,
    check_preload,
)
from deformctl.characterize.quality import thresholds_help
from deformctl.cli import _options as opt
from deformctl.cli._common import finish_sweep, translate_errors
from deformctl.cli._summary import Quiet, RunClock
from deformctl.errors import UsageError
from deformctl.parallel import SweepOptions
from deformctl.squeeze.window import DEFAULT_WINDOW_S

if TYPE_CHECKING:  # pragma: no cover - the fits (pandas, scipy) load when the command runs
    import pandas as pd

    from deformctl.characterize.stage import LogCoefficients

Preload = Annotated[
    str | None,
    typer.Option(
        "--preload",
        metavar="fit|zero",
        help="lsq: fit a contact preload (f = F0 + D d + λ d') or assume none [default: fit for "
        "rig recordings (measure bag/csv), zero for simulated squeezes].",
    ),
]
#: Deprecated, hidden: the lsq fits always bound λ >= 0, so the flag changes no number. It is
#: still accepted for this release, with one deprecation line, and goes no further than here.
ConstrainDamping = Annotated[
    bool, typer.Option("--constrain-damping", hidden=True, help="Deprecated: has no effect.")
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
        metavar="|".join(MODEL_CHOICES),
        help="lsq: the material law. kv: Kelvin-Voigt f = F0 + D d + λ d'; hc: Hunt-Crossley "
        "f = F0 + k d^n + λ d^n d' (n in [1, 3]); sls: standard linear solid (spring k1 beside "
        "a spring k2 in series with a dashpot, relaxation time τ); exp: exponential "
        "stiffening f = F0 + k0 (e^(B d) - 1)/B + λ e^(B d) d'; auto: all four, Kelvin-Voigt "
        "reported unless a richer law's extra parameters are off their bounds, its stiffness "
        "above 0 and its BIC lower by 10; every law's parameters, standard errors, AIC and BIC "
        "in the table.",
    ),
]
AtForceN = Annotated[
    float | None,
    typer.Option(
        "--at-force-n",
        metavar="F",
        help="lsq: state D as the secant stiffness of the law's rate-free force-compression "
        "curve at this force, N (> 0, at most each object's peak force) [default: F_w = "
        "W/(2 μ) when the log knows the object's weight and friction, else its median loading "
        "force; the table records the force used].",
    ),
]
Plot = Annotated[
    str | None,
    typer.Option(
        "--plot",
        metavar="DIR",
        help="lsq: draw each object's fit into DIR/<object>.png (force against compression "
        "with every law's fit, force and compression against time, residuals, flags in the "
        "title); the paths are printed on stderr.",
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
        (
            "object",
            "model",
            "D (N/cm)",
            "at (N)",
            "λ (N·s/cm)",
            "R²",
            "samples",
            "squeezes",
            "quality",
            "window (s)",
        )
    ]
    for rec in df.to_dict("records"):
        oid = str(rec["object_id"])
        at = rec.get("operating_force_n", math.nan)
        rows.append(
            (
                oid,
                str(rec.get("model", "")),
                _pm(rec["deformability_n_per_cm"], rec["deformability_se_n_per_cm"], 3),
                f"{at:.4g}" if isinstance(at, float) and math.isfinite(at) else "",
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
    logs: Annotated[
        list[str],
        typer.Argument(
            metavar="SQUEEZE.mcap...",
            help="Squeeze logs (- for stdin); the squeezes of one object id in several logs "
            "(recordings at several speeds) get one joint fit.",
        ),
    ],
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
    preload: Preload = None,
    constrain_damping: ConstrainDamping = False,
    model: Model = "auto",
    at_force_n: AtForceN = None,
    plot: Plot = None,
    strict: Strict = False,
    allow_flagged: AllowFlagged = False,
    quiet: Quiet = False,
    force: opt.Force = False,
    sweep: SweepOptions = opt.NO_SWEEP,
) -> None:
    """Estimate each object's deformability D (N/cm) and damping λ (N·s/cm) from squeeze logs.

    The squeezes are grouped by object and fitted with a material law (--model; d is the total
    compression between the palms), bounded (stiffness, λ >= 0; a parameter at its bound is
    flagged at_bound). D is the secant stiffness at the operating force (--at-force-n). The
    table goes to the output; a summary goes to stdout, or to stderr when the table itself goes
    to stdout (-o -).

    Every row carries the fit's diagnostics and a quality column, ok or the flags (see
    --strict and the README's "When the numbers are doubtful"); each flagged object gives one
    warning line on stderr.

    SQUEEZE.mcap may also be a directory written by measure sim -o DIR/ (its _logs/part-*.mcap
    logs, in order). With a dataset directory output (-o DIR/) the objects are fitted in
    parallel (--workers, --scheduler; --resume) into DIR/part-*.parquet; an object that cannot
    be fitted is recorded in DIR/_failures/ and the others go on.

    Example: deformctl characterize squeeze.mcap -o coefficients.parquet --model auto
    """
    clock = RunClock("characterize")
    from deformctl.characterize.stage import (
        CharacterizeTask,
        characterize_file,
        characterize_sweep,
        sweep_warnings,
    )

    fit = FitOptions(
        method=check_method(method),
        window_s=window_s,
        preload=None if preload is None else check_preload(preload),
        materials=MaterialOptions(model=model, at_force_n=at_force_n),
    )
    policy = QualityPolicy(strict=strict, allow_flagged=allow_flagged)
    if constrain_damping:
        typer.echo(
            "deformctl: 'characterize --constrain-damping' is deprecated and has no effect: "
            "the lsq fits always bound λ >= 0",
            err=True,
        )
    if sweep.check(output):
        if len(logs) != 1 or plot is not None:
            raise UsageError(
                "a dataset directory output (-o DIR/) takes one log directory and no --plot"
            )
        task = CharacterizeTask(fit=fit, policy=policy)
        summary = characterize_sweep(logs[0], task, output=output, sweep=sweep, force=force)
        for line in sweep_warnings(summary.out_dir):
            typer.echo(f"warning: {line}", err=True)
        finish_sweep(summary, "characterize", quiet=quiet)
        return
    result = characterize_file(logs, fit, policy, output=output, force=force, plot_dir=plot)
    for line in result.warnings:
        typer.echo(f"warning: {line}", err=True)
    typer.echo(render_summary(result), err=is_stdio(output))
    for path in result.plots:
        typer.echo(f"plot: {path}", err=True)
    flagged = int((result.table["quality"] != "ok").sum())
    clock.finish(
        done=len(result.table),
        flagged=flagged,
        failed=0,
        quiet=quiet,
        output="stdout" if is_stdio(output) else output,
    )
