"""The ``deformctl`` command: one module per subcommand, registered here in pipeline order.

Commands translate: they check paths and options, call one library function and report its
result. Each command is wrapped by :func:`deformctl.cli._common.translate_errors`, so a
:class:`~deformctl.errors.DeformctlError` becomes one line on stderr,
``error: <file>: <what is wrong>``, and the error's exit code; anything else is a bug and keeps
its traceback. The options several commands share are declared once in
:mod:`deformctl.cli._options`. Typer lists commands in the order they are registered.

A command module is imported only when it runs: ``deformctl predict ...`` builds the app with
the ``predict`` command alone (:func:`main`), so it does not import what ``measure``, ``lift``
or ``inspect`` need (pandas, pyarrow, numba, OpenCV). ``deformctl``, ``deformctl --help``,
``--version`` and anything that is not a command name need only the commands' names and
docstrings: :func:`main` reads those from the command modules' source (:func:`listed_command`)
and imports none of them. :data:`app` and :data:`COMMANDS` (attributes made on first use) are
the whole app and every command function. A command module imports the heavy libraries its
command runs on (pandas, pyarrow, scikit-learn, numba, OpenCV, Dask, the MCAP readers) inside
the command, so that ``deformctl <command> --help`` does not pay for them either
(``tests/cli/test_startup.py``; ``make bench`` times them).
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import typer

from deformctl.cli._group import HelpCommand, OneLineErrorGroup

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
    "adapt",
    "inspect",
    "examples",
    "warmup",
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


def listed_command(name: str) -> Callable[..., Any]:
    """A stand-in for subcommand ``name`` that only lists it: its docstring is the command
    function's, read from ``deformctl/cli/<name>.py`` without importing it (``deformctl
    --help`` prints the same first lines; running the stand-in is a bug)."""
    spec = importlib.util.find_spec(f"deformctl.cli.{name}")
    assert spec is not None, name
    assert spec.origin is not None, name
    tree = ast.parse(Path(spec.origin).read_text(encoding="utf-8"))
    found = (n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == name)
    doc = ast.get_docstring(next(found))

    def listed() -> None:
        raise AssertionError(f"{name}: a listed command stand-in was run")  # pragma: no cover

    listed.__name__ = listed.__qualname__ = name
    listed.__doc__ = doc
    return listed


def build_app(
    names: Sequence[str] = COMMAND_NAMES,
    make: Callable[[str], Callable[..., Any]] = command,
) -> typer.Typer:
    """The ``deformctl`` app with the subcommands ``names`` (all by default), in that order,
    each ``make(name)`` (the command function; :func:`listed_command` to list it only)."""
    built = typer.Typer(
        name="deformctl",
        cls=type("DeformctlGroup", (OneLineErrorGroup,), {"ORDER": tuple(names)}),
        no_args_is_help=True,
        add_completion=False,
        pretty_exceptions_enable=False,
        rich_markup_mode=None,
        context_settings={"help_option_names": ["-h", "--help"]},
    )
    built.callback()(_root)
    for name in names:
        function = make(name)
        group = getattr(function, "group", None)  # a command with subcommands: its typer app
        if isinstance(group, typer.Typer):
            built.add_typer(group, name=name)
        else:
            built.command(cls=HelpCommand)(function)
    return built


def leaf_commands(function: Callable[..., Any]) -> tuple[Callable[..., Any], ...]:
    """The functions that run: ``function`` itself, or each of its subcommands."""
    group = getattr(function, "group", None)
    if not isinstance(group, typer.Typer):
        return (function,)
    return tuple(c.callback for c in group.registered_commands if c.callback is not None)


def __getattr__(name: str) -> Any:
    """``app`` (the whole app) and ``COMMANDS`` (every function that runs a command or a
    subcommand, in order), made on first use."""
    if name == "app":
        value: Any = build_app()
    elif name == "COMMANDS":
        value = tuple(leaf for n in COMMAND_NAMES for leaf in leaf_commands(command(n)))
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def main() -> None:
    """Console-script entry point: only the invoked command's module is imported (none for
    ``deformctl --help``, which lists the commands)."""
    args = sys.argv[1:]
    if args and args[0] in COMMAND_NAMES:
        build_app([args[0]])(prog_name="deformctl")
    else:
        build_app(COMMAND_NAMES, listed_command)(prog_name="deformctl")
