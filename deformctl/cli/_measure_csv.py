"""``deformctl measure csv FILE…``: one object per CSV export, into one log or a dataset.

The flags become a :class:`deformctl.measure.CsvOptions` (how to read the files) and a
:class:`deformctl.measure.CsvFileTask`; :func:`deformctl.measure.csv_objects` says which object
each file is. One library function runs them: :func:`deformctl.measure.measure_csv_files` (one
squeeze log) or, for a dataset directory output, :func:`deformctl.measure.measure_csv_sweep`.
What was found in the files (the columns and units, a sign flipped) and their defects are
printed here, once per distinct line.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Annotated

import typer

from deformctl.cli._common import finish_sweep, parse_mapping
from deformctl.cli._measure_csv_report import report_dataset, report_files
from deformctl.cli._measure_rig import (
    Columns,
    ObjectFlags,
    PositionIncreasesWhen,
    PositionIs,
    Units,
)
from deformctl.cli._options import OptionGroup
from deformctl.measure.csv.options import DEFAULT_CSV_MEMORY_BUDGET_GIB as DEFAULT_BUDGET
from deformctl.measure.csv.options import CsvDialect, CsvOptions

if TYPE_CHECKING:  # pragma: no cover - the readers (pandas, pyarrow, MCAP) load when it runs
    from deformctl.measure.csv.batch import CsvFile, CsvFileTask
    from deformctl.parallel import SweepOptions

SkipRows = Annotated[
    int | None,
    typer.Option("--skip-rows", metavar="N", help="Lines before the header [default: found]."),
]
Delimiter = Annotated[
    str | None,
    typer.Option("--delimiter", metavar=",|;|tab", help="The delimiter [default: sniffed]."),
]
Decimal = Annotated[
    str | None,
    typer.Option("--decimal", metavar=".|,", help="The decimal mark [default: sniffed]."),
]
Thousands = Annotated[
    str | None,
    typer.Option(
        "--thousands",
        metavar=",|.|space|'",
        help="The thousands separator [default: sniffed].",
    ),
]
Encoding = Annotated[
    str | None,
    typer.Option(
        "--encoding",
        metavar="NAME",
        help="Text encoding, e.g. cp1252 [default: utf-8].",
    ),
]
ForceSign = Annotated[
    str | None,
    typer.Option(
        "--force-sign",
        metavar="SIGN",
        help="Sign of a compressive force: positive, negative or auto (reported) [default: auto].",
    ),
]
LagS = Annotated[
    str | None,
    typer.Option(
        "--lag-s",
        metavar="auto|S",
        help="Shift the force S s earlier, the rig's latency (auto: by the estimated lag, "
        "which keeps D and withholds λ) [default: flag a lag, no shift].",
    ),
]
ObjectsFrom = Annotated[
    str | None,
    typer.Option(
        "--objects-from",
        metavar="MAP.csv",
        help="Each file's object_id, weight_n, size_*_cm, friction_mu [default: id = stem].",
    ),
]

DryRun = Annotated[
    bool,
    typer.Option(
        "--dry-run",
        help="Print what would be detected in each file; write nothing (-o is not needed).",
    ),
]


#: ``measure csv``'s budget: the rows of a CSV export and its log.
MemoryBudgetGib = Annotated[
    float | None,
    typer.Option(
        "--memory-budget-gib",
        metavar="GIB",
        help=f"Largest estimated memory of a file or log, GiB [default: {DEFAULT_BUDGET:g}].",
    ),
]


def csv_options(
    *,
    columns: str | None,
    units: str | None,
    position_is: str,
    position_increases_when: str | None,
    skip_rows: int | None,
    delimiter: str | None,
    decimal: str | None,
    thousands: str | None,
    encoding: str | None,
    force_sign: str | None,
    lag_s: str | None,
    memory_budget_gib: float | None,
) -> CsvOptions:
    """The options every file is read with (checked by :class:`CsvOptions` when built).

    Raises:
        UsageError: a malformed ``--columns``/``--units``, or a value outside its rule.
    """
    dialect = CsvDialect(
        delimiter=delimiter,
        decimal=decimal,
        thousands=thousands,
        encoding=encoding or "utf-8",
        skip_rows=skip_rows,
    )
    return CsvOptions(
        dialect=dialect,
        columns=parse_mapping(columns, "--columns") if columns else {},
        units=parse_mapping(units, "--units") if units else {},
        force_sign=force_sign or "auto",  # type: ignore[arg-type]
        lag_s=lag_s,  # type: ignore[arg-type]  # checked by CsvOptions
        position_is=position_is,  # type: ignore[arg-type]
        position_increases_when=position_increases_when,  # type: ignore[arg-type]
        memory_budget_gib=DEFAULT_BUDGET if memory_budget_gib is None else memory_budget_gib,
    )


#: How ``measure csv`` reads its files, as one :class:`CsvOptions`.
READ = OptionGroup(
    "options",
    (
        ("columns", Columns, None),
        ("units", Units, None),
        ("position_is", PositionIs, "travel"),
        ("position_increases_when", PositionIncreasesWhen, None),
        ("skip_rows", SkipRows, None),
        ("delimiter", Delimiter, None),
        ("decimal", Decimal, None),
        ("thousands", Thousands, None),
        ("encoding", Encoding, None),
        ("force_sign", ForceSign, None),
        ("lag_s", LagS, None),
        ("memory_budget_gib", MemoryBudgetGib, None),
    ),
    csv_options,
)


def _files(paths: Sequence[str], objects_from: str | None, named: ObjectFlags) -> list[CsvFile]:
    """Each file of ``paths`` with the object it holds (the same for a run and a dry run)."""
    from deformctl.measure.csv.batch import csv_objects

    return csv_objects(
        paths,
        objects_from=objects_from,
        object_id=named.object_id,
        weight_n=named.weight_n,
        size_cm=named.size_cm,
        friction_mu=named.friction_mu,
    )


def run(
    paths: Sequence[str],
    task: CsvFileTask,
    objects_from: str | None,
    named: ObjectFlags,
    output: str,
    force: bool,
    sweep: SweepOptions,
    quiet: bool = False,
) -> None:
    """Read every CSV file of ``paths`` and write their squeeze log or dataset directory (with
    its summary line unless ``quiet``)."""
    from deformctl.measure.csv.batch import measure_csv_files, measure_csv_sweep
    from deformctl.parallel import single_file_workers

    files = _files(paths, objects_from, named)
    if sweep.check(output, file_workers=True):
        summary = measure_csv_sweep(files, task, output=output, sweep=sweep, force=force)
        report_dataset(summary.out_dir)
        finish_sweep(summary, "measure", quiet=quiet)
        return
    workers = single_file_workers(sweep.workers, len(files))
    result = measure_csv_files(files, task, output=output, force=force, workers=workers)
    report_files(result, output, quiet=quiet)
    if result.exit_code:
        raise typer.Exit(result.exit_code)


def dry_run(
    paths: Sequence[str],
    task: CsvFileTask,
    objects_from: str | None,
    named: ObjectFlags,
    sweep: SweepOptions,
) -> None:
    """``measure csv --dry-run``: each file's detection on stdout, its error line on stderr;
    the exit code a real run would give (65 for one bad file, 1 when some of many fail)."""
    from deformctl.measure.csv.dry_run import dry_run_files, outcome_lines
    from deformctl.parallel import single_file_workers

    files = _files(paths, objects_from, named)
    result = dry_run_files(files, task, workers=single_file_workers(sweep.workers, len(files)))
    for outcome in result.outcomes:
        lines = outcome_lines(outcome)
        for line in lines:
            typer.echo(line, err=outcome.recording is None)
    typer.echo(f"dry run: {len(result.read)} of {len(files)} file(s) read; nothing written")
    if result.exit_code:
        raise typer.Exit(result.exit_code)
