"""A squeeze's phases (``--phase``): up to its peak force, down from it, or the whole squeeze.

``measure`` keeps the phase asked for and ``characterize`` fits it; the cut itself is
:func:`deformctl.squeeze.rupture.phase_slice`.
"""

from __future__ import annotations

from typing import Literal

from deformctl.errors import UsageError

#: A squeeze's phases (``--phase``): up to its peak force, down from it, or the whole squeeze.
Phase = Literal["loading", "unloading", "all"]
PHASES: tuple[str, ...] = ("loading", "unloading", "all")


def check_phase(phase: object) -> Phase:
    """``phase`` when it is one of :data:`PHASES` (the one rule for ``--phase``).

    Raises:
        UsageError: an unknown phase (exit 2).
    """
    if phase not in PHASES:
        raise UsageError(f"--phase must be one of {', '.join(PHASES)}, got {phase!r}")
    return phase  # type: ignore[return-value]
