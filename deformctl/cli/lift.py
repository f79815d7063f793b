"""``deformctl lift sim|rig``: the minimum lifting force of catalog objects, by iterative lifting.

One subcommand per trial runner (their options: :mod:`deformctl.cli._lift_runner`); each builds
its runner and calls one library function: :func:`deformctl.lift.stage.lift_catalog_files` (a
table file and a log) or, for a dataset directory output,
:func:`deformctl.lift.runners.sim.lift_sweep`; then it turns failures into the exit code.

Failures, decided here:

* bad options (tolerance, growth, max attempts, unknown ``--objects`` id): exit 2,
  before any attempt runs and before anything is written;
* an object with ``friction_mu <= 0`` in the catalog, or (``sim``) without material values:
  bad input data, exit 65, nothing run;
* a search that does not converge, or a rig that crashes, times out or answers garbage: the log
  (all completed attempts) and the table (a row per object, ``converged = false``, ``error``) are
  written first, then exit 1 with one line. A rig failure stops the run: the objects after it
  are not run (rows with ``attempts = 0`` and ``error`` "not run: ..."), since a rig that failed
  usually needs a person. A search that runs out of attempts does not stop the others.
* with ``rig``, the table and the log are also kept on disk as the run goes
  (:mod:`deformctl.lift.journal`): a run killed or stopped by an error after its first attempt
  keeps every attempt and the finished objects, and its error line says so.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated

import typer

from deformctl.artifacts.io import is_stdio
from deformctl.cli import _options as opt
from deformctl.cli._common import progress_bar, translate_errors, warn
from deformctl.cli._lift_frames import FRAMES
from deformctl.cli._lift_runner import PRESET, SEARCH, RigTimeout, lift_dataset
from deformctl.cli._lift_start import START, CatalogArg, report_run, run_summary
from deformctl.cli._sources import LiftGroup, source_group
from deformctl.cli._summary import Quiet, RunClock, stderr_console
from deformctl.errors import UsageError
from deformctl.lift.options import DEFAULT_RIG_TIMEOUT_S
from deformctl.parallel import SweepOptions

if TYPE_CHECKING:  # pragma: no cover - the runners (numba; pandas, MCAP) load when they run
    from deformctl.lift.options import SearchOptions
    from deformctl.lift.runners.rig import SlipFromFrames
    from deformctl.lift.seeded import StartSeed
    from deformctl.lift.stage import RunnerFactory
    from deformctl.parallel.auto import Auto
    from deformctl.presets import SimPreset

Output = Annotated[
    str,
    typer.Option(
        "-o", "--output", metavar="lift.parquet", help="Lift results table; - for stdout."
    ),
]
Log = Annotated[
    str | None,
    typer.Option("--log", metavar="lift.mcap", help="Lift log with every attempt; - for stdout."),
]
Start = Callable[..., "StartSeed | None"]


def lift() -> None:
    """Find each object's minimum lifting force L_f by iterative lifting.

    One subcommand per trial runner: the simulator or an external rig. Each search starts at
    the rigid-object force F_w = W / (2 mu) (or at a prediction, --start-model) and raises the
    grip force by --growth until the object lifts; refine then bisects to --tolerance.

    Example: deformctl lift sim datasets/paper/objects.csv -o lift.parquet --log lift.mcap
    """


@translate_errors
@opt.with_options(PRESET, SEARCH, START, opt.SWEEP)
def sim(
    catalog: CatalogArg,
    output: Output,
    log: Log = None,
    objects: opt.Objects = None,
    log_epoch: opt.LogEpoch = None,
    scene_hz: opt.SceneHz = None,
    quiet: Quiet = False,
    force: opt.Force = False,
    preset: SimPreset = None,  # type: ignore[assignment]  # built by the option groups
    search: SearchOptions = None,  # type: ignore[assignment]
    start: Start = None,  # type: ignore[assignment]
    sweep: SweepOptions = opt.NO_SWEEP,
) -> None:
    """Find each object's L_f with attempts in the simulator (the catalog's material values).

    Each attempt grips, rises and holds, then judges slip. One row per object (L_f, F_w,
    attempts, converged); exit 1 when one does not converge, after writing the outputs.

    Example: deformctl lift sim objects.csv -o lift.parquet --log lift.mcap
    """
    clock = RunClock("lift")
    dataset = sweep.check(output, file_workers=True)
    if scene_hz is not None and log is None and not dataset:
        raise UsageError("--scene-hz needs --log FILE: the scene is written into the lift log")
    if dataset and log is not None:
        raise UsageError("--log is not used with a dataset directory output (DIR/_logs/ has them)")
    # the scene goes into a log: without one, the attempts record none
    scene = opt.scene_rate(scene_hz) if log is not None or dataset else 0.0
    epoch_ns = opt.parse_log_epoch(log_epoch)
    from deformctl.lift.runners.sim import LiftTask, sim_runner_factory

    # the scene rate is checked once, by the task or the factory built with it
    if dataset:
        task = LiftTask(preset=preset, search=search, log_epoch_ns=epoch_ns, scene_hz=scene)
        start(protocol=search.protocol, dataset=True)  # refuses a start seed
        object_ids = opt.parse_object_ids(objects)
        lift_dataset(catalog, task, output, sweep, object_ids=object_ids, force=force, quiet=quiet)
        return
    factory = sim_runner_factory(preset=preset, scene_hz=scene)
    run = _FileRun(catalog=catalog, output=output, log=log, objects=objects, force=force)
    run.lift(
        factory,
        search,
        start,
        clock=None if quiet else clock,
        epoch_ns=epoch_ns,
        workers=sweep.workers,
    )


@translate_errors
@opt.with_options(FRAMES, SEARCH, START)
def rig(
    catalog: CatalogArg,
    command: Annotated[
        str,
        typer.Option(
            "--command",
            metavar="CMD",
            help="Rig command: a JSON request in, a JSON answer out (docs/rig-protocol.md).",
        ),
    ],
    output: Output,
    rig_timeout: RigTimeout = None,
    log: Log = None,
    objects: opt.Objects = None,
    quiet: Quiet = False,
    force: opt.Force = False,
    judge: SlipFromFrames = None,  # type: ignore[assignment]  # built by the option groups
    search: SearchOptions = None,  # type: ignore[assignment]
    start: Start = None,  # type: ignore[assignment]
) -> None:
    """Find each object's L_f with attempts on a rig (a command run per attempt).

    One row per object (L_f, F_w, attempts, converged), kept on disk as the run goes; a rig that
    fails stops the run. Exit 1 when an object does not converge or the rig fails.

    Example: deformctl lift rig objects.csv --command "python3 rig.py" -o lift.parquet
    """
    clock = RunClock("lift")
    if opt.NO_SWEEP.check(output):
        raise UsageError("a dataset directory output (-o DIR/) needs lift sim")
    from deformctl.lift.runners.rig import rig_runner_factory

    timeout_s = DEFAULT_RIG_TIMEOUT_S if rig_timeout is None else rig_timeout
    factory = rig_runner_factory(command, timeout_s=timeout_s, slip_from_frames=judge)
    run = _FileRun(catalog=catalog, output=output, log=log, objects=objects, force=force)
    run.lift(factory, search, start, clock=None if quiet else clock)


@dataclass(frozen=True, kw_only=True)
class _FileRun:
    """The table-file output that ``lift sim`` and ``lift rig`` share: the catalog, the
    outputs, the ``--objects`` chosen and ``--force``."""

    catalog: str
    output: str
    log: str | None
    objects: str | None
    force: bool

    def lift(
        self,
        factory: RunnerFactory,
        search: SearchOptions,
        start: Start,
        *,
        clock: RunClock | None,
        epoch_ns: int | None = None,
        workers: int | Auto | None = opt.NO_SWEEP.workers,
    ) -> None:
        """Lift the objects into the table file (and the log) with ``factory``'s runner, the
        search from ``start``'s seed (if any), then report the run (its summary line unless
        ``clock`` is None: ``--quiet``)."""
        from deformctl.lift.stage import lift_catalog_files

        object_ids = opt.parse_object_ids(self.objects)
        seed = start(protocol=search.protocol, dataset=False)
        output, log = self.output, self.log
        with progress_bar(stderr_console(), "lift") as progress:
            run = lift_catalog_files(
                self.catalog,
                factory,
                output=output,
                log=log,
                object_ids=object_ids,
                search=search,
                progress=progress,
                force=self.force,
                log_epoch_ns=epoch_ns,
                seed=seed,
                warn=warn,
                workers=workers,
            )
        summary = None if clock is None else run_summary(run, clock, output, log)
        quiet = is_stdio(output) or (log is not None and is_stdio(log))
        report_run(run, quiet=quiet, summary=summary)


#: ``lift`` and its subcommands (registered on the root app as one group).
GROUP = source_group(LiftGroup, lift, (sim, rig))
lift.group = GROUP  # type: ignore[attr-defined]
