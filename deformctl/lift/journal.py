"""No lost attempts: a rig run's table and log kept on disk as the run goes.

An attempt on a real rig costs a grip, a lift, a check and a reset, and it cannot be made again
for free. So a run whose runner asks for it (:attr:`~deformctl.lift.stage.RunnerFactory.journal`,
the external rig) keeps its outputs on disk while it runs, instead of writing them once at the
end:

* the **lift log** is rewritten after every attempt, with every attempt made so far;
* the **results table** is rewritten at the same time: the rows of the objects that finished,
  a row for the object being searched (``attempts`` so far, ``error`` starting with
  ``incomplete``) and a row for each object not reached yet (``attempts = 0``, ``error``
  starting with ``not run``).

Each rewrite is atomic (:func:`~deformctl.artifacts.io.atomic_output`: a temporary file renamed
into place), so at every moment both files are complete, readable artifacts. Whatever ends the
run (a kill, a power cut, a refused value, a bug), the attempts made are in the log and the
objects that finished are in the table. An attempt is written when its answer arrives: one whose
rig command was still running when the run died has no outcome to record.

The first write comes with the first attempt's answer: a run refused before any attempt
(a bad option, a bad catalog) writes nothing. Outputs on stdout (``-``) cannot be rewritten and
are written once, at the end, as before. The run's final write (``lift_catalog_files``) replaces
the journal's files with the finished ones.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import pandas as pd

from deformctl.artifacts import Provenance, validate_frame, write_lift_log, write_table
from deformctl.artifacts.io import is_stdio
from deformctl.series import LiftAttempt

__all__ = ["INCOMPLETE", "NOT_RUN_YET", "LiftJournal"]

#: ``error`` of the row of an object whose search was under way when the run ended.
INCOMPLETE = (
    "incomplete: the run ended during this object's search after {n} attempt{s} "
    "(every one is in the lift log)"
)
#: ``error`` of the row of an object the run had not reached when it ended.
NOT_RUN_YET = "not run: the run ended before this object"


@dataclass
class LiftJournal:
    """The on-disk state of a running lift (module docstring).

    Attributes:
        output: the results table path (``-``: not journaled).
        log: the lift log path, or None (``-``: not journaled).
        provenance: stored in both files.
        log_epoch: keyword arguments of :func:`~deformctl.artifacts.write_lift_log`
            (``epoch_ns``).
        objects: the catalog rows of every object of the run, for the log (:meth:`begin`).
        placeholder: ``placeholder(index, error, attempts) -> row``: the table row of object
            ``index`` that has no result yet (:meth:`begin`).
    """

    output: str
    log: str | None
    provenance: Provenance | None
    log_epoch: Mapping[str, int] = field(default_factory=dict)
    objects: Sequence[Mapping[str, Any]] = ()
    placeholder: Callable[[int, str, int], dict[str, object]] | None = None
    _rows: dict[int, dict[str, object]] = field(default_factory=dict)
    _attempts: list[LiftAttempt] = field(default_factory=list)
    _current: tuple[int, int] | None = None  # (object index, attempts so far)
    _log_written: int = -1  # attempts in the log file on disk (-1: none written)
    _table_written: int = -1  # finished objects in the table on disk (-1: none written)

    @property
    def active(self) -> bool:
        """True when at least one output is a file (stdout cannot be rewritten)."""
        return not is_stdio(self.output) or (self.log is not None and not is_stdio(self.log))

    @property
    def written(self) -> bool:
        """True once a file is on disk."""
        return self._log_written >= 0 or self._table_written >= 0

    @property
    def attempts(self) -> int:
        """Attempts recorded so far."""
        return len(self._attempts)

    @property
    def finished(self) -> int:
        """Objects whose row is final."""
        return len(self._rows)

    def begin(
        self,
        objects: Sequence[Mapping[str, Any]],
        placeholder: Callable[[int, str, int], dict[str, object]],
    ) -> None:
        """The run's objects are known (nothing is written yet)."""
        self.objects = objects
        self.placeholder = placeholder

    def start_object(self, index: int) -> None:
        """Object ``index`` (its place in :attr:`objects`) is about to be searched."""
        self._current = (index, 0)

    def attempt(self, attempt: LiftAttempt) -> None:
        """One attempt's answer arrived: record it and rewrite both files."""
        self._attempts.append(attempt)
        if self._current is not None:
            self._current = (self._current[0], self._current[1] + 1)
        self.write()

    def object_done(self, index: int, row: dict[str, object]) -> None:
        """Object ``index`` finished with ``row`` (already validated); rewrite the table."""
        self._rows[index] = row
        self._current = None
        if self.written:  # nothing on disk before the first attempt: keep it that way
            self.write()

    def table(self) -> pd.DataFrame:
        """The table as it stands: final rows, the current object's, the objects not reached."""
        assert self.placeholder is not None, "begin() first"
        rows = []
        for i in range(len(self.objects)):
            if i in self._rows:
                rows.append(self._rows[i])
            elif self._current is not None and self._current[0] == i:
                n = self._current[1]
                rows.append(self.placeholder(i, INCOMPLETE.format(n=n, s="" if n == 1 else "s"), n))
            else:
                rows.append(self.placeholder(i, NOT_RUN_YET, 0))
        return validate_frame(pd.DataFrame(rows), "lift_results")

    def write(self) -> None:
        """Rewrite the log (when it is a file), then the table (when it is a file)."""
        if not self.active:
            return
        if self.log is not None and not is_stdio(self.log):
            write_lift_log(
                self.log,
                self.objects,
                self._attempts,
                provenance=self.provenance,
                force=True,
                **self.log_epoch,
            )
            self._log_written = len(self._attempts)
        if not is_stdio(self.output):
            write_table(
                self.table(), self.output, "lift_results", provenance=self.provenance, force=True
            )
            self._table_written = len(self._rows)

    def kept(self) -> str:
        """What the files on disk hold, for an error line: ``"kept: ..."``."""
        where = []
        if self._log_written >= 0:
            n = self._log_written
            where.append(f"{n} attempt{'' if n == 1 else 's'} in {self.log}")
        if self._table_written >= 0:
            n = self._table_written
            where.append(f"{n} finished object{'' if n == 1 else 's'} in {self.output}")
        return "kept: " + ", ".join(where)
