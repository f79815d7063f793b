"""The root command group: click's usage errors as the project's one line, a ``--help``
that does not import pydantic, and a command whose plain option values do not either
(:mod:`deformctl.cli._plain_values`)."""

from __future__ import annotations

import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, ClassVar

import typer
from typer._click import exceptions as click_exc  # typer vendors click: its exceptions
from typer.core import TyperCommand, TyperGroup

from deformctl.cli import _plain_values
from deformctl.cli._common import _one_line
from deformctl.errors import EXIT_FAILURE, EXIT_USAGE

if TYPE_CHECKING:  # pragma: no cover - annotations only
    from typer._click import Command, Context
    from typer.core import TyperOption


class _HelpFlagDefault:
    """A command whose ``-h/--help`` flag, not given, is False (:meth:`get_help_option`)."""

    def get_help_option(self, ctx: Context) -> TyperOption | None:
        """The ``-h/--help`` flag, not given = False. Typer leaves an unset flag at None and
        coerces None through a pydantic adapter, which imports pydantic: about a third of what
        ``deformctl <command> --help`` costs (bench/bench_startup.py). False skips it (a bool
        needs no coercion); the help printed is the same."""
        option: TyperOption | None = super().get_help_option(ctx)  # type: ignore[misc]
        if option is not None and option.default is None:
            option.default = False
        return option


class PlainValuesGroup(TyperGroup):
    """A group whose subcommands coerce plain option values without pydantic
    (:func:`deformctl.cli._plain_values.install`, on the subcommand it resolves)."""

    def resolve_command(
        self, ctx: Context, args: list[str]
    ) -> tuple[str | None, Command | None, list[str]]:
        """The subcommand ``args[0]``, its plain parameters given
        :class:`~deformctl.cli._plain_values.PlainFirst`."""
        name, command, rest = super().resolve_command(ctx, args)
        _plain_values.install(command)
        return name, command, rest


class HelpCommand(_HelpFlagDefault, TyperCommand):
    """A command whose ``--help`` (or its help flag, not given) does not import pydantic."""


class OneLineErrorGroup(_HelpFlagDefault, PlainValuesGroup):
    """The root command group: every click usage error becomes one ``error: ...`` line, exit 2.

    Click prints a usage error (an unknown command or option, ``--seed abc``, a missing argument)
    as a three-line box; shell pipelines and CI want the project's one-line form, so the group
    runs click in non-standalone mode and formats what it raises itself. ``--help`` and the
    help printed for a bare ``deformctl`` are unchanged; the commands are listed in pipeline
    order.
    """

    #: The commands in the order they are listed (typer adds those with subcommands last).
    ORDER: ClassVar[tuple[str, ...]] = ()

    def list_commands(self, ctx: Context) -> list[str]:
        """The commands in :data:`ORDER`, then any other."""
        rank = {name: i for i, name in enumerate(self.ORDER)}
        return sorted(super().list_commands(ctx), key=lambda name: rank.get(name, len(rank)))

    def main(  # type: ignore[override]
        self,
        args: Sequence[str] | None = None,
        prog_name: str | None = None,
        complete_var: str | None = None,
        standalone_mode: bool = True,
        **extra: Any,
    ) -> Any:
        """Run the command; in standalone mode exit with its code, errors as one line."""
        try:
            result = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except click_exc.NoArgsIsHelpError as err:
            if not standalone_mode:
                raise
            typer.echo(err.ctx.get_help() if err.ctx is not None else "")
            sys.exit(EXIT_USAGE)
        except click_exc.ClickException as err:
            if not standalone_mode:
                raise
            sys.exit(_report_click_error(err))
        except typer.Abort:
            if not standalone_mode:
                raise
            typer.echo("error: aborted", err=True)
            sys.exit(EXIT_FAILURE)
        if not standalone_mode:
            return result
        sys.exit(result if isinstance(result, int) else 0)


def _report_click_error(err: click_exc.ClickException) -> int:
    """Print ``err`` as the project's one line; return its exit code (2 for usage errors)."""
    message = _one_line(err.format_message()).rstrip(".")
    if isinstance(err, click_exc.UsageError):
        where = f"{err.ctx.command_path}: " if err.ctx is not None else ""
        hint = f" (see '{err.ctx.command_path} --help')" if err.ctx is not None else ""
        typer.echo(f"error: {where}{message[:1].lower()}{message[1:]}{hint}", err=True)
        return EXIT_USAGE
    typer.echo(f"error: {message}", err=True)
    return err.exit_code
