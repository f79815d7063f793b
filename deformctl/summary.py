"""The one line a long run ends with: objects done, flagged, failed, wall time and where the
output went (``deformctl measure --sim``, ``characterize``, ``lift``, ``train`` and ``make
calibrate``), with what ``--workers auto`` chose meanwhile; the commands' ``--quiet`` drops it
(warnings and errors still print)."""

from __future__ import annotations

import logging
import sys
import time
from dataclasses import dataclass, field
from typing import Any

#: The logger :func:`deformctl.parallel.map_in_order` tells its ``--workers auto`` choice on.
_PARALLEL_LOG = logging.getLogger("deformctl.parallel")


class _ChoiceCatcher(logging.Handler):
    """Keeps the :class:`~deformctl.parallel.auto.WorkerChoice` records of one run."""

    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.choices: list[Any] = []

    def emit(self, record: logging.LogRecord) -> None:
        choice = getattr(record, "worker_choice", None)
        if choice is not None:
            self.choices.append(choice)


@dataclass
class RunClock:
    """Started when a command starts its work; :meth:`line` is its summary at the end, with
    the ``--workers auto`` choice made meanwhile (if any)."""

    command: str
    started_s: float = field(default_factory=time.monotonic)
    _catcher: _ChoiceCatcher = field(default_factory=_ChoiceCatcher, repr=False)

    def __post_init__(self) -> None:
        for old in [h for h in _PARALLEL_LOG.handlers if isinstance(h, _ChoiceCatcher)]:
            _PARALLEL_LOG.removeHandler(old)  # a run that ended with an error left it
        _PARALLEL_LOG.addHandler(self._catcher)
        if _PARALLEL_LOG.getEffectiveLevel() > logging.INFO:
            _PARALLEL_LOG.setLevel(logging.INFO)

    def workers_note(self) -> str:
        """What ``--workers auto`` chose during the run ("" when it chose nothing)."""
        _PARALLEL_LOG.removeHandler(self._catcher)
        return "; ".join(c.note() for c in self._catcher.choices)

    def line(self, *, done: int, flagged: int, failed: int, output: str, detail: str = "") -> str:
        """``lift: 4 object(s) done, 1 flagged, 0 failed in 12.3 s -> lift.parquet``, then
        ``detail`` in parentheses when given."""
        wall_s = time.monotonic() - self.started_s
        text = (
            f"{self.command}: {done} object(s) done, {flagged} flagged, {failed} failed in "
            f"{wall_s:.1f} s -> {output}"
        )
        detail = "; ".join(d for d in (detail, self.workers_note()) if d)
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
