"""The ``deformctl`` command: one module per subcommand, registered here in pipeline order.

Commands translate: they check paths and options, call one library function and report its
result. Each command is wrapped by :func:`deformctl.cli._common.translate_errors`, so a
:class:`~deformctl.errors.DeformctlError` becomes one line on stderr,
``error: <file>: <what is wrong>``, and the error's exit code; anything else is a bug and keeps
its traceback. The options several commands share are declared once in
:mod:`deformctl.cli._options`. Typer lists commands in the order they are registered.

A command module is imported only when it runs: ``deformctl predict ...`` builds the app with
the ``predict`` command alone (:func:`main`), so it does not import what ``measure``, ``lift``
or ``inspect`` need (pandas, pyarrow, numba, OpenCV). ``deformctl``, ``deformctl --help`` and
anything that is not a command name build the whole app, as do :data:`app` and
:data:`COMMANDS` (attributes made on first use).
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import typer

from deformctl.cli._common import OneLineErrorGroup

if TYPE_CHECKING:  # pragma: no cover - built on first use (module __getattr__)
    app: typer.Typer
    COMMANDS: tuple[Callable[..., Any], ...]

#: The subcommands in pipeline order (``inspect`` reads any artifact and comes last): each is
#: the function of the same name in ``deformctl.cli.<name>``.
COMMAND_NAMES: tuple[str, ...] = (
    "population",
    "measure",
    "characterize",
    "lift",
    "table",
    "train",
    "predict",
    "inspect",
)


def _version_callback(value: bool) -> None:
    if value:
        from deformctl import __version__

        typer.echo(f"deformctl {__version__}")
        raise typer.Exit()


def _root(
    version: bool = typer.Option(
        False,
        "--version",
        callback=_version_callback,
        is_eager=True,
        help="Print the version and exit.",
    ),
) -> None:
    """Learn how hard a robot must squeeze a deformable object to lift it without slip.

    Exit codes: 0 ok, 1 failure, 2 usage, 65 bad input data, 66 missing input file.
    """


def command(name: str) -> Callable[..., Any]:
    """The function behind subcommand ``name`` (importing its module)."""
    function: Callable[..., Any] = getattr(importlib.import_module(f"deformctl.cli.{name}"), name)
    return function


def build_app(names: Sequence[str] = COMMAND_NAMES) -> typer.Typer:
    """The ``deformctl`` app with the subcommands ``names`` (all by default), in that order."""
    built = typer.Typer(
        name="deformctl",
        cls=OneLineErrorGroup,
        no_args_is_help=True,
        add_completion=False,
        pretty_exceptions_enable=False,
        rich_markup_mode=None,
        context_settings={"help_option_names": ["-h", "--help"]},
    )
    built.callback()(_root)
    for name in names:
        built.command()(command(name))
    return built


def __getattr__(name: str) -> Any:
    """``app`` (the whole app) and ``COMMANDS`` (every command function), made on first use."""
    if name == "app":
        value: Any = build_app()
    elif name == "COMMANDS":
        value = tuple(command(n) for n in COMMAND_NAMES)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def main() -> None:
    """Console-script entry point: only the invoked command's module is imported."""
    args = sys.argv[1:]
    names = [args[0]] if args and args[0] in COMMAND_NAMES else COMMAND_NAMES
    build_app(names)(prog_name="deformctl")
