"""The options more than one command takes, declared once as ``Annotated`` aliases.

Help texts state defaults taken from the library, not typed in: the search
(:mod:`deformctl.lift.search`), the sweep executor (:mod:`deformctl.parallel`), the squeeze
protocol (:mod:`deformctl.measure`) and the rig runner. The simulator's and OpenCV's defaults are
restated in :data:`HEAVY_DEFAULTS`, because importing numba or OpenCV costs the command line half
a second at start-up; ``tests/test_layout.py`` checks each of them against the library
object it restates, so they cannot drift.

An option whose value is ``None`` was not given; the library default then applies. Options that
travel together are handed to a command as the one value they build
(:mod:`deformctl.cli._option_groups`, re-exported here: the five sweep options as one
:class:`~deformctl.parallel.SweepOptions`, :data:`SIMULATOR` the simulator's).
"""

from __future__ import annotations

from typing import Annotated, Any

import typer

from deformctl.cli._option_groups import (
    NO_SWEEP,
    SWEEP,
    OptionGroup,
    with_options,
    with_sweep_options,
)
from deformctl.errors import UsageError

#: Defaults of the simulator (``SimSettings``, ``LiftProfile``, ``SlipCriterion``, the scene rate
#: of ``simulate_squeezes``: :data:`deformctl.scene.DEFAULT_SCENE_HZ`) and of the vision
#: functions (``detect_slip``, ``measure_object_size``), restated for the help texts only.
HEAVY_DEFAULTS: dict[str, object] = {
    "SimSettings.dt_s": 1e-3,
    "SimSettings.particles_per_side": 5,
    "SimSettings.memory_budget_gib": 2.0,
    "LiftProfile.accel_m_s2": 2.0,
    "LiftProfile.speed_m_s": 0.25,
    "LiftProfile.hold_s": 0.5,
    "SlipCriterion.tolerance_m": 0.5e-3,
    "SlipCriterion.measure": "contact",
    "detect_slip.tolerance_m": 0.005,
    "detect_slip.marker_dict": "DICT_4X4_50",
    "measure_object_size.marker_dict": "DICT_4X4_50",
    "simulate_squeezes.scene_hz": 30.0,
}


def default(name: str) -> str:
    """``[default: X]`` for a restated default (``name`` as in :data:`HEAVY_DEFAULTS`)."""
    value = HEAVY_DEFAULTS[name]
    return f"[default: {value:g}]" if isinstance(value, float) else f"[default: {value}]"


_PARTICLES = int(str(HEAVY_DEFAULTS["SimSettings.particles_per_side"]))
_PAPER_PARTICLES = 7  #: deformctl.presets.PAPER_FIXED["particles_per_side"] (checked by a test)


# ---------------------------------------------------------------------------- every writer

Force = Annotated[bool, typer.Option("--force", help="Overwrite existing outputs.")]
LogEpoch = Annotated[
    str | None,
    typer.Option(
        "--log-epoch",
        metavar="TIME",
        help="Start of the log's clock, ISO 8601 or Unix s [default: 2000-01-01T00:00:00Z].",
    ),
]
#: 2500-01-01T00:00:00Z: the latest epoch accepted (MCAP log times are unsigned 64-bit ns, which
#: end in 2554, and a log laid end to end from the epoch must still fit)
_LAST_EPOCH_S = 16_725_225_600


def parse_log_epoch(text: str | None) -> int | None:
    """``--log-epoch`` in ns since the Unix epoch (None: not given).

    Raises:
        UsageError: neither a number of seconds nor an ISO 8601 time, or a time before 1970
            or too late for a log's unsigned 64-bit nanoseconds.
    """
    import datetime
    import math

    if text is None:
        return None
    try:
        seconds = float(text)
    except ValueError:
        try:
            stamp = datetime.datetime.fromisoformat(text)
        except ValueError:
            raise UsageError(
                f"--log-epoch must be an ISO 8601 time or seconds since 1970, got {text!r}"
            ) from None
        if stamp.tzinfo is None:
            stamp = stamp.replace(tzinfo=datetime.UTC)
        delta = stamp - datetime.datetime(1970, 1, 1, tzinfo=datetime.UTC)
        ns = (delta.days * 86_400 + delta.seconds) * 1_000_000_000 + delta.microseconds * 1_000
    else:
        if not math.isfinite(seconds):
            raise UsageError(f"--log-epoch must be a finite time, got {text!r}")
        ns = round(seconds * 1_000_000_000)
    if not 0 <= ns <= _LAST_EPOCH_S * 1_000_000_000:
        raise UsageError(f"--log-epoch must lie between 1970 and 2500, got {text!r}")
    return ns


# ---------------------------------------------------------------------------- the simulator

SimPresetName = Annotated[
    str | None,
    typer.Option(
        "--sim-preset",
        metavar="paper|table",
        help="Object model and lift: paper (calibrated) or table [default: paper].",
    ),
]

AlphaCm = Annotated[
    float | None,
    typer.Option(
        "--alpha-cm",
        metavar="CM",
        help=f"Lattice spacing, cm [default: the longest side / {_PAPER_PARTICLES - 1} (paper), "
        f"/ {_PARTICLES - 1} (table)].",
    ),
]
DtS = Annotated[
    float | None,
    typer.Option("--dt-s", metavar="S", help=f"Time step, s {default('SimSettings.dt_s')}."),
]
MemoryBudgetGib = Annotated[
    float | None,
    typer.Option(
        "--memory-budget-gib",
        metavar="GIB",
        help=f"Largest lattice memory, GiB {default('SimSettings.memory_budget_gib')}.",
    ),
]
Objects = Annotated[
    str | None,
    typer.Option("--objects", metavar="ID,...", help="Only these catalog objects, in order."),
]


def parse_object_ids(text: str | None) -> list[str] | None:
    """``--objects A,C``: the ids, in order; None when the option was not given.

    Raises:
        UsageError: no id, or an empty one.
    """
    if text is None:
        return None
    ids = [part.strip() for part in text.split(",")]
    if not any(ids):
        raise UsageError("--objects needs at least one object id")
    if any(not oid for oid in ids):
        raise UsageError(f"--objects has an empty id: {text!r}")
    return ids


#: :data:`deformctl.scene.DEFAULT_SCENE_HZ`, restated (the scene module imports numpy).
DEFAULT_SCENE_HZ = float(str(HEAVY_DEFAULTS["simulate_squeezes.scene_hz"]))

SceneHz = Annotated[
    float | None,
    typer.Option(
        "--scene-hz",
        metavar="HZ",
        help="Frames per simulated s of the log's 3-D scene; 0: none "
        f"{default('simulate_squeezes.scene_hz')}.",
    ),
]


def scene_rate(value: float | None) -> float:
    """The rate ``--scene-hz`` asks for (its default when not given); checked by the options type
    built with it (:func:`deformctl.scene.check_scene_hz`)."""
    return DEFAULT_SCENE_HZ if value is None else float(value)


#: The simulator options ``measure sim`` and ``lift sim`` share: (parameter, alias, default).
SIMULATOR: tuple[tuple[str, Any, Any], ...] = (
    ("sim_preset", SimPresetName, None),
    ("alpha_cm", AlphaCm, None),
    ("dt_s", DtS, None),
    ("memory_budget_gib", MemoryBudgetGib, None),
)


__all__ = ["NO_SWEEP", "SWEEP", "OptionGroup", "with_options", "with_sweep_options"]
