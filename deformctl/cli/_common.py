"""Helpers shared by the subcommand modules: error translation, progress bars, sweep summaries."""

from __future__ import annotations

import functools
import inspect
import os
import warnings
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any, ParamSpec, TypeVar

import typer

from deformctl.artifacts.io import command_inputs
from deformctl.errors import EXIT_FAILURE, DeformctlError, UsageError

if TYPE_CHECKING:  # pragma: no cover - rich and the executor load where a command uses them
    from rich.console import Console

    from deformctl.parallel import SweepSummary

P = ParamSpec("P")
R = TypeVar("R")

Advance = Callable[[str, int, int], None]
"""``advance(object_id, done, total)``: what the library's progress hooks call."""


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def _warning_text(caught: Sequence[warnings.WarningMessage]) -> str:
    """The distinct warnings raised during a command, as one clause (first three, then a count)."""
    texts = list(
        dict.fromkeys(f"{w.category.__name__}: {_one_line(str(w.message))}" for w in caught)
    )
    more = f" (+{len(texts) - 3} more)" if len(texts) > 3 else ""
    return "; ".join(texts[:3]) + more


#: The parameters through which commands name the files they write.
OUTPUT_PARAMETERS = ("output", "log", "metrics")


def _output_names(func: Callable[..., Any]) -> tuple[str, ...]:
    """The parameters of ``func`` that name outputs: :data:`OUTPUT_PARAMETERS` given as options
    (``characterize``'s positional ``log`` is its input)."""
    params = inspect.signature(func).parameters
    return tuple(
        name for name in OUTPUT_PARAMETERS if name in params and not _is_argument(params[name])
    )


def _is_argument(param: inspect.Parameter) -> bool:
    """A positional typer argument (``typer.Argument`` as default or ``Annotated`` metadata)."""
    if isinstance(param.default, typer.models.ArgumentInfo):
        return True
    annotation = param.annotation
    if isinstance(annotation, str):
        return "Argument(" in annotation
    return any(
        isinstance(m, typer.models.ArgumentInfo) for m in getattr(annotation, "__metadata__", ())
    )


def _refuse_output_as_input(kwargs: dict[str, Any], outputs: Sequence[str]) -> None:
    """Before any work: no output may resolve to an existing file given as an input.

    (The writers check again against every input actually read, see
    :func:`deformctl.artifacts.io.check_not_an_input`.)

    Raises:
        UsageError: one line naming the output (exit 2).
    """
    inputs: set[str] = set()
    for name, value in kwargs.items():
        values = value if isinstance(value, list | tuple) else [value]
        for v in values:
            if name not in outputs and isinstance(v, str) and os.path.isfile(v):
                inputs.add(os.path.realpath(v))
    for name in outputs:
        out = kwargs.get(name)
        if isinstance(out, str) and out != "-" and os.path.realpath(out) in inputs:
            raise UsageError(f"{out}: the output is one of the inputs; choose another name")


def translate_errors(func: Callable[P, R]) -> Callable[P, R]:
    """Turn a :class:`DeformctlError` raised by ``func`` into one stderr line and its exit code.

    Warnings that numpy, scipy or scikit-learn raise on the way (overflow, an ill-conditioned
    matrix) are collected rather than printed: with an error they are folded into its one line
    (``error: <file>: <what is wrong> (while: RuntimeWarning: overflow ...)``); after a
    success each distinct one is printed as one ``warning:`` line. ``functools.wraps`` keeps the
    signature typer reads. A :class:`MemoryError` (an allocation beyond the machine, once a
    budget check was passed by raising the budget) is one line with exit 1.
    """

    outputs = _output_names(func)

    @functools.wraps(func)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        with command_inputs(), warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("default")
            try:
                _refuse_output_as_input(kwargs, outputs)
                result = func(*args, **kwargs)
            except DeformctlError as err:
                folded = f" (while: {_warning_text(caught)})" if caught else ""
                typer.echo(f"error: {err}{folded}", err=True)
                raise typer.Exit(err.exit_code) from None
            except MemoryError as err:  # a budget raised beyond what the machine has
                detail = f": {_one_line(str(err))}" if str(err) else ""
                typer.echo(
                    f"error: out of memory{detail}; lower the problem size (or the "
                    "--memory-budget-gib you raised)",
                    err=True,
                )
                raise typer.Exit(EXIT_FAILURE) from None
        for text in dict.fromkeys(_one_line(str(w.message)) for w in caught):
            typer.echo(f"warning: {text}", err=True)
        return result

    return wrapper


def warn(line: str) -> None:
    """One ``warning: ...`` line on stderr (doubtful but usable input)."""
    typer.echo(f"warning: {line}", err=True)


@contextmanager
def progress_bar(console: Console, label: str, *, at_least: int = 2) -> Iterator[Advance | None]:
    """A transient rich bar (done/total, elapsed, ETA) on ``console`` for ``at_least``+ steps.

    Yields the ``advance(object_id, done, total)`` hook, which draws the bar from its first call
    (when the total is known), or None when ``console`` is not a terminal.
    """
    if not console.is_terminal:
        yield None
        return
    from rich import progress as rp

    bar = rp.Progress(
        rp.TextColumn(f"{label} {{task.description}}"),
        rp.BarColumn(),
        rp.MofNCompleteColumn(),
        rp.TimeElapsedColumn(),
        rp.TextColumn("ETA"),
        rp.TimeRemainingColumn(),
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


def finish_sweep(summary: SweepSummary, what: str, *, quiet: bool = False) -> None:
    """Print a sweep's one-line summary on stderr (unless ``quiet``); exit 1 when any failed."""
    failures = f"; failed objects: {summary.out_dir}/_failures/" if summary.failed_total else ""
    if not quiet:
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
