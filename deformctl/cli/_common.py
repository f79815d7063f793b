"""Helpers shared by the subcommand modules: error translation, progress bars, sweep summaries."""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import ParamSpec, TypeVar

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from deformctl.errors import DeformctlError, UsageError
from deformctl.parallel import SweepSummary

P = ParamSpec("P")
R = TypeVar("R")

Advance = Callable[[str, int, int], None]
"""``advance(object_id, done, total)``: what the library's progress hooks call."""


def translate_errors(func: Callable[P, R]) -> Callable[P, R]:
    """Turn a :class:`DeformctlError` raised by ``func`` into one stderr line and its exit code.

    ``functools.wraps`` keeps the signature typer reads.
    """

    @functools.wraps(func)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        try:
            return func(*args, **kwargs)
        except DeformctlError as err:
            typer.echo(f"error: {err}", err=True)
            raise typer.Exit(err.exit_code) from None

    return wrapper


@contextmanager
def progress_bar(console: Console, label: str, *, at_least: int = 2) -> Iterator[Advance | None]:
    """A transient rich bar on ``console`` for a run of ``at_least`` steps or more.

    Yields the ``advance(object_id, done, total)`` hook, which draws the bar from its first call
    (when the total is known), or None when ``console`` is not a terminal.
    """
    if not console.is_terminal:
        yield None
        return
    bar = Progress(
        TextColumn(f"{label} {{task.description}}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=console,
        transient=True,
    )
    task: list[object] = []

    def advance(object_id: str, done: int, total: int) -> None:
        if total < at_least:
            return
        if not task:
            bar.start()
            task.append(bar.add_task("", total=total))
        bar.update(task[0], completed=done, description=object_id)  # type: ignore[arg-type]

    try:
        yield advance
    finally:
        if task:
            bar.stop()


def finish_sweep(summary: SweepSummary, what: str) -> None:
    """Print a sweep's one-line summary on stderr; exit 1 when any object failed."""
    failures = f"; failed objects: {summary.out_dir}/_failures/" if summary.failed_total else ""
    typer.echo(f"{summary.out_dir}: {what}: {summary.line()}{failures}", err=True)
    if summary.exit_code:
        raise typer.Exit(summary.exit_code)


def parse_mapping(text: str, option: str) -> dict[str, str]:
    """Parse ``key=value,key=value`` (``--columns``, ``--units``) into a dict.

    Raises:
        UsageError: an item without ``=``, an empty key or value, or a repeated key.
    """
    out: dict[str, str] = {}
    for item in text.split(","):
        key, sep, value = item.partition("=")
        key, value = key.strip(), value.strip()
        if not sep or not key or not value:
            raise UsageError(f"{option}: expected key=value[,key=value...], got {item!r}")
        if key in out:
            raise UsageError(f"{option}: {key!r} given twice")
        out[key] = value
    return out
