"""``--quiet``, which drops the one line a long command ends with (:class:`RunClock`, from
:mod:`deformctl.summary`: objects done, flagged, failed, wall time, where the output went;
warnings and errors still print), and the console its progress bar draws on."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated

import typer

from deformctl.summary import RunClock

if TYPE_CHECKING:  # pragma: no cover - rich loads when a command draws its bar
    from rich.console import Console

Quiet = Annotated[
    bool,
    typer.Option(
        "--quiet",
        "-q",
        help="No summary line; warnings and errors print.",
    ),
]


def stderr_console() -> Console:
    """The console a command's progress bar draws on (rich, imported when a command runs)."""
    from rich.console import Console

    return Console(stderr=True)


__all__ = ["Quiet", "RunClock", "stderr_console"]
