"""Commands with one subcommand per source (``measure sim|csv|bag|images``, ``lift sim|rig``),
and the old flag forms they still take for one release.

An old command line names its source with a flag (``measure --csv FILE ...``, ``measure CATALOG
--sim``, ``lift CATALOG --rig CMD``). :class:`SourceGroup` rewrites it into the subcommand form
(``measure csv FILE ...``, ``measure sim CATALOG``, ``lift rig CATALOG --command CMD``), prints
one deprecation line on stderr, and runs the subcommand: the same options reach the same code.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import typer
from typer._click import exceptions as click_exc  # typer vendors click: its exceptions

from deformctl.cli._group import HelpCommand, PlainValuesGroup, _HelpFlagDefault

if TYPE_CHECKING:  # pragma: no cover - annotations only
    from typer._click import Command, Context


@dataclass(frozen=True)
class OldSourceFlag:
    """An old source flag and the subcommand it became.

    Attributes:
        flag: the old flag (``--csv``).
        subcommand: its subcommand (``csv``).
        values: how many values follow the flag (0, 1 or 2).
        option: the subcommand's option the values go to (``--command`` for ``lift --rig CMD``);
            None: they become the subcommand's first arguments.
    """

    flag: str
    subcommand: str
    values: int = 0
    option: str | None = None


def rewrite(
    command: str, args: Sequence[str], flags: Sequence[OldSourceFlag], subcommands: Sequence[str]
) -> tuple[list[str], str] | None:
    """``args`` of an old command line in the subcommand form, and the deprecation line; None
    when ``args`` use no old source flag (the new form, or a bare ``--help``).

    Raises:
        UsageError: several old source flags (click's, exit 2).
    """
    if not args or args[0] in subcommands:
        return None
    by_flag = {f.flag: f for f in flags}
    found: list[OldSourceFlag] = []
    moved: list[str] = []
    rest: list[str] = []
    i = 0
    while i < len(args):
        token = args[i]
        if token == "--":
            rest.extend(args[i:])
            break
        name, eq, value = token.partition("=")
        old = by_flag.get(name)
        if old is None or (eq and old.values != 1):
            rest.append(token)
            i += 1
            continue
        found.append(old)
        values = [value] if eq else list(args[i + 1 : i + 1 + old.values])
        i += 1 if eq else 1 + old.values
        if old.option is None:
            moved.extend(values)
        else:
            rest.extend([old.option, *values])
    if not found:
        return None
    if len(found) > 1:
        given = ", ".join(sorted({f.flag for f in found}))
        raise click_exc.UsageError(
            f"several sources ({given}): give one subcommand, {command} {'|'.join(subcommands)}"
        )
    old = found[0]
    notice = f"deformctl: '{command} {old.flag}' is deprecated; use '{command} {old.subcommand}'"
    return [old.subcommand, *moved, *rest], notice


class SourceGroup(_HelpFlagDefault, PlainValuesGroup):
    """A command whose subcommands are its sources; it also runs the old flag forms
    (:data:`OLD_FLAGS`), with one deprecation line on stderr."""

    OLD_FLAGS: ClassVar[tuple[OldSourceFlag, ...]] = ()

    def parse_args(self, ctx: Context, args: list[str]) -> list[str]:
        """Rewrite an old command line (see :func:`rewrite`) before parsing it."""
        new = rewrite(str(ctx.info_name), args, self.OLD_FLAGS, list(self.commands))
        if new is not None:
            args, notice = new
            typer.echo(notice, err=True)
        return super().parse_args(ctx, args)

    def resolve_command(
        self, ctx: Context, args: list[str]
    ) -> tuple[str | None, Command | None, list[str]]:
        """The subcommand ``args[0]``; anything else is a usage error naming the subcommands."""
        if args and args[0] not in self.commands and not args[0].startswith("-"):
            raise click_exc.UsageError(
                f"{args[0]!r} is not a source: give one of {', '.join(self.commands)} first "
                f"(e.g. {ctx.command_path} {next(iter(self.commands))} {args[0]} ...)",
                ctx,
            )
        return super().resolve_command(ctx, args)


class MeasureGroup(SourceGroup):
    """``measure sim|csv|bag|images``."""

    OLD_FLAGS = (
        OldSourceFlag("--sim", "sim"),
        OldSourceFlag("--csv", "csv", 1),
        OldSourceFlag("--bag", "bag", 1),
        OldSourceFlag("--images", "images", 2),
    )


class LiftGroup(SourceGroup):
    """``lift sim|rig``."""

    OLD_FLAGS = (
        OldSourceFlag("--sim", "sim"),
        OldSourceFlag("--rig", "rig", 1, option="--command"),
    )


def source_group(
    cls: type[SourceGroup], callback: Any, subcommands: Sequence[Callable[..., Any]]
) -> typer.Typer:
    """The typer app of command ``callback`` (its docstring is the command's help) with
    ``subcommands`` (each named as its function), in that order."""
    group = typer.Typer(
        cls=cls,
        no_args_is_help=True,
        add_completion=False,
        pretty_exceptions_enable=False,
        rich_markup_mode=None,
        context_settings={"help_option_names": ["-h", "--help"]},
    )
    group.callback()(callback)
    for subcommand in subcommands:
        group.command(cls=HelpCommand)(subcommand)
    return group
