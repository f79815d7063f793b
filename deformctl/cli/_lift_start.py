"""``deformctl lift``: the options that start the search from a prediction; the run's report.

``--start-model MODEL`` or ``--start-table INDEX`` (with ``--start-interpolate K``), the first
attempt at the prediction × ``--start-margin``; the objects' D and λ from ``--coefficients`` (or
the catalog, see :mod:`deformctl.lift.seeded`). :func:`start_seed` turns them into the
library's :class:`~deformctl.lift.seeded.StartSeed`.
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING, Annotated

import typer

from deformctl.artifacts.io import is_stdio
from deformctl.cli._options import OptionGroup
from deformctl.errors import SearchError, UsageError
from deformctl.lift.options import DEFAULT_START_MARGIN

if TYPE_CHECKING:  # pragma: no cover - the seed sources import scikit-learn when used
    from collections.abc import Callable

    from deformctl.cli._summary import RunClock
    from deformctl.lift.seeded import StartSeed
    from deformctl.lift.stage import CatalogLiftResult

#: ``lift``'s first argument: a catalog, or a coefficients table whose objects carry their values.
CatalogArg = Annotated[
    str,
    typer.Argument(
        metavar="CATALOG",
        help="Catalog, CSV or Parquet (- for stdin), or a coefficients table.",
    ),
]
StartModel = Annotated[
    str | None,
    typer.Option(
        "--start-model",
        metavar="MODEL",
        help="Start at this model's L_f (grip: bundled).",
    ),
]
StartTable = Annotated[
    str | None,
    typer.Option(
        "--start-table",
        metavar="INDEX.parquet",
        help="Start at the nearest index entry's L_f/F_w.",
    ),
]
StartInterpolate = Annotated[
    int | None,
    typer.Option(
        "--start-interpolate",
        metavar="K",
        help="With --start-table: K nearest [default: 1].",
    ),
]
StartMargin = Annotated[
    float | None,
    typer.Option(
        "--start-margin",
        metavar="M",
        help=f"Start at the prediction x M [default: {DEFAULT_START_MARGIN:g}].",
    ),
]
Coefficients = Annotated[
    str | None,
    typer.Option(
        "--coefficients",
        metavar="COEF.parquet",
        help="Their D and λ [default: the catalog's].",
    ),
]


def _start(
    *,
    start_model: str | None,
    start_table: str | None,
    start_interpolate: int | None,
    start_margin: float | None,
    coefficients: str | None,
) -> Callable[..., StartSeed | None]:
    return functools.partial(
        start_seed, start_model, start_table, start_interpolate, start_margin, coefficients
    )


#: ``--start-model`` ... ``--coefficients`` as one ``start(protocol=..., dataset=...)``, which
#: returns the :class:`~deformctl.lift.seeded.StartSeed` (or None) once the output is known.
START = OptionGroup(
    "start",
    (
        ("start_model", StartModel, None),
        ("start_table", StartTable, None),
        ("start_interpolate", StartInterpolate, None),
        ("start_margin", StartMargin, None),
        ("coefficients", Coefficients, None),
    ),
    _start,
)


def start_seed(
    model: str | None,
    table: str | None,
    interpolate: int | None,
    margin: float | None,
    coefficients: str | None,
    *,
    protocol: str,
    dataset: bool,
) -> StartSeed | None:
    """The seed the start options ask for, or None without ``--start-model``/``--start-table``.

    Raises:
        UsageError: both sources, a start option without a source, ``--start-interpolate``
            without ``--start-table``, ``--protocol paper``, a dataset output, or a margin < 1.
        MissingInputError, InputDataError: see :mod:`deformctl.lift.seeded`.
    """
    if model is not None and table is not None:
        raise UsageError("give --start-model or --start-table, not both")
    if interpolate is not None and table is None:
        raise UsageError("--start-interpolate needs --start-table")
    if model is None and table is None:
        for flag, value in (("--start-margin", margin), ("--coefficients", coefficients)):
            if value is not None:
                raise UsageError(f"{flag} needs --start-model or --start-table")
        return None
    flag = "--start-model" if model is not None else "--start-table"
    if protocol == "paper":
        raise UsageError(f"{flag} bisects to --tolerance as refine does; drop --protocol paper")
    if dataset:
        raise UsageError(f"{flag} writes a table file, not a dataset directory output (-o DIR/)")
    from deformctl.lift.search import validate_start_margin
    from deformctl.lift.seeded import load_start_model, load_start_table

    chosen = DEFAULT_START_MARGIN if margin is None else margin
    validate_start_margin(chosen)

    if model is not None:
        return load_start_model(model, margin=chosen, coefficients=coefficients)
    assert table is not None
    return load_start_table(table, margin=chosen, k=interpolate, coefficients=coefficients)


def run_counts(run: CatalogLiftResult) -> tuple[int, int, int]:
    """``(done, flagged, failed)`` objects of a run: flagged, those whose start fell back to F_w
    (outside the start model's training range, a warning line each); failed, those that did not
    converge or were not run."""
    failed = len(run.failures) + len(run.not_run)
    flagged = 0
    if "start_in_training_range" in run.table.columns:
        outside = run.table["start_in_training_range"].astype("boolean").eq(False)
        flagged = int(outside.fillna(False).sum())
    return len(run.table) - failed, flagged, failed


def run_summary(run: CatalogLiftResult, clock: RunClock, output: str, log: str | None) -> str:
    """The line a single-file ``lift`` ends with (:class:`~deformctl.cli._summary.RunClock`)."""
    done, flagged, failed = run_counts(run)
    where = ", ".join("stdout" if is_stdio(p) else p for p in (output, log) if p is not None)
    return clock.line(done=done, flagged=flagged, failed=failed, output=where)


def report_run(run: CatalogLiftResult, *, quiet: bool, summary: str | None = None) -> None:
    """Each object's line on stdout (unless an output is stdout), the ``summary`` line on stderr
    (when given and every object converged; else the one error line), then the exit.

    Raises:
        SearchError: an object did not converge or the runner failed (exit 1; one line).
    """
    if not quiet:
        aborted = {f.object_id for f in run.failures if f.aborted}  # their line is the error
        for result in run.results:
            if result.object_id not in aborted:
                typer.echo(result.message)
    message = run.error_message()
    if summary is not None and message is None:  # a failed run's one line is its error
        typer.echo(summary, err=True)
    if message is not None:
        raise SearchError(message)
