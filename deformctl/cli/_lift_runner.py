"""``deformctl lift``: its runner options, and the one trial runner they ask for.

``--rig CMD`` (an external rig, :func:`deformctl.lift.runners.rig.rig_runner_factory`) or
``--sim`` (the simulator, :func:`deformctl.lift.runners.sim.sim_runner_factory`, built from the
lift-profile, slip and simulator options by :func:`sim_options`). Options of a runner that was not
chosen are refused by name.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Annotated

import typer

from deformctl.cli._common import finish_sweep
from deformctl.cli._options import HEAVY_DEFAULTS, default
from deformctl.errors import UsageError
from deformctl.lift.options import DEFAULT_RIG_TIMEOUT_S, SearchOptions

if TYPE_CHECKING:  # pragma: no cover - the runners (numba; pandas, MCAP) load when they run
    from deformctl.lift.runners.rig import SlipFromFrames
    from deformctl.lift.stage import RunnerFactory
    from deformctl.parallel import SweepOptions
    from deformctl.presets import SimPreset

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
        help="Sim: peak lift acceleration a_max, m/s² [default: the preset's; paper: calibrated "
        f"(datasets/calibration/paper.json), table: {HEAVY_DEFAULTS['LiftProfile.accel_m_s2']:g}].",
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
        "--lift-hold-s",
        help="Sim: hold after the rise, s [default: the preset's; paper 0.3, table "
        f"{HEAVY_DEFAULTS['LiftProfile.hold_s']:g}].",
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
        help="Slip beyond which an attempt fails, m [default with --sim: the preset's, paper "
        f"1e-06 (any slip), table {HEAVY_DEFAULTS['SlipCriterion.tolerance_m']:g} (contact slip); "
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


def sim_options(
    sim: bool,
    *,
    preset_name: str | None,
    alpha_cm: float | None,
    dt_s: float | None,
    memory_budget_gib: float | None,
    lift_accel_m_s2: float | None,
    lift_speed_m_s: float | None,
    lift_height_m: float | None,
    lift_hold_s: float | None,
    hold_s_alias: float | None,
    slip_tolerance_m: float | None,
    slip_criterion: str | None,
    log_epoch: str | None,
    scene_hz: float | None = None,
) -> SimPreset | None:
    """The simulator preset of ``--sim`` with the single options given (None without ``--sim``).

    Args:
        sim: ``--sim`` was given.
        preset_name ... slip_criterion: :class:`~deformctl.presets.SimOptions`'s fields as given
            (None: not given, the preset's value applies); ``hold_s_alias`` is ``--hold-s``,
            the old spelling of ``--lift-hold-s``.
        log_epoch, scene_hz: ``--log-epoch`` and ``--scene-hz``, which only a simulated run
            takes (checked where they are used).

    Raises:
        UsageError: a sim option without ``--sim``, an unknown preset, or a value out of range
            (the simulator's settings types check each, when the preset is built).
    """
    if lift_hold_s is not None and hold_s_alias is not None:
        raise UsageError("give --lift-hold-s (or its old spelling --hold-s), not both")
    hold = lift_hold_s if lift_hold_s is not None else hold_s_alias
    given = [
        ("--lift-accel-m-s2", lift_accel_m_s2), ("--lift-speed-m-s", lift_speed_m_s),
        ("--lift-height-m", lift_height_m),
        ("--hold-s" if hold_s_alias is not None else "--lift-hold-s", hold),
        ("--slip-tolerance-m", slip_tolerance_m), ("--slip-criterion", slip_criterion),
        ("--sim-preset", preset_name), ("--alpha-cm", alpha_cm), ("--dt-s", dt_s),
        ("--memory-budget-gib", memory_budget_gib), ("--log-epoch", log_epoch),
        ("--scene-hz", scene_hz),
    ]  # fmt: skip
    if not sim:
        for flag, value in given:
            if value is not None:
                raise UsageError(f"{flag} needs --sim")
        return None
    from deformctl.presets import DEFAULT_PRESET, SimOptions

    return SimOptions(
        preset_name=preset_name or DEFAULT_PRESET,
        alpha_cm=alpha_cm,
        dt_s=dt_s,
        memory_budget_gib=memory_budget_gib,
        lift_accel_m_s2=lift_accel_m_s2,
        lift_speed_m_s=lift_speed_m_s,
        lift_height_m=lift_height_m,
        lift_hold_s=hold,
        slip_tolerance_m=slip_tolerance_m,
        slip_criterion=slip_criterion,
    ).preset()


def choose_runner(
    rig: str | None,
    rig_timeout_s: float | None,
    judge: SlipFromFrames | None,
    sim: SimPreset | None,
    scene_hz: float = 0.0,
) -> RunnerFactory:
    """The one trial runner the options ask for (``sim``: the parts of ``--sim``, if given, with
    its scene at ``scene_hz``).

    Raises:
        UsageError: no runner, more than one, or a runner option without its runner.
    """
    chosen: list[RunnerFactory] = []
    if rig is not None:
        from deformctl.lift.runners.rig import rig_runner_factory as rig_factory

        timeout_s = DEFAULT_RIG_TIMEOUT_S if rig_timeout_s is None else rig_timeout_s
        chosen.append(rig_factory(rig, timeout_s=timeout_s, slip_from_frames=judge))
    elif rig_timeout_s is not None or judge is not None:
        raise UsageError(
            f"{'--rig-timeout' if judge is None else '--slip-from-frames'} needs --rig"
        )
    if sim is not None:
        from deformctl.lift.runners.sim import sim_runner_factory

        chosen.append(sim_runner_factory(preset=sim, scene_hz=scene_hz))
    if len(chosen) != 1:
        raise UsageError(
            "choose exactly one trial runner: --rig CMD or --sim"
            if not chosen
            else "choose exactly one trial runner (--rig or --sim)"
        )
    return chosen[0]


def lift_dataset(
    catalog: str,
    preset: SimPreset | None,
    log: str | None,
    search: SearchOptions,
    log_epoch_ns: int | None,
    scene_hz: float,
    output: str,
    sweep: SweepOptions,
    object_ids: Sequence[str] | None,
    force: bool,
    quiet: bool = False,
    max_force_n: float | None = None,
) -> None:
    """``lift --sim -o DIR/``: every object's search (under its force ceiling) through the sweep
    executor, then its summary (unless ``quiet``); each part's log has the scene at ``scene_hz``.

    Raises:
        UsageError: no ``--sim``, or ``--log`` (each part has its log).
    """
    if preset is None:
        raise UsageError("a dataset directory output (-o DIR/) needs --sim")
    if log is not None:
        raise UsageError("--log is not used with a dataset directory output (DIR/_logs/ has them)")
    from deformctl.lift.runners.sim import LiftTask, lift_sweep

    task = LiftTask(preset=preset, search=search, log_epoch_ns=log_epoch_ns, scene_hz=scene_hz,
                    max_force_n=max_force_n)  # fmt: skip
    summary = lift_sweep(catalog, task, output=output, sweep=sweep, object_ids=object_ids,
                         force=force)  # fmt: skip
    finish_sweep(summary, "lift", quiet=quiet)
