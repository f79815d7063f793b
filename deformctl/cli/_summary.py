"""The one line a long command ends with (objects done, flagged, failed, wall time, where the
output went) and ``--quiet``, which drops it (warnings and errors still print)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Annotated

import typer

if TYPE_CHECKING:  # pragma: no cover - rich loads when a command draws its bar
    from rich.console import Console

Quiet = Annotated[
    bool,
    typer.Option(
        "--quiet",
        "-q",
        help="No summary line at the end (objects done, flagged, failed, wall time, output); "
        "warnings and errors still print.",
    ),
]


@dataclass
class RunClock:
    """Started when a command starts its work; :meth:`line` is its summary at the end."""

    command: str
    started_s: float = field(default_factory=time.monotonic)

    def line(self, *, done: int, flagged: int, failed: int, output: str, detail: str = "") -> str:
        """``lift: 4 object(s) done, 1 flagged, 0 failed in 12.3 s -> lift.parquet``, then
        ``detail`` in parentheses when given."""
        wall_s = time.monotonic() - self.started_s
        text = (
            f"{self.command}: {done} object(s) done, {flagged} flagged, {failed} failed in "
            f"{wall_s:.1f} s -> {output}"
        )
        return f"{text} ({detail})" if detail else text

    def finish(
        self,
        *,
        done: int,
        flagged: int,
        failed: int,
        output: str,
        detail: str = "",
        quiet: bool = False,
    ) -> None:
        """Print :meth:`line` on stderr, unless ``quiet``."""
        if not quiet:
            typer.echo(
                self.line(done=done, flagged=flagged, failed=failed, output=output, detail=detail),
                err=True,
            )


def stderr_console() -> Console:
    """The console a command's progress bar draws on (rich, imported when a command runs)."""
    from rich.console import Console

    return Console(stderr=True)
