"""``deformctl measure --csv FILE…``: one object per CSV export, into one log or a dataset.

The flags become a :class:`deformctl.measure.CsvOptions` (how to read the files) and a
:class:`deformctl.measure.CsvFileTask`; :func:`deformctl.measure.csv_objects` says which object
each file is. One library function runs them: :func:`deformctl.measure.measure_csv_files` (one
squeeze log) or, for a dataset directory output, :func:`deformctl.measure.measure_csv_sweep`.
What was found in the files (the columns and units, a sign flipped) and their defects are
printed here, once per distinct line.
"""

from __future__ import annotations

import dataclasses
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from os import PathLike
from typing import Annotated, Any

import typer

from deformctl.artifacts.io import display_name
from deformctl.cli._common import finish_sweep, parse_mapping
from deformctl.measure import DEFAULT_CSV_MEMORY_BUDGET_GIB as DEFAULT_BUDGET
from deformctl.measure import (
    CsvBatchResult,
    CsvDialect,
    CsvFileTask,
    CsvOptions,
    csv_objects,
    measure_csv_files,
    measure_csv_sweep,
)
from deformctl.parallel import SweepOptions, single_file_workers

SkipRows = Annotated[
    int | None,
    typer.Option(
        "--skip-rows",
        metavar="N",
        help="CSV: the header is the line after N lines (a preamble) [default: the first row of "
        "names above the numbers].",
    ),
]
Delimiter = Annotated[
    str | None,
    typer.Option("--delimiter", metavar=",|;|tab", help="CSV: the delimiter [default: sniffed]."),
]
Decimal = Annotated[
    str | None,
    typer.Option("--decimal", metavar=".|,", help="CSV: the decimal mark [default: sniffed]."),
]
Thousands = Annotated[
    str | None,
    typer.Option(
        "--thousands",
        metavar=",|.|space|'",
        help="CSV: the thousands separator [default: sniffed from digit groups, e.g. 1,234.5].",
    ),
]
Encoding = Annotated[
    str | None,
    typer.Option(
        "--encoding",
        metavar="NAME",
        help="CSV: the text encoding, e.g. gbk, cp1252 [default: utf-8; a byte-order mark wins].",
    ),
]
ForceSign = Annotated[
    str | None,
    typer.Option(
        "--force-sign",
        metavar="auto|positive|negative",
        help="CSV: the sign of a compressive force in the file [default: auto, the sign that "
        "grows with the compression; a flip is reported and recorded].",
    ),
]
LagS = Annotated[
    str | None,
    typer.Option(
        "--lag-s",
        metavar="auto|S",
        help="CSV: shift the force S seconds earlier before the fit (it lags the position); "
        "auto: by the lag estimated on the loading ramp [default: estimated, reported, "
        "flagged force_lag, not shifted].",
    ),
]
ObjectsFrom = Annotated[
    str | None,
    typer.Option(
        "--objects-from",
        metavar="MAP.csv",
        help="CSV: a table of file, object_id, weight_n, size_x_cm, size_y_cm, size_z_cm, "
        "friction_mu (any but file may be left out; empty cells take the flags' values) "
        "[default: id = the file's stem].",
    ),
]


@dataclass(frozen=True)
class CsvFlags:
    """The ``--csv``-only flags as given (None: not given)."""

    skip_rows: int | None = None
    delimiter: str | None = None
    decimal: str | None = None
    thousands: str | None = None
    encoding: str | None = None
    force_sign: str | None = None
    lag_s: str | None = None
    objects_from: str | None = None

    def given(self) -> dict[str, object]:
        """Flag → value (for refusing them with another source)."""
        return {"--" + k.replace("_", "-"): v for k, v in dataclasses.asdict(self).items()}


FLAGS = tuple(CsvFlags().given())


def csv_options(
    flags: CsvFlags, rig: Any, memory_budget_gib: float | None
) -> tuple[CsvOptions, dict[str, Any]]:
    """The options every file is read with, and the reader's other arguments."""
    dialect = CsvDialect(
        delimiter=flags.delimiter,
        decimal=flags.decimal,
        thousands=flags.thousands,
        encoding=flags.encoding or "utf-8",
        skip_rows=flags.skip_rows,
    )
    options = CsvOptions(
        dialect=dialect,
        columns=parse_mapping(rig.columns, "--columns") if rig.columns else {},
        units=parse_mapping(rig.units, "--units") if rig.units else {},
        force_sign=flags.force_sign or "auto",  # type: ignore[arg-type]
        lag_s=flags.lag_s,  # type: ignore[arg-type]  # checked by CsvOptions
        position_is=rig.position_is,
        position_increases_when=rig.position_increases_when,
        memory_budget_gib=DEFAULT_BUDGET if memory_budget_gib is None else memory_budget_gib,
    )
    reader = {"segment": bool(rig.segment), "phase": rig.phase or "all"}
    return options, reader


def run(
    paths: Sequence[str],
    flags: CsvFlags,
    rig: Any,
    obj: dict[str, Any],
    memory_budget_gib: float | None,
    output: str,
    force: bool,
    sweep: SweepOptions,
) -> None:
    """Read every CSV file of ``paths`` and write their squeeze log or dataset directory."""
    options, reader = csv_options(flags, rig, memory_budget_gib)
    task = CsvFileTask(options, reader)
    files = csv_objects(paths, objects_from=flags.objects_from, **obj)
    if sweep.check(output, file_workers=True):
        summary = measure_csv_sweep(files, task, output=output, sweep=sweep, force=force)
        _report_dataset(summary.out_dir)
        finish_sweep(summary, "measure")
        return
    workers = single_file_workers(sweep.workers, len(files))
    result = measure_csv_files(files, task, output=output, force=force, workers=workers)
    _report_files(result, output)
    if result.exit_code:
        raise typer.Exit(result.exit_code)


def _counted(lines: Sequence[str], of: int) -> list[str]:
    """Each distinct line once, with ``(all M files)`` or ``(N of M files)``."""
    counts = Counter(lines)
    return [
        line if of == 1 else f"{line} ({'all ' if n == of else f'{n} of '}{of} files)"
        for line, n in counts.items()
    ]


def _report_files(result: CsvBatchResult, output: str) -> None:
    read = result.read
    total = len(result.outcomes)
    notes: list[str] = []
    for o in read:
        rec = o.recording
        assert rec is not None
        notes.append(rec.notes[0])
        for line in rec.notes[1:]:
            typer.echo(f"{display_name(o.file.path)}: {line}", err=True)
        for line in rec.warnings:
            typer.echo(
                f"warning: {display_name(o.file.path)}: object {o.file.object_id!r}: {line}",
                err=True,
            )
        for r in rec.ruptures:
            typer.echo(
                f"warning: {display_name(o.file.path)}: object {o.file.object_id!r}: rupture in "
                f"{r.describe()}: cut off",
                err=True,
            )
    for line in _counted(notes, len(read)):
        typer.echo(line if total > 1 else f"{display_name(read[0].file.path)}: {line}", err=True)
    for o in result.failed:
        typer.echo(f"error: {o.error}", err=True)
    if not read:
        return
    where = "stdout" if output == "-" else output
    squeezes = [s for o in read for s in o.recording.squeezes]  # type: ignore[union-attr]
    duration_s = sum(float(s.time_s[-1]) for s in squeezes)
    rec = read[0].recording
    assert rec is not None
    if total == 1:
        typer.echo(
            f"{where}: {len(squeezes)} squeeze(s) of {read[0].file.object_id!r}, {duration_s:.1f} "
            f"s, force {rec.force_rate_hz:.4g} Hz, position {rec.position_rate_hz:.4g} Hz",
            err=True,
        )
        return
    failed = f"; {len(result.failed)} file(s) failed (recorded in the log)" if result.failed else ""
    typer.echo(
        f"{where}: {len(read)} object(s) from {total} files, {len(squeezes)} squeeze(s), "
        f"{duration_s:.1f} s{failed}",
        err=True,
    )


def _report_dataset(out_dir: str | PathLike[str]) -> None:
    """The columns, warnings and failures of a ``measure --csv -o DIR/`` run, from its parts."""
    from deformctl.artifacts.dataset import read_dataset, read_failures
    from deformctl.errors import DeformctlError

    try:
        rows = read_dataset(out_dir)
    except DeformctlError:
        rows = None
    if rows is not None and len(rows):
        for line in _counted([f"columns: {c}" for c in rows["columns"]], len(rows)):
            typer.echo(f"{out_dir}: {line}", err=True)
        for rec in rows.to_dict("records"):
            for text in filter(None, str(rec["warnings"]).split("\n")):
                typer.echo(
                    f"warning: {rec['source_file']}: object {rec['object_id']!r}: {text}", err=True
                )
    try:
        failures = read_failures(out_dir)
    except (DeformctlError, ValueError):
        return
    for rec in failures.to_dict("records"):
        typer.echo(f"error: {rec['error_message']}", err=True)
