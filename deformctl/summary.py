"""The one line a long run ends with: objects done, flagged, failed, wall time and where the
output went (``deformctl measure --sim``, ``characterize``, ``lift``, ``train`` and ``make
calibrate``); the commands' ``--quiet`` drops it (warnings and errors still print)."""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field


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
            line = self.line(
                done=done, flagged=flagged, failed=failed, output=output, detail=detail
            )
            print(line, file=sys.stderr, flush=True)
