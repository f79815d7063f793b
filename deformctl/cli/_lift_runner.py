"""``deformctl lift sim|rig``: the options of each trial runner, as option groups.

``lift sim`` (the simulator, :func:`deformctl.lift.runners.sim.sim_runner_factory`) takes the
simulator, lift-profile and slip options as one preset (:data:`PRESET`); ``lift rig`` (an
external rig, :func:`deformctl.lift.runners.rig.rig_runner_factory`) takes ``--rig-timeout`` and
the frame options (:data:`FRAMES`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Annotated

import typer

from deformctl.cli._common import finish_sweep
from deformctl.cli._options import SIMULATOR, OptionGroup, default
from deformctl.errors import UsageError
from deformctl.lift.options import (
    DEFAULT_GROWTH,
    DEFAULT_MAX_ATTEMPTS,
    DEFAULT_RIG_TIMEOUT_S,
    DEFAULT_TOLERANCE_REL,
    SearchOptions,
)

if TYPE_CHECKING:  # pragma: no cover - the runners (numba; pandas, MCAP) load when they run
    from deformctl.lift.runners.sim import LiftTask
    from deformctl.parallel import SweepOptions
    from deformctl.presets import SimPreset

RigTimeout = Annotated[
    float | None,
    typer.Option(
        "--rig-timeout",
        metavar="S",
        help=f"Seconds one attempt may take [default: {DEFAULT_RIG_TIMEOUT_S:g}].",
    ),
]
LiftAccel = Annotated[
    float | None,
    typer.Option(
        "--lift-accel-m-s2",
        metavar="A",
        help="Lift acceleration, m/s² [default: preset's].",
    ),
]
LiftSpeed = Annotated[
    float | None,
    typer.Option(
        "--lift-speed-m-s",
        metavar="V",
        help=f"Cruise speed, m/s {default('LiftProfile.speed_m_s')}.",
    ),
]
LiftHeight = Annotated[
    float | None,
    typer.Option("--lift-height-m", metavar="H", help="Rise, m [default: half the height]."),
]
LiftHoldS = Annotated[
    float | None,
    typer.Option(
        "--lift-hold-s", metavar="S", help="Hold after the rise, s [default: the preset's]."
    ),
]
#: The old spelling of ``--lift-hold-s`` (``measure``'s ``--hold-s`` is the squeeze hold).
HoldSAlias = Annotated[
    float | None, typer.Option("--hold-s", hidden=True, help="Old spelling of --lift-hold-s.")
]
SlipToleranceM = Annotated[
    float | None,
    typer.Option(
        "--slip-tolerance-m",
        metavar="T",
        help="Slip failing an attempt, m [default: preset's].",
    ),
]
SlipCriterionOption = Annotated[
    str | None,
    typer.Option(
        "--slip-criterion",
        metavar="CRITERION",
        help="contact (palms slid) or shortfall (palm minus object rise) "
        f"{default('SlipCriterion.measure')}.",
    ),
]


def lift_preset(
    *,
    sim_preset: str | None,
    alpha_cm: float | None,
    dt_s: float | None,
    memory_budget_gib: float | None,
    lift_accel_m_s2: float | None,
    lift_speed_m_s: float | None,
    lift_height_m: float | None,
    lift_hold_s: float | None,
    hold_s: float | None,
    slip_tolerance_m: float | None,
    slip_criterion: str | None,
) -> SimPreset:
    """The simulator preset of ``lift sim`` with the single options given (None: not given, the
    preset's value applies; ``hold_s`` is ``--hold-s``, the old spelling of ``--lift-hold-s``).

    Raises:
        UsageError: both spellings of the hold, an unknown preset, or a value out of range (the
            simulator's settings types check each, when the preset is built).
    """
    if lift_hold_s is not None and hold_s is not None:
        raise UsageError("give --lift-hold-s (or its old spelling --hold-s), not both")
    from deformctl.presets import DEFAULT_PRESET, SimOptions

    return SimOptions(
        preset_name=sim_preset or DEFAULT_PRESET,
        alpha_cm=alpha_cm,
        dt_s=dt_s,
        memory_budget_gib=memory_budget_gib,
        lift_accel_m_s2=lift_accel_m_s2,
        lift_speed_m_s=lift_speed_m_s,
        lift_height_m=lift_height_m,
        lift_hold_s=lift_hold_s if lift_hold_s is not None else hold_s,
        slip_tolerance_m=slip_tolerance_m,
        slip_criterion=slip_criterion,
    ).preset()


#: The simulator, lift-profile and slip options of ``lift sim`` as one ``SimPreset``.
PRESET = OptionGroup(
    "preset",
    (
        *SIMULATOR,
        ("lift_accel_m_s2", LiftAccel, None),
        ("lift_speed_m_s", LiftSpeed, None),
        ("lift_height_m", LiftHeight, None),
        ("lift_hold_s", LiftHoldS, None),
        ("hold_s", HoldSAlias, None),
        ("slip_tolerance_m", SlipToleranceM, None),
        ("slip_criterion", SlipCriterionOption, None),
    ),
    lift_preset,
)


Protocol = Annotated[
    str,
    typer.Option(
        "--protocol",
        metavar="refine|paper",
        show_default=False,
        help="paper: ramp by --growth; refine: then bisect [default: refine].",
    ),
]
Growth = Annotated[
    float,
    typer.Option(
        "--growth",
        metavar="G",
        show_default=False,
        help=f"Ramp factor, > 1 [default: {DEFAULT_GROWTH:g}].",
    ),
]
Tolerance = Annotated[
    float,
    typer.Option(
        "--tolerance",
        metavar="T",
        show_default=False,
        help=f"refine: relative bracket [default: {DEFAULT_TOLERANCE_REL:g}].",
    ),
]
MaxAttempts = Annotated[
    int, typer.Option("--max-attempts", metavar="N", help="Most attempts per object.")
]
MaxForceN = Annotated[
    float | None,
    typer.Option(
        "--max-force-n",
        metavar="N",
        help="Force ceiling per palm, N [default: the catalog's max_force_n, else 10 x F_w "
        "or a known rupture force]; with a rig never above its stated maximum (else 500 N).",
    ),
]


def _search(
    *, protocol: str, growth: float, tolerance: float, max_attempts: int, max_force_n: float | None
) -> SearchOptions:
    return SearchOptions(
        protocol=protocol,  # type: ignore[arg-type]  # checked by SearchOptions
        growth=growth,
        tolerance_rel=tolerance,
        max_attempts=max_attempts,
        max_force_n=max_force_n,
    )


#: ``--protocol``, ``--growth``, ``--tolerance``, ``--max-attempts``, ``--max-force-n`` as one
#: ``SearchOptions``.
SEARCH = OptionGroup(
    "search",
    (
        ("protocol", Protocol, "refine"),
        ("growth", Growth, DEFAULT_GROWTH),
        ("tolerance", Tolerance, DEFAULT_TOLERANCE_REL),
        ("max_attempts", MaxAttempts, DEFAULT_MAX_ATTEMPTS),
        ("max_force_n", MaxForceN, None),
    ),
    _search,
)


def lift_dataset(
    catalog: str,
    task: LiftTask,
    output: str,
    sweep: SweepOptions,
    *,
    object_ids: Sequence[str] | None,
    force: bool,
    quiet: bool = False,
) -> None:
    """``lift sim -o DIR/``: every object's search (:class:`~deformctl.lift.runners.sim.LiftTask`:
    the preset, the search under its force ceiling, the logs' epoch and scene rate) through the
    sweep executor, then its summary (unless ``quiet``)."""
    from deformctl.lift.runners.sim import lift_sweep

    summary = lift_sweep(
        catalog, task, output=output, sweep=sweep, object_ids=object_ids, force=force
    )
    finish_sweep(summary, "lift", quiet=quiet)
