"""``deformctl lift``: the minimum lifting force of catalog objects, by iterative lifting.

The command checks options and paths, picks the trial runner, and hands the work to
:func:`deformctl.lift.stage.lift_catalog`; then it writes the lift log (every attempt) and the
lift_results table, and turns failures into the exit code.

Runners: exactly one must be chosen: ``--rig "CMD"`` (an external rig command) or ``--sim``
(the built-in simulator, with its lift-profile, slip and simulator options, built by
:func:`_sim_factory`); each runner kind is a :class:`deformctl.lift.stage.RunnerFactory`.

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
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from typing import Any, cast

import typer
from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
)

from deformctl.artifacts import (
    Provenance,
    check_output_path,
    read_catalog,
    write_lift_log,
    write_table,
)
from deformctl.artifacts.io import is_stdio
from deformctl.catalog import select_objects
from deformctl.cli import _sweep, app
from deformctl.cli._common import translate_errors
from deformctl.cli._lift_frames import DEFAULT_SLIP_TOLERANCE_M, frames_judge
from deformctl.errors import SearchError, UsageError
from deformctl.lift.runners.rig import SlipFromFrames, rig_runner_factory
from deformctl.lift.search import (
    DEFAULT_GROWTH,
    DEFAULT_MAX_ATTEMPTS,
    DEFAULT_TOLERANCE_REL,
    SearchProtocol,
    validate_search_options,
)
from deformctl.lift.stage import LiftProgress, RunnerFactory, lift_catalog

DEFAULT_RIG_TIMEOUT_S = 60.0


def _sim_factory(sim: bool, options: Mapping[str, Any]) -> RunnerFactory | None:
    """The simulator runner when ``--sim`` is given (None otherwise).

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
    from deformctl.lift.runners.sim import sim_runner_factory

    profile, settings, criterion = _sim_parts(options)
    return sim_runner_factory(profile=profile, settings=settings, criterion=criterion)


def _sim_parts(options: Mapping[str, Any]) -> tuple[Any, Any, Any]:
    """The (LiftProfile, SimSettings, SlipCriterion) of the sim options (None: default)."""
    from deformctl.sim import LiftProfile, SimSettings, SlipCriterion

    def pick(flag: str, default: Any) -> Any:
        value = options.get(flag)
        return default if value is None else value

    profile = LiftProfile(
        accel_m_s2=pick("--lift-accel-m-s2", LiftProfile.accel_m_s2),
        speed_m_s=pick("--lift-speed-m-s", LiftProfile.speed_m_s),
        height_m=pick("--lift-height-m", LiftProfile.height_m),
        hold_s=pick("--hold-s", LiftProfile.hold_s),
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


def _choose_runner(
    rig: str | None,
    rig_timeout_s: float | None,
    judge: SlipFromFrames | None = None,
    sim: RunnerFactory | None = None,
) -> RunnerFactory:
    """The one trial runner the options ask for (``sim``: the factory of ``--sim``, if given).

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
        chosen.append(sim)
    if len(chosen) != 1:
        raise UsageError(
            "choose exactly one trial runner: --rig CMD or --sim"
            if not chosen
            else "choose exactly one trial runner (--rig or --sim)"
        )
    return chosen[0]


def _parse_objects(objects: str | None) -> list[str] | None:
    if objects is None:
        return None
    ids = [part.strip() for part in objects.split(",")]
    if not any(ids):
        raise UsageError("--objects needs at least one object id")
    if any(not oid for oid in ids):
        raise UsageError(f"--objects has an empty id: {objects!r}")
    return ids


def _check_outputs(output: str, log: str | None, force: bool) -> None:
    if log is not None:
        if is_stdio(output) and is_stdio(log):
            raise UsageError("-o and --log cannot both be - (stdout)")
        if not is_stdio(log) and os.path.abspath(log) == os.path.abspath(output):
            raise UsageError(f"-o and --log are the same file: {log!r}")
        check_output_path(log, force)
    check_output_path(output, force)


@contextmanager
def _progress_bar(total: int) -> Iterator[LiftProgress | None]:
    """A rich progress bar on stderr for a multi-object run; nothing when stderr is no TTY."""
    console = Console(stderr=True)
    if total < 2 or not console.is_terminal:
        yield None
        return
    with Progress(
        TextColumn("lift {task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=console,
        transient=True,
    ) as bar:
        task = bar.add_task("", total=total)

        def advance(object_id: str, done: int, total_objects: int) -> None:
            bar.update(task, completed=done, description=object_id)

        yield advance


@app.command()
@translate_errors
def lift(
    catalog: str = typer.Argument(..., help="Object catalog, CSV or Parquet; - for stdin."),
    output: str = typer.Option(
        ..., "-o", "--output", help="Lift results table (Parquet); - for stdout."
    ),
    rig: str | None = typer.Option(
        None,
        "--rig",
        help="External rig command, run once per attempt: JSON request on stdin, JSON answer "
        "on stdout (protocol: docs/rig-protocol.md).",
    ),
    rig_timeout: float | None = typer.Option(
        None,
        "--rig-timeout",
        help=f"Seconds one rig attempt may take before it is killed [default: "
        f"{DEFAULT_RIG_TIMEOUT_S:g}].",
    ),
    sim: bool = typer.Option(
        False, "--sim", help="Run the attempts in the built-in simulator (needs material values)."
    ),
    lift_accel_m_s2: float | None = typer.Option(
        None, "--lift-accel-m-s2", help="Sim: peak lift acceleration a_max, m/s² [default: 2]."
    ),
    lift_speed_m_s: float | None = typer.Option(
        None, "--lift-speed-m-s", help="Sim: lift cruise speed, m/s [default: 0.25]."
    ),
    lift_height_m: float | None = typer.Option(
        None, "--lift-height-m", help="Sim: rise, m [default: half the object's height]."
    ),
    hold_s: float | None = typer.Option(
        None, "--hold-s", help="Sim: hold after the rise, s [default: 0.5]."
    ),
    slip_from_frames: bool = typer.Option(
        False,
        "--slip-from-frames",
        help="Rig answers with before/after frames: judge lifted/slipped from them (vision).",
    ),
    palm_marker_ids: str | None = typer.Option(
        None, "--palm-marker-ids", metavar="L,R", help="Frames: ids of ArUco markers on the palms."
    ),
    palm_regions: str | None = typer.Option(
        None,
        "--palm-regions",
        metavar="x,y,w,h;x,y,w,h",
        help="Frames: palm rectangles in the before frame, px (each with a distinct palm part).",
    ),
    frame_marker_size_cm: float | None = typer.Option(
        None,
        "--frame-marker-size-cm",
        metavar="S",
        help="Frames: side of the markers in view, cm (the image scale).",
    ),
    frame_marker_dict: str | None = typer.Option(
        None, "--frame-marker-dict", help="Frames: ArUco dictionary [default: DICT_4X4_50]."
    ),
    slip_tolerance_m: float | None = typer.Option(
        None,
        "--slip-tolerance-m",
        metavar="T",
        help=f"Slip beyond which an attempt fails, m [default: 0.0005 with --sim (contact "
        f"slip), {DEFAULT_SLIP_TOLERANCE_M:g} with --slip-from-frames (object behind palms)].",
    ),
    slip_criterion: str | None = typer.Option(
        None,
        "--slip-criterion",
        metavar="contact|shortfall",
        help="Sim: contact = sliding at the palms since the rise began; shortfall = palm rise "
        "minus object rise at the end [default: contact].",
    ),
    alpha_cm: float | None = typer.Option(
        None, "--alpha-cm", help="Sim: lattice spacing, cm [default: longest side / 4]."
    ),
    dt_s: float | None = typer.Option(None, "--dt-s", help="Sim: time step, s [default: 0.001]."),
    memory_budget_gib: float | None = typer.Option(
        None,
        "--memory-budget-gib",
        help="Sim: refuse a lattice whose estimated memory exceeds this, GiB [default: 2].",
    ),
    debug_dir: str | None = typer.Option(
        None, "--debug-dir", help="Frames: write the last attempt's annotated frames here."
    ),
    log: str | None = typer.Option(
        None, "--log", help="Lift log (MCAP) with every attempt; - for stdout."
    ),
    objects: str | None = typer.Option(
        None, "--objects", help="Comma-separated object ids to lift, in this order [default: all]."
    ),
    protocol: str = typer.Option(
        "refine",
        "--protocol",
        help="refine: the paper's ramp, then bisection to --tolerance; paper: the ramp only.",
    ),
    growth: float = typer.Option(
        DEFAULT_GROWTH, "--growth", help="Ramp factor between attempts (> 1; the paper's 1.2)."
    ),
    tolerance: float = typer.Option(
        DEFAULT_TOLERANCE_REL,
        "--tolerance",
        help="refine: stop when (high - low) / high <= this, relative, in (0, 1).",
    ),
    max_attempts: int = typer.Option(
        DEFAULT_MAX_ATTEMPTS, "--max-attempts", help="Most attempts per object (>= 1)."
    ),
    force: bool = typer.Option(False, "--force", help="Overwrite existing outputs."),
    workers: int | None = _sweep.workers_option(),
    scheduler: str | None = _sweep.scheduler_option(),
    connect_timeout: float | None = _sweep.connect_timeout_option(),
    partition_size: int | None = _sweep.partition_size_option(),
    resume: bool = _sweep.resume_option(),
) -> None:
    """Find each object's minimum lifting force L_f by iterative lifting.

    Starts at the rigid-object force F_w = W / (2 mu) and raises the grip force by --growth
    until the object lifts (paper); refine then bisects to --tolerance. Writes one row per
    object (L_f, F_w, F_d = L_f - F_w, attempts, bracket, converged) and, with --log, every
    attempt to an MCAP log. Exit 1 when an object does not converge or the rig fails; the
    outputs are written first, keeping the attempts made so far.

    With --sim each attempt is simulated: grip, lift along the profile (S-curve to --lift-accel-m-s2
    and --lift-speed-m-s, rise --lift-height-m, hold --hold-s), judge slip by --slip-criterion
    against --slip-tolerance-m; every row records the profile and the criterion.

    With --sim and a dataset directory output (-o DIR/), the objects run in parallel
    (--workers N local processes, or --scheduler tcp://HOST:PORT of a Dask cluster) into
    DIR/part-*.parquet with each part's attempts in DIR/part-*.mcap; --resume completes an
    interrupted run. An object that fails is recorded in DIR/_failures/ and the rest go on.

    Example: deformctl lift datasets/paper/objects.csv --rig "python3 examples/threshold_rig.py"
    -o lift.parquet --log lift.mcap
    """
    sweep = _sweep.SweepOptions(workers, scheduler, connect_timeout, partition_size, resume)
    dataset = sweep.check(output)
    sim_options = {
        "--lift-accel-m-s2": lift_accel_m_s2,
        "--lift-speed-m-s": lift_speed_m_s,
        "--lift-height-m": lift_height_m,
        "--hold-s": hold_s,
        "--slip-tolerance-m": slip_tolerance_m if sim else None,  # else: frames' option
        "--slip-criterion": slip_criterion,
        "--alpha-cm": alpha_cm,
        "--dt-s": dt_s,
        "--memory-budget-gib": memory_budget_gib,
    }
    sim_factory = _sim_factory(sim, sim_options)
    judge = frames_judge(
        enabled=slip_from_frames, palm_marker_ids=palm_marker_ids, palm_regions=palm_regions,
        frame_marker_size_cm=frame_marker_size_cm,
        slip_tolerance_m=None if sim else slip_tolerance_m,
        marker_dict=frame_marker_dict, debug_dir=debug_dir,
    )  # fmt: skip
    factory = _choose_runner(rig, rig_timeout, judge, sim_factory)
    validate_search_options(
        protocol=protocol, growth=growth, tolerance_rel=tolerance, max_attempts=max_attempts
    )
    object_ids = _parse_objects(objects)
    if dataset:
        if sim_factory is None:
            raise UsageError("a dataset directory output (-o DIR/) needs --sim")
        if log is not None:
            raise UsageError(
                "--log is not used with a dataset directory output (see DIR/part-*.mcap)"
            )
        from deformctl.lift.runners.sim import LiftTask, lift_sweep

        task = LiftTask(*_sim_parts(sim_options), protocol, growth, tolerance, max_attempts)
        selected = select_objects(read_catalog(catalog), object_ids)
        summary = lift_sweep(selected, task, catalog_path=catalog, output=output, sweep=sweep,
                             force=force)  # fmt: skip
        _sweep.finish(summary, "lift")
        return
    _check_outputs(output, log, force)
    selected = select_objects(read_catalog(catalog), object_ids)
    provenance = Provenance.from_invocation(
        [catalog],
        settings={
            "runner": factory.name,
            **factory.settings,
            "protocol": protocol,
            "growth": growth,
            "tolerance_rel": tolerance,
            "max_attempts": max_attempts,
            "objects": list(selected["object_id"]),
        },
    )
    with _progress_bar(len(selected)) as progress:
        run = lift_catalog(
            selected,
            factory,
            protocol=cast(SearchProtocol, protocol),  # checked by validate_search_options
            growth=growth,
            tolerance_rel=tolerance,
            max_attempts=max_attempts,
            progress=progress,
            path=catalog,
        )
    if log is not None:
        write_lift_log(log, run.objects, run.attempts, provenance=provenance, force=force)
    write_table(run.table, output, "lift_results", provenance=provenance, force=force)
    if not is_stdio(output) and (log is None or not is_stdio(log)):
        aborted = {f.object_id for f in run.failures if f.aborted}  # their line is the error
        for result in run.results:
            if result.object_id not in aborted:
                typer.echo(result.message)
    message = run.error_message()
    if message is not None:
        raise SearchError(message)
