"""``deformctl measure CATALOG --sim``: simulated squeezes of every (selected) catalog object.

The options become a :class:`deformctl.measure.SimulateCatalogTask` (a
:class:`~deformctl.measure.options.SqueezeProtocol` and the preset of a
:class:`~deformctl.presets.SimOptions`); one library function runs
it: :func:`deformctl.measure.simulate_catalog_file` (one squeeze log) or, for a dataset directory
output, :func:`deformctl.measure.simulate_catalog_sweep`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated, Any

import typer

from deformctl.artifacts.io import is_stdio
from deformctl.cli._common import finish_sweep, progress_bar
from deformctl.cli._options import default, parse_log_epoch, parse_object_ids
from deformctl.cli._scene_options import scene_rate
from deformctl.cli._summary import RunClock
from deformctl.errors import UsageError
from deformctl.measure.csv_options import DEFAULT_CSV_MEMORY_BUDGET_GIB
from deformctl.measure.options import (
    DEFAULT_SIM_HOLD_S,
    DEFAULT_SIM_RAMP_S,
    DEFAULT_SIM_SQUEEZES,
    DEFAULT_SQUEEZE_STRAIN,
)

if TYPE_CHECKING:  # pragma: no cover - the stage (pandas, the simulator) loads when --sim runs
    from rich.console import Console

    from deformctl.measure.stage import SimulateCatalogTask
    from deformctl.parallel import SweepOptions

#: ``measure``'s budget: the simulator's lattice, or the rows of a CSV export and its log.
MemoryBudgetGib = Annotated[
    float | None,
    typer.Option(
        "--memory-budget-gib",
        metavar="GIB",
        help="Sim: refuse a lattice whose estimated memory exceeds this, GiB "
        f"{default('SimSettings.memory_budget_gib')}. CSV: refuse a file (or one log of all "
        f"files) whose estimated memory exceeds this [default: {DEFAULT_CSV_MEMORY_BUDGET_GIB:g}].",
    ),
]
Squeezes = Annotated[
    int | None,
    typer.Option(
        "--squeezes",
        metavar="X",
        help="Sim: squeezes per object, at 0.5..1 x the peak force [default: "
        f"{DEFAULT_SIM_SQUEEZES}, the paper's].",
    ),
]
PeakForceN = Annotated[
    float | None,
    typer.Option(
        "--peak-force-n",
        metavar="F",
        help="Sim: peak force of the largest squeeze, N, for every object [default: the "
        "strain rule, D x strain x size_x; a Hunt–Crossley object: k (strain x size_x)^n, at "
        "least 1.5 F_w].",
    ),
]
Strain = Annotated[
    float | None,
    typer.Option(
        "--strain",
        metavar="E",
        help=f"Sim: the default rule's static strain [default: {DEFAULT_SQUEEZE_STRAIN:g}].",
    ),
]
RampS = Annotated[
    float | None,
    typer.Option("--ramp-s", help=f"Sim: force ramp, s [default: {DEFAULT_SIM_RAMP_S:g}]."),
]
HoldS = Annotated[
    float | None,
    typer.Option(
        "--hold-s", help=f"Sim: hold at the peak force, s [default: {DEFAULT_SIM_HOLD_S:g}]."
    ),
]
Floating = Annotated[
    bool | None,
    typer.Option(
        "--floating",
        help="Sim: squeeze without gravity and table (a material test) [default: on the table].",
    ),
]
Seed = Annotated[int | None, typer.Option("--seed", help="Sim: noise seed [default: 0].", min=0)]
NoiseForceN = Annotated[
    float | None, typer.Option("--noise-force-n", help="Sim: force noise std, N [default: 0].")
]
NoisePositionM = Annotated[
    float | None,
    typer.Option(
        "--noise-position-m", help="Sim: noise std of each palm position, m [default: 0]."
    ),
]


@dataclass(frozen=True)
class SimFlags:
    """The ``--sim`` options as given (None: not given, the documented default applies)."""

    squeezes: int | None
    sim_preset: str | None
    objects: str | None
    peak_force_n: float | None
    strain: float | None
    ramp_s: float | None
    hold_s: float | None
    floating: bool | None
    alpha_cm: float | None
    dt_s: float | None
    memory_budget_gib: float | None
    seed: int | None
    noise_force_n: float | None
    noise_position_m: float | None
    log_epoch: str | None = None
    scene_hz: float | None = None

    def given(self) -> list[str]:
        """The flags of the options given on the command line."""
        return [
            "--" + name.replace("_", "-") for name, value in vars(self).items() if value is not None
        ]

    def task(self) -> SimulateCatalogTask:
        """The squeezes, simulator settings and seed these options ask for.

        Raises:
            UsageError: both ``--peak-force-n`` and ``--strain``, or a value outside its rule
                (:class:`~deformctl.measure.options.SqueezeProtocol`,
                :class:`~deformctl.presets.SimOptions`).
        """
        from deformctl.measure.options import SqueezeProtocol
        from deformctl.measure.stage import SimulateCatalogTask
        from deformctl.presets import DEFAULT_PRESET, SimOptions
        from deformctl.scene import scene_every_steps

        if self.peak_force_n is not None and self.strain is not None:
            raise UsageError("give --peak-force-n or --strain, not both")
        given: dict[str, Any] = {
            "squeezes": self.squeezes,
            "peak_force_n": self.peak_force_n,
            "strain": self.strain,
            "ramp_s": self.ramp_s,
            "hold_s": self.hold_s,
            "gravity": None if self.floating is None else not self.floating,
            "noise_force_n": self.noise_force_n,
            "noise_position_m": self.noise_position_m,
        }
        protocol = SqueezeProtocol(**{k: v for k, v in given.items() if v is not None})
        preset = SimOptions(
            preset_name=self.sim_preset or DEFAULT_PRESET,
            alpha_cm=self.alpha_cm,
            dt_s=self.dt_s,
            memory_budget_gib=self.memory_budget_gib,
        ).preset()
        scene_hz = scene_rate(self.scene_hz)
        scene_every_steps(scene_hz, preset.settings.dt_s)
        epoch_ns = parse_log_epoch(self.log_epoch)
        return SimulateCatalogTask(
            protocol=protocol,
            settings=preset.settings,
            seed=0 if self.seed is None else self.seed,
            sim_preset=preset.name,
            scene_hz=scene_hz,
            **({} if epoch_ns is None else {"log_epoch_ns": epoch_ns}),
        )


#: The flags of :class:`SimFlags` (only ``--sim`` takes them).
FLAGS = tuple("--" + f.name.replace("_", "-") for f in dataclasses.fields(SimFlags))


def run(
    catalog: str,
    opts: SimFlags,
    output: str,
    force: bool,
    sweep: SweepOptions,
    console: Console,
    quiet: bool = False,
) -> None:
    """Squeeze the objects of ``catalog`` into ``output`` (a squeeze log or a dataset directory)
    and end with the summary line (unless ``quiet``).

    Raises:
        UsageError: no catalog, or a bad option (see :meth:`SimFlags.task`).
    """
    from deformctl.measure.stage import simulate_catalog_file, simulate_catalog_sweep

    if not catalog:
        raise UsageError("--sim needs a CATALOG argument (the objects to squeeze)")
    task = opts.task()
    object_ids = parse_object_ids(opts.objects)
    clock = RunClock("measure")
    if sweep.check(output, file_workers=True):
        summary = simulate_catalog_sweep(
            catalog, task, output=output, sweep=sweep, object_ids=object_ids, force=force
        )
        finish_sweep(summary, "measure", quiet=quiet)
        return
    with progress_bar(console, "squeeze") as progress:
        objects, series = simulate_catalog_file(
            catalog,
            task,
            output=output,
            object_ids=object_ids,
            progress=progress,
            force=force,
            workers=sweep.workers,
        )
    duration_s = sum(float(s.time_s[-1]) for s in series)
    clock.finish(
        done=len(objects),
        flagged=0,  # a simulated squeeze carries no flag; a failure stops the run (exit 65)
        failed=0,
        output="stdout" if is_stdio(output) else output,
        detail=f"{len(series)} simulated squeeze(s) of {len(objects)} object(s), "
        f"{task.protocol.squeezes} each, {duration_s:.1f} s simulated, "
        f"dt {task.settings.dt_s:g} s",
        quiet=quiet,
    )
