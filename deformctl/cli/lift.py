"""``deformctl lift``: the minimum lifting force of catalog objects, by iterative lifting.

The command checks options, picks the trial runner (:mod:`deformctl.cli._lift_runner`) and
calls one library function: :func:`deformctl.lift.stage.lift_catalog_files` (a table file and a
log) or, for a dataset directory output, :func:`deformctl.lift.runners.sim.lift_sweep`; then it
turns failures into the exit code.

Failures, decided here:

* bad options (tolerance, growth, max attempts, no runner, unknown ``--objects`` id): exit 2,
  before any attempt runs and before anything is written;
* an object with ``friction_mu <= 0`` in the catalog, or (``--sim``) without material values:
  bad input data, exit 65, nothing run;
* a search that does not converge, or a rig that crashes, times out or answers garbage: the log
  (all completed attempts) and the table (a row per object, ``converged = false``, ``error``) are
  written first, then exit 1 with one line. A rig failure stops the run: the objects after it
  are not run (rows with ``attempts = 0`` and ``error`` "not run: ..."), since a rig that failed
  usually needs a person. A search that runs out of attempts does not stop the others.
* with ``--rig``, the table and the log are also kept on disk as the run goes
  (:mod:`deformctl.lift.journal`): a run killed or stopped by an error after its first attempt
  keeps every attempt and the finished objects, and its error line says so.
"""

from __future__ import annotations

from typing import Annotated, cast

import typer

from deformctl.artifacts.io import is_stdio
from deformctl.cli import _options as opt
from deformctl.cli._common import progress_bar, translate_errors, warn
from deformctl.cli._lift_frames import frames_judge
from deformctl.cli._lift_runner import (
    DebugDir,
    FrameMarkerDict,
    FrameMarkerSizeCm,
    HoldSAlias,
    LiftAccel,
    LiftHeight,
    LiftHoldS,
    LiftSpeed,
    PalmMarkerIds,
    PalmRegions,
    RigTimeout,
    SlipCriterionOption,
    SlipToleranceM,
    choose_runner,
    lift_dataset,
    sim_options,
)
from deformctl.cli._lift_start import (
    CatalogArg,
    Coefficients,
    MaxForceN,
    StartInterpolate,
    StartMargin,
    StartModel,
    StartTable,
    report_run,
    run_summary,
    start_seed,
)
from deformctl.cli._scene_options import SceneHz, scene_rate
from deformctl.cli._summary import Quiet, RunClock, stderr_console
from deformctl.errors import UsageError
from deformctl.lift.options import (
    DEFAULT_GROWTH,
    DEFAULT_MAX_ATTEMPTS,
    DEFAULT_TOLERANCE_REL,
    SearchOptions,
    SearchProtocol,
)
from deformctl.parallel import SweepOptions
from deformctl.quantities import MAX_FORCE_N


@translate_errors
@opt.with_sweep_options
def lift(
    catalog: CatalogArg,
    output: Annotated[
        str, typer.Option("-o", "--output", help="Lift results table (Parquet); - for stdout.")
    ],
    rig: Annotated[
        str | None,
        typer.Option(
            "--rig",
            help="External rig command, run once per attempt: JSON request on stdin, JSON answer "
            "on stdout (protocol: docs/rig-protocol.md).",
        ),
    ] = None,
    rig_timeout: RigTimeout = None,
    sim: Annotated[
        bool,
        typer.Option(
            "--sim", help="Run the attempts in the built-in simulator (needs material values)."
        ),
    ] = False,
    sim_preset: opt.SimPresetName = None,
    lift_accel_m_s2: LiftAccel = None,
    lift_speed_m_s: LiftSpeed = None,
    lift_height_m: LiftHeight = None,
    lift_hold_s: LiftHoldS = None,
    hold_s: HoldSAlias = None,
    slip_from_frames: Annotated[
        bool,
        typer.Option(
            "--slip-from-frames",
            help="Rig answers with before/after frames: judge lifted/slipped from them (vision).",
        ),
    ] = False,
    palm_marker_ids: PalmMarkerIds = None,
    palm_regions: PalmRegions = None,
    frame_marker_size_cm: FrameMarkerSizeCm = None,
    frame_marker_dict: FrameMarkerDict = None,
    slip_tolerance_m: SlipToleranceM = None,
    slip_criterion: SlipCriterionOption = None,
    alpha_cm: opt.AlphaCm = None,
    dt_s: opt.DtS = None,
    memory_budget_gib: opt.MemoryBudgetGib = None,
    debug_dir: DebugDir = None,
    log: Annotated[
        str | None, typer.Option("--log", help="Lift log (MCAP) with every attempt; - for stdout.")
    ] = None,
    objects: opt.Objects = None,
    protocol: Annotated[
        str,
        typer.Option(
            "--protocol",
            help="refine: the paper's ramp, then bisection to --tolerance; paper: the ramp only.",
        ),
    ] = "refine",
    growth: Annotated[
        float, typer.Option("--growth", help="Ramp factor between attempts (> 1; the paper's 1.2).")
    ] = DEFAULT_GROWTH,
    tolerance: Annotated[
        float,
        typer.Option(
            "--tolerance",
            help="refine: stop when (high - low) / high <= this, relative, in (0, 1).",
        ),
    ] = DEFAULT_TOLERANCE_REL,
    max_attempts: Annotated[
        int, typer.Option("--max-attempts", help="Most attempts per object (>= 1).")
    ] = DEFAULT_MAX_ATTEMPTS,
    max_force_n: MaxForceN = None,
    log_epoch: opt.LogEpoch = None,
    scene_hz: SceneHz = None,
    quiet: Quiet = False,
    start_model: StartModel = None,
    start_table: StartTable = None,
    start_interpolate: StartInterpolate = None,
    start_margin: StartMargin = None,
    coefficients: Coefficients = None,
    force: opt.Force = False,
    sweep: SweepOptions = opt.NO_SWEEP,
) -> None:
    """Find each object's minimum lifting force L_f by iterative lifting.

    Starts at the rigid-object force F_w = W / (2 mu) and raises the grip force by --growth
    until the object lifts (paper); refine then bisects to --tolerance. Writes one row per
    object (L_f, F_w, F_d = L_f - F_w, attempts, bracket, converged) and, with --log, every
    attempt to an MCAP log. Exit 1 when an object does not converge or the rig fails; the
    outputs are written first, keeping the attempts made so far.

    With --sim each attempt is simulated under --sim-preset (paper by default: the object starts
    stress-free on a support that gives way as the palms accelerate; table: lifted from the
    table along an S-curve): grip, rise (--lift-accel-m-s2, --lift-speed-m-s, --lift-height-m,
    hold --lift-hold-s), judge slip by --slip-criterion against --slip-tolerance-m; every row
    records the preset, the profile and the criterion.

    With --sim and a dataset directory output (-o DIR/), the objects run in parallel
    (--workers N local processes, or --scheduler tcp://HOST:PORT of a Dask cluster) into
    DIR/part-*.parquet with each part's attempts in DIR/_logs/; --resume completes an
    interrupted run. An object that fails is recorded in DIR/_failures/ and the rest go on.
    A single-file output with --sim also runs on --workers N local processes (default auto:
    workers only where they save time, measured); the rows and attempts are the same whatever N.

    With --start-model MODEL (or --start-table INDEX) each search starts at the predicted L_f ×
    --start-margin instead of at F_w, goes down (or up by --growth) until the outcome flips and
    bisects to --tolerance: the same L_f as refine in fewer attempts. D and λ come from
    --coefficients (or the catalog); an object outside the training range starts at F_w.

    Example: deformctl lift datasets/paper/objects.csv --rig "python3 examples/threshold_rig.py"
    -o lift.parquet --log lift.mcap
    """
    clock = RunClock("lift")
    dataset = sweep.check(output, file_workers=True)
    if not dataset and sweep.workers_given and not sim:
        raise UsageError(
            "--workers with a single-file output needs --sim (a rig lifts one object at a time)"
        )
    preset = sim_options(
        sim, preset_name=sim_preset, alpha_cm=alpha_cm, dt_s=dt_s,
        memory_budget_gib=memory_budget_gib, lift_accel_m_s2=lift_accel_m_s2,
        lift_speed_m_s=lift_speed_m_s, lift_height_m=lift_height_m, lift_hold_s=lift_hold_s,
        hold_s_alias=hold_s, slip_criterion=slip_criterion, log_epoch=log_epoch,
        slip_tolerance_m=slip_tolerance_m if sim else None,  # else: the frames' option
        scene_hz=scene_hz,
    )  # fmt: skip
    judge = frames_judge(
        enabled=slip_from_frames, palm_marker_ids=palm_marker_ids, palm_regions=palm_regions,
        frame_marker_size_cm=frame_marker_size_cm,
        slip_tolerance_m=None if sim else slip_tolerance_m,
        marker_dict=frame_marker_dict, debug_dir=debug_dir,
    )  # fmt: skip
    if scene_hz is not None and log is None and not dataset:
        raise UsageError("--scene-hz needs --log FILE: the scene is written into the lift log")
    # the scene goes into a log: without one, the attempts record none
    scene = scene_rate(scene_hz) if log is not None or dataset else 0.0
    factory = choose_runner(rig, rig_timeout, judge, preset, scene)
    search = SearchOptions(
        protocol=cast(SearchProtocol, protocol), growth=growth, tolerance_rel=tolerance,
        max_attempts=max_attempts,
    )  # fmt: skip
    MAX_FORCE_N.check_optional(max_force_n)  # None: the catalog's or the default ceiling
    object_ids = opt.parse_object_ids(objects)
    seed = start_seed(start_model, start_table, start_interpolate, start_margin, coefficients,
                      protocol=protocol, dataset=dataset)  # fmt: skip
    epoch_ns = opt.parse_log_epoch(log_epoch)
    if dataset:
        lift_dataset(catalog, preset, log, search, epoch_ns, scene, output, sweep, object_ids,
                     force, quiet, max_force_n=max_force_n)  # fmt: skip
        return
    from deformctl.lift.stage import lift_catalog_files

    with progress_bar(stderr_console(), "lift") as progress:
        run = lift_catalog_files(
            catalog, factory, output=output, log=log, object_ids=object_ids, search=search,
            progress=progress, force=force, log_epoch_ns=epoch_ns, seed=seed, warn=warn,
            workers=sweep.workers, max_force_n=max_force_n,
        )  # fmt: skip
    report_run(run, quiet=is_stdio(output) or (log is not None and is_stdio(log)),
               summary=None if quiet else run_summary(run, clock, output, log))  # fmt: skip
