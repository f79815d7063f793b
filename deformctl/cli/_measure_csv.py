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
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated

import typer

from deformctl.cli._common import finish_sweep, parse_mapping
from deformctl.cli._measure_csv_report import report_dataset, report_files
from deformctl.cli._measure_rig import RigOptions, segmentation
from deformctl.measure.csv_options import DEFAULT_CSV_MEMORY_BUDGET_GIB as DEFAULT_BUDGET
from deformctl.measure.csv_options import CsvDialect, CsvOptions

if TYPE_CHECKING:  # pragma: no cover - the readers (pandas, pyarrow, MCAP) load when --csv runs
    from deformctl.measure.options import Segmentation
    from deformctl.parallel import SweepOptions

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

    def given(self) -> list[str]:
        """The flags given (for refusing them with another source)."""
        return [
            _flag(f.name) for f in dataclasses.fields(self) if getattr(self, f.name) is not None
        ]


def _flag(name: str) -> str:
    return "--" + name.replace("_", "-")


#: The ``--csv``-only flags.
FLAGS = tuple(_flag(f.name) for f in dataclasses.fields(CsvFlags))


@dataclass(frozen=True)
class ObjectFlags:
    """What the command line says of the objects (each file's ``--objects-from`` row wins).

    The values are checked per file, when the file's object is built
    (:func:`deformctl.measure.csv_objects`, :class:`deformctl.catalog.MeasuredObject`).
    """

    object_id: str | None = None
    weight_n: float | None = None
    size_cm: tuple[float, float, float] | None = None
    friction_mu: float | None = None


def csv_options(
    flags: CsvFlags, rig: RigOptions, memory_budget_gib: float | None
) -> tuple[CsvOptions, Segmentation]:
    """The options every file is read with, and how each is cut into squeezes."""
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
        position_is=rig.position_is,  # type: ignore[arg-type]
        position_increases_when=rig.position_increases_when,  # type: ignore[arg-type]
        memory_budget_gib=DEFAULT_BUDGET if memory_budget_gib is None else memory_budget_gib,
    )
    return options, segmentation(rig)


def run(
    paths: Sequence[str],
    flags: CsvFlags,
    rig: RigOptions,
    named: ObjectFlags,
    memory_budget_gib: float | None,
    output: str,
    force: bool,
    sweep: SweepOptions,
) -> None:
    """Read every CSV file of ``paths`` and write their squeeze log or dataset directory."""
    from deformctl.measure.csv_batch import (
        CsvFileTask,
        csv_objects,
        measure_csv_files,
        measure_csv_sweep,
    )
    from deformctl.parallel import single_file_workers

    options, cut = csv_options(flags, rig, memory_budget_gib)
    task = CsvFileTask(options, cut)
    files = csv_objects(
        paths, objects_from=flags.objects_from, object_id=named.object_id,
        weight_n=named.weight_n, size_cm=named.size_cm, friction_mu=named.friction_mu,
    )  # fmt: skip
    if sweep.check(output, file_workers=True):
        summary = measure_csv_sweep(files, task, output=output, sweep=sweep, force=force)
        report_dataset(summary.out_dir)
        finish_sweep(summary, "measure")
        return
    workers = single_file_workers(sweep.workers, len(files))
    result = measure_csv_files(files, task, output=output, force=force, workers=workers)
    report_files(result, output)
    if result.exit_code:
        raise typer.Exit(result.exit_code)
