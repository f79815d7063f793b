"""The ``deformctl`` command: one module per subcommand, registered here in pipeline order.

Commands translate: they check paths and options, call one library function and report its
result. Each command is wrapped by :func:`deformctl.cli._common.translate_errors`, so a
:class:`~deformctl.errors.DeformctlError` becomes one line on stderr,
``error: <file>: <what is wrong>``, and the error's exit code; anything else is a bug and keeps
its traceback. The options several commands share are declared once in
:mod:`deformctl.cli._options`. Typer lists commands in the order they are registered.
"""

from __future__ import annotations

import typer

from deformctl.cli import (
    characterize,
    inspect,
    lift,
    measure,
    population,
    predict,
    table,
    train,
)
from deformctl.cli._common import OneLineErrorGroup
from deformctl.version import __version__

app = typer.Typer(
    name="deformctl",
    cls=OneLineErrorGroup,
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _version_callback(value: bool) -> None:
    if value:
        typer.echo(f"deformctl {__version__}")
        raise typer.Exit()


@app.callback()
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


#: The subcommands in pipeline order; ``inspect`` reads any artifact and comes last.
COMMANDS = (
    population.population,
    measure.measure,
    characterize.characterize,
    lift.lift,
    table.table,
    train.train,
    predict.predict,
    inspect.inspect,
)
for _command in COMMANDS:
    app.command()(_command)


def main() -> None:
    """Console-script entry point."""
    app(prog_name="deformctl")
