"""``deformctl measure sim CATALOG``: simulated squeezes of every (selected) catalog object.

The options become a :class:`deformctl.measure.SimulateCatalogTask` (a
:class:`~deformctl.measure.options.SqueezeProtocol` and the preset of a
:class:`~deformctl.presets.SimOptions`); one library function runs
it: :func:`deformctl.measure.simulate_catalog_file` (one squeeze log) or, for a dataset directory
output, :func:`deformctl.measure.simulate_catalog_sweep`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Any

import typer

from deformctl.artifacts.io import is_stdio
from deformctl.cli._common import finish_sweep, progress_bar
from deformctl.cli._options import (
    SIMULATOR,
    LogEpoch,
    OptionGroup,
    SceneHz,
    parse_log_epoch,
    parse_object_ids,
    scene_rate,
)
from deformctl.cli._summary import RunClock
from deformctl.errors import UsageError
from deformctl.measure.options import (
    DEFAULT_SIM_HOLD_S,
    DEFAULT_SIM_RAMP_S,
    DEFAULT_SIM_SQUEEZES,
    DEFAULT_SQUEEZE_STRAIN,
)

if TYPE_CHECKING:  # pragma: no cover - the stage (pandas, the simulator) loads when it runs
    from rich.console import Console

    from deformctl.measure.stage import SimulateCatalogTask
    from deformctl.parallel import SweepOptions

Squeezes = Annotated[
    int | None,
    typer.Option(
        "--squeezes",
        metavar="X",
        help=f"Squeezes per object, at 0.5..1 x the peak force [default: {DEFAULT_SIM_SQUEEZES}].",
    ),
]
PeakForceN = Annotated[
    float | None,
    typer.Option(
        "--peak-force-n",
        metavar="F",
        help="Peak force of the largest squeeze, N [default: D x strain x size_x; Hunt-Crossley: "
        "k (strain x size_x)^n, within 1.5..3 F_w].",
    ),
]
Strain = Annotated[
    float | None,
    typer.Option(
        "--strain",
        metavar="E",
        help=f"The default peak force's static strain [default: {DEFAULT_SQUEEZE_STRAIN:g}].",
    ),
]
RampS = Annotated[
    float | None,
    typer.Option("--ramp-s", help=f"Force ramp, s [default: {DEFAULT_SIM_RAMP_S:g}]."),
]
HoldS = Annotated[
    float | None,
    typer.Option("--hold-s", help=f"Hold at the peak force, s [default: {DEFAULT_SIM_HOLD_S:g}]."),
]
Floating = Annotated[
    bool | None,
    typer.Option("--floating", help="No gravity and no table (a material test)."),
]
Seed = Annotated[int | None, typer.Option("--seed", help="Noise seed [default: 0].", min=0)]
NoiseForceN = Annotated[
    float | None, typer.Option("--noise-force-n", help="Force noise std, N [default: 0].")
]
NoisePositionM = Annotated[
    float | None,
    typer.Option("--noise-position-m", help="Palm position noise std, m [default: 0]."),
]


def simulate_task(
    *,
    squeezes: int | None,
    peak_force_n: float | None,
    strain: float | None,
    ramp_s: float | None,
    hold_s: float | None,
    floating: bool | None,
    seed: int | None,
    noise_force_n: float | None,
    noise_position_m: float | None,
    sim_preset: str | None,
    alpha_cm: float | None,
    dt_s: float | None,
    memory_budget_gib: float | None,
    log_epoch: str | None,
    scene_hz: float | None,
) -> SimulateCatalogTask:
    """The squeezes, simulator settings and seed the options ask for (None: not given, the
    library default applies).

    Raises:
        UsageError: both ``--peak-force-n`` and ``--strain``, or a value outside its rule
            (:class:`~deformctl.measure.options.SqueezeProtocol`,
            :class:`~deformctl.presets.SimOptions`).
    """
    from deformctl.measure.options import SqueezeProtocol
    from deformctl.measure.stage import SimulateCatalogTask
    from deformctl.presets import DEFAULT_PRESET, SimOptions

    if peak_force_n is not None and strain is not None:
        raise UsageError("give --peak-force-n or --strain, not both")
    given: dict[str, Any] = {
        "squeezes": squeezes,
        "peak_force_n": peak_force_n,
        "strain": strain,
        "ramp_s": ramp_s,
        "hold_s": hold_s,
        "gravity": None if floating is None else not floating,
        "noise_force_n": noise_force_n,
        "noise_position_m": noise_position_m,
    }
    protocol = SqueezeProtocol(**{k: v for k, v in given.items() if v is not None})
    preset = SimOptions(
        preset_name=sim_preset or DEFAULT_PRESET,
        alpha_cm=alpha_cm,
        dt_s=dt_s,
        memory_budget_gib=memory_budget_gib,
    ).preset()
    epoch_ns = parse_log_epoch(log_epoch)
    return SimulateCatalogTask(
        protocol=protocol,
        settings=preset.settings,
        seed=0 if seed is None else seed,
        sim_preset=preset.name,
        scene_hz=scene_rate(scene_hz),
        **({} if epoch_ns is None else {"log_epoch_ns": epoch_ns}),
    )


#: The squeeze and simulator options of ``measure sim``, as one ``SimulateCatalogTask``.
TASK = OptionGroup(
    "task",
    (
        ("squeezes", Squeezes, None),
        ("peak_force_n", PeakForceN, None),
        ("strain", Strain, None),
        ("ramp_s", RampS, None),
        ("hold_s", HoldS, None),
        ("floating", Floating, None),
        ("seed", Seed, None),
        ("noise_force_n", NoiseForceN, None),
        ("noise_position_m", NoisePositionM, None),
        *SIMULATOR,
        ("log_epoch", LogEpoch, None),
        ("scene_hz", SceneHz, None),
    ),
    simulate_task,
)


def run(
    catalog: str,
    task: SimulateCatalogTask,
    objects: str | None,
    output: str,
    force: bool,
    sweep: SweepOptions,
    console: Console,
    quiet: bool = False,
) -> None:
    """Squeeze the objects of ``catalog`` into ``output`` (a squeeze log or a dataset directory)
    and end with the summary line (unless ``quiet``)."""
    from deformctl.measure.stage import simulate_catalog_file, simulate_catalog_sweep

    object_ids = parse_object_ids(objects)
    clock = RunClock("measure")
    if sweep.check(output, file_workers=True):
        summary = simulate_catalog_sweep(
            catalog, task, output=output, sweep=sweep, object_ids=object_ids, force=force
        )
        finish_sweep(summary, "measure", quiet=quiet)
        return
    with progress_bar(console, "measure") as progress:  # counts objects
        rows, series = simulate_catalog_file(
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
        done=len(rows),
        flagged=0,  # a simulated squeeze carries no flag; a failure stops the run (exit 65)
        failed=0,
        output="stdout" if is_stdio(output) else output,
        detail=f"{len(series)} simulated squeeze(s) of {len(rows)} object(s), "
        f"{task.protocol.squeezes} each, {duration_s:.1f} s simulated, "
        f"dt {task.settings.dt_s:g} s",
        quiet=quiet,
    )
