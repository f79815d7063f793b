"""What ``measure csv`` prints of a run: the columns and units found (once per distinct line),
each file's notes and warnings, the ruptures cut off, the failures and the summary line."""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from os import PathLike
from typing import TYPE_CHECKING

import typer

from deformctl.artifacts.io import display_name

if TYPE_CHECKING:  # pragma: no cover - the batch reader loads when it runs
    from deformctl.measure.csv.batch import CsvBatchResult


def _counted(lines: Sequence[str], of: int) -> list[str]:
    """Each distinct line once, with ``(all M files)`` or ``(N of M files)``."""
    counts = Counter(lines)
    return [
        line if of == 1 else f"{line} ({'all ' if n == of else f'{n} of '}{of} files)"
        for line, n in counts.items()
    ]


def report_files(result: CsvBatchResult, output: str, *, quiet: bool = False) -> None:
    from deformctl.measure.csv.batch import file_notices

    read = result.read
    total = len(result.outcomes)
    notes: list[str] = []
    for o in read:
        rec = o.recording
        assert rec is not None
        notes.append(rec.notes[0])
        for line in file_notices(o):
            typer.echo(line, err=True)
    for line in _counted(notes, len(read)):
        typer.echo(line if total > 1 else f"{display_name(read[0].file.path)}: {line}", err=True)
    for o in result.failed:
        typer.echo(f"error: {o.error}", err=True)
    if not read or quiet:  # --quiet: no summary line
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


def report_dataset(out_dir: str | PathLike[str]) -> None:
    """The columns, warnings and failures of a ``measure csv -o DIR/`` run, from its parts."""
    from deformctl.artifacts.dataset import read_dataset, read_failures
    from deformctl.errors import DeformctlError
    from deformctl.measure.csv.batch import dataset_notices

    try:
        rows = read_dataset(out_dir)
    except DeformctlError:
        rows = None
    if rows is not None and len(rows):
        for line in _counted([f"columns: {c}" for c in rows["columns"]], len(rows)):
            typer.echo(f"{out_dir}: {line}", err=True)
        for line in dataset_notices(rows):
            typer.echo(line, err=True)
    try:
        failures = read_failures(out_dir)
    except (DeformctlError, ValueError):
        return
    for rec in failures.to_dict("records"):
        typer.echo(f"error: {rec['error_message']}", err=True)
