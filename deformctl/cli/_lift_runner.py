"""``deformctl lift``: its runner options, and the one trial runner they ask for.

``--rig CMD`` (an external rig, :func:`deformctl.lift.runners.rig.rig_runner_factory`) or
``--sim`` (the simulator, :func:`deformctl.lift.runners.sim.sim_runner_factory`, built from the
lift-profile, slip and simulator options by :func:`sim_parts`). Options of a runner that was not
chosen are refused by name.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Annotated, Any

import typer

from deformctl.cli._options import HEAVY_DEFAULTS, default
from deformctl.errors import UsageError
from deformctl.lift.runners.rig import DEFAULT_RIG_TIMEOUT_S, SlipFromFrames, rig_runner_factory
from deformctl.lift.stage import RunnerFactory

if TYPE_CHECKING:  # pragma: no cover - the simulator is imported when --sim is given
    from deformctl.sim import LiftProfile, SimSettings, SlipCriterion

    SimParts = tuple[LiftProfile, SimSettings, SlipCriterion]

RigTimeout = Annotated[
    float | None,
    typer.Option(
        "--rig-timeout",
        help="Seconds one rig attempt may take before it is killed "
        f"[default: {DEFAULT_RIG_TIMEOUT_S:g}].",
    ),
]
LiftAccel = Annotated[
    float | None,
    typer.Option(
        "--lift-accel-m-s2",
        help=f"Sim: peak lift acceleration a_max, m/s² {default('LiftProfile.accel_m_s2')}.",
    ),
]
LiftSpeed = Annotated[
    float | None,
    typer.Option(
        "--lift-speed-m-s", help=f"Sim: lift cruise speed, m/s {default('LiftProfile.speed_m_s')}."
    ),
]
LiftHeight = Annotated[
    float | None,
    typer.Option("--lift-height-m", help="Sim: rise, m [default: half the object's height]."),
]
LiftHoldS = Annotated[
    float | None,
    typer.Option(
        "--lift-hold-s", help=f"Sim: hold after the rise, s {default('LiftProfile.hold_s')}."
    ),
]
#: The old spelling of ``--lift-hold-s`` (``measure``'s ``--hold-s`` is the squeeze hold).
HoldSAlias = Annotated[
    float | None, typer.Option("--hold-s", hidden=True, help="Old spelling of --lift-hold-s.")
]
PalmMarkerIds = Annotated[
    str | None,
    typer.Option(
        "--palm-marker-ids", metavar="L,R", help="Frames: ids of ArUco markers on the palms."
    ),
]
PalmRegions = Annotated[
    str | None,
    typer.Option(
        "--palm-regions",
        metavar="x,y,w,h;x,y,w,h",
        help="Frames: palm rectangles in the before frame, px (each with a distinct palm part).",
    ),
]
FrameMarkerSizeCm = Annotated[
    float | None,
    typer.Option(
        "--frame-marker-size-cm",
        metavar="S",
        help="Frames: side of the markers in view, cm (the image scale).",
    ),
]
FrameMarkerDict = Annotated[
    str | None,
    typer.Option(
        "--frame-marker-dict",
        help=f"Frames: ArUco dictionary {default('detect_slip.marker_dict')}.",
    ),
]
SlipToleranceM = Annotated[
    float | None,
    typer.Option(
        "--slip-tolerance-m",
        metavar="T",
        help=f"Slip beyond which an attempt fails, m [default: "
        f"{HEAVY_DEFAULTS['SlipCriterion.tolerance_m']:g} with --sim (contact slip), "
        f"{HEAVY_DEFAULTS['detect_slip.tolerance_m']:g} with --slip-from-frames (object "
        "behind palms)].",
    ),
]
SlipCriterionOption = Annotated[
    str | None,
    typer.Option(
        "--slip-criterion",
        metavar="contact|shortfall",
        help="Sim: contact = sliding at the palms since the rise began; shortfall = palm rise "
        f"minus object rise at the end {default('SlipCriterion.measure')}.",
    ),
]
DebugDir = Annotated[
    str | None,
    typer.Option("--debug-dir", help="Frames: write the last attempt's annotated frames here."),
]


def sim_parts(sim: bool, options: Mapping[str, Any]) -> SimParts | None:
    """The (LiftProfile, SimSettings, SlipCriterion) of ``--sim`` (None without ``--sim``).

    Args:
        sim: ``--sim`` was given.
        options: the sim options by flag (None: not given, the simulator's default applies).

    Raises:
        UsageError: a sim option without ``--sim``, or a value out of range.
    """
    if not sim:
        given = [flag for flag, value in options.items() if value is not None]
        if given:
            raise UsageError(f"{given[0]} needs --sim")
        return None
    from deformctl.sim import LiftProfile, SimSettings, SlipCriterion

    values = dict(options)
    hold = values.get("--lift-hold-s", values.get("--hold-s"))

    def pick(flag: str, fallback: Any) -> Any:
        value = hold if flag == "--lift-hold-s" else values.get(flag)
        return fallback if value is None else value

    profile = LiftProfile(
        accel_m_s2=pick("--lift-accel-m-s2", LiftProfile.accel_m_s2),
        speed_m_s=pick("--lift-speed-m-s", LiftProfile.speed_m_s),
        height_m=pick("--lift-height-m", LiftProfile.height_m),
        hold_s=pick("--lift-hold-s", LiftProfile.hold_s),
    )
    criterion = SlipCriterion(
        tolerance_m=pick("--slip-tolerance-m", SlipCriterion.tolerance_m),
        measure=pick("--slip-criterion", SlipCriterion.measure),
    )
    settings = SimSettings(
        alpha_cm=pick("--alpha-cm", SimSettings.alpha_cm),
        dt_s=pick("--dt-s", SimSettings.dt_s),
        memory_budget_gib=pick("--memory-budget-gib", SimSettings.memory_budget_gib),
    )
    return profile, settings, criterion


def choose_runner(
    rig: str | None,
    rig_timeout_s: float | None,
    judge: SlipFromFrames | None,
    sim: SimParts | None,
) -> RunnerFactory:
    """The one trial runner the options ask for (``sim``: the parts of ``--sim``, if given).

    Raises:
        UsageError: no runner, more than one, or a runner option without its runner.
    """
    chosen: list[RunnerFactory] = []
    if rig is not None:
        timeout_s = DEFAULT_RIG_TIMEOUT_S if rig_timeout_s is None else rig_timeout_s
        chosen.append(rig_runner_factory(rig, timeout_s=timeout_s, slip_from_frames=judge))
    elif rig_timeout_s is not None or judge is not None:
        raise UsageError(
            f"{'--rig-timeout' if judge is None else '--slip-from-frames'} needs --rig"
        )
    if sim is not None:
        from deformctl.lift.runners.sim import sim_runner_factory

        profile, settings, criterion = sim
        chosen.append(sim_runner_factory(profile=profile, settings=settings, criterion=criterion))
    if len(chosen) != 1:
        raise UsageError(
            "choose exactly one trial runner: --rig CMD or --sim"
            if not chosen
            else "choose exactly one trial runner (--rig or --sim)"
        )
    return chosen[0]
