"""Option groups: options several commands share, declared once and handed to each command as
the one value they build (:class:`OptionGroup`, :func:`with_options`), and the sweep group.

A command wrapped by :func:`with_options` takes one parameter per group (a
:class:`~deformctl.parallel.SweepOptions`, a library options type, ...); the command line sees the
group's options instead, and the wrapper builds the value from them before the command runs. An
option whose value is ``None`` was not given; the library default then applies.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable
from dataclasses import dataclass
from typing import Annotated, Any, TypeVar

import typer

from deformctl.parallel import DEFAULT_CONNECT_TIMEOUT_S, DEFAULT_PARTITION_SIZE, SweepOptions

R = TypeVar("R")

Workers = Annotated[
    str,
    typer.Option(
        "--workers",
        metavar="auto|N",
        show_default=False,
        help="N local processes, or auto [default: auto].",
    ),
]
Scheduler = Annotated[
    str | None,
    typer.Option(
        "--scheduler", metavar="tcp://HOST:PORT", help="Dataset output: run on this Dask scheduler."
    ),
]
ConnectTimeout = Annotated[
    float | None,
    typer.Option(
        "--connect-timeout",
        metavar="S",
        help=f"Seconds to reach the scheduler [default: {DEFAULT_CONNECT_TIMEOUT_S:g}].",
    ),
]
PartitionSize = Annotated[
    int | None,
    typer.Option(
        "--partition-size",
        metavar="N",
        help=f"Objects per part of -o DIR/ [default: {DEFAULT_PARTITION_SIZE}].",
    ),
]
Resume = Annotated[
    bool, typer.Option("--resume", help="Keep -o DIR/'s complete parts; do the rest.")
]


@dataclass(frozen=True)
class OptionGroup:
    """Options several commands share, declared once and handed to each as one value.

    Attributes:
        parameter: the name under which the command receives the value.
        options: ``(parameter name, Annotated alias, default)`` of each option, in help order.
        build: makes the value from the options' values (passed by parameter name); it checks
            them, raising :class:`~deformctl.errors.UsageError`.
    """

    parameter: str
    options: tuple[tuple[str, Any, Any], ...]
    build: Callable[..., Any]


def with_options(*groups: OptionGroup) -> Callable[[Callable[..., R]], Callable[..., R]]:
    """Give a command the options of ``groups``, each received as its one built value.

    The command takes ``group.parameter`` for each group; the command line sees the group's
    options instead (after the command's own), and the wrapper builds each value from them.
    """

    def decorate(command: Callable[..., R]) -> Callable[..., R]:
        signature = inspect.signature(command)  # the groups' values may be typing-only names
        names = {g.parameter for g in groups}
        kept = [
            p.replace(annotation=_resolved(p.annotation, command))
            for p in signature.parameters.values()
            if p.name not in names
        ]
        added = [
            inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=value, annotation=alias)
            for group in groups
            for name, alias, value in group.options
        ]

        @functools.wraps(command)
        def wrapper(*args: Any, **kwargs: Any) -> R:
            built = {
                g.parameter: g.build(**{n: kwargs.pop(n, v) for n, _, v in g.options})
                for g in groups
            }
            return command(*args, **built, **kwargs)

        parameters = [*kept, *added]
        wrapper.__signature__ = signature.replace(  # type: ignore[attr-defined]
            parameters=parameters, return_annotation=None
        )
        wrapper.__annotations__ = {p.name: p.annotation for p in parameters}
        return wrapper

    return decorate


def _resolved(annotation: Any, command: Callable[..., Any]) -> Any:
    """A parameter's annotation as an object (under ``from __future__ import annotations`` it
    is a string, evaluated in the command's module)."""
    if isinstance(annotation, str):
        return eval(annotation, command.__globals__)  # the module's own annotation
    return annotation


def _sweep(**given: Any) -> SweepOptions:
    return SweepOptions(
        workers=given["workers"],
        scheduler=given["scheduler"],
        connect_timeout_s=given["connect_timeout"],
        partition_size=given["partition_size"],
        resume=given["resume"],
    )


#: ``--workers`` ... ``--resume`` as one :class:`~deformctl.parallel.SweepOptions`, ``sweep``.
SWEEP = OptionGroup(
    "sweep",
    (
        ("workers", Workers, "auto"),
        ("scheduler", Scheduler, None),
        ("connect_timeout", ConnectTimeout, None),
        ("partition_size", PartitionSize, None),
        ("resume", Resume, False),
    ),
    _sweep,
)
#: What a command wrapped by :func:`with_sweep_options` receives when called directly.
NO_SWEEP = SweepOptions()
#: Give a command the options ``--workers`` ... ``--resume`` as one ``sweep`` argument.
with_sweep_options = with_options(SWEEP)
