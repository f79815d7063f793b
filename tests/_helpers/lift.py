"""Helpers of the lift tests: a threshold runner with a known answer and the ``lift --rig`` CLI.

:class:`ThresholdRunner` lifts iff the grip force is at least its threshold, so the true minimum
lifting force is max(T, F_w). :func:`rig` builds the ``--rig`` string of a scripted rig in
``tests/rigs/`` (``threshold_rig.py`` lifts iff the grip force >= :data:`THRESHOLD_N`);
:func:`run` runs ``deformctl lift``; :func:`one_line_error` checks the single error line.
"""

from __future__ import annotations

import shlex
import sys
from pathlib import Path
from typing import Any

from typer.testing import CliRunner

from deformctl.cli import app
from deformctl.series import TrialOutcome

cli = CliRunner()
RIGS = Path(__file__).resolve().parents[1] / "rigs"
SLIP_WHEN_DROPPED_M = 0.05


class ThresholdRunner:
    """Lifts iff grip_force_n >= threshold_n; records every call."""

    def __init__(self, threshold_n: float) -> None:
        self.threshold_n = threshold_n
        self.calls: list[tuple[float, int]] = []

    def __call__(self, grip_force_n: float, attempt_index: int, /) -> TrialOutcome:
        self.calls.append((grip_force_n, attempt_index))
        lifted = grip_force_n >= self.threshold_n
        return TrialOutcome(grip_force_n, lifted, 0.0 if lifted else SLIP_WHEN_DROPPED_M)


HEADER = "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu\n"


THRESHOLD_N = 17.0  # every object lifts iff the grip force >= 17 N (tests/rigs/threshold_rig.py)


def rig(name: str, *args: object) -> str:
    """The --rig string running a scripted rig with this interpreter."""
    return shlex.join([sys.executable, str(RIGS / name), *map(str, args)])


def run(*args: object) -> Any:
    return cli.invoke(app, ["lift", *map(str, args)])


def one_line_error(result: Any) -> str:
    """The single ``error: ...`` line on stderr."""
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("error: ")
    return str(lines[0])


def listing(directory: Path) -> list[str]:
    return sorted(p.name for p in directory.iterdir())
