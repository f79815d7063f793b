"""``deformctl measure``: squeeze logs from a source (a ROS 2 bag, a CSV export, the simulator).

Exactly one source option is given per run. :data:`SOURCES` names, for every option that only
some sources take, those sources; an option given with another source is refused by name (one
table, one check). Each source then runs in its own module: :mod:`deformctl.cli._measure_rig`
(``--bag``, ``--csv``: a rig recording), :mod:`deformctl.cli._measure_sim` (``--sim``: every
object of a catalog in the simulator), :mod:`deformctl.cli._measure_images` (``--images``: an
object-catalog row instead of a squeeze log).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated

import typer

from deformctl.cli import _image_options as img
from deformctl.cli import _measure_csv, _measure_images, _measure_rig, _measure_sim
from deformctl.cli import _measure_csv as csvo
from deformctl.cli import _measure_rig as rec
from deformctl.cli import _measure_sim as sq
from deformctl.cli import _options as opt
from deformctl.cli._common import translate_errors
from deformctl.cli._scene_options import SceneHz
from deformctl.cli._summary import Quiet, stderr_console
from deformctl.errors import UsageError
from deformctl.parallel import SweepOptions

if TYPE_CHECKING:  # pragma: no cover - rich and numpy load when a source runs
    from deformctl.catalog import MeasuredObject


def _object(object_id: str, weight_n: float, **kwargs: object) -> MeasuredObject:
    from deformctl.catalog import MeasuredObject

    return MeasuredObject(object_id, weight_n, **kwargs)  # type: ignore[arg-type]


RIG, IMAGES = ("--bag", "--csv"), ("--images",)
#: Every option that only some sources take → those sources (``--sim`` takes the sweep options).
SOURCES: dict[str, tuple[str, ...]] = {
    **dict.fromkeys(
        ("--wrench-topic", "--position-topic", "--joint", "--no-crc-check"), ("--bag",)
    ),
    **dict.fromkeys(("--columns", "--units", *_measure_csv.FLAGS), ("--csv",)),
    **dict.fromkeys(("--segment/--no-segment", "--phase", "--position-increases-when"), RIG),
    **dict.fromkeys(("--object-id", "--weight-n", "--friction-mu"), (*RIG, *IMAGES)),
    "--size-cm": RIG,
    **dict.fromkeys(img.FLAGS, IMAGES),
    **dict.fromkeys(_measure_sim.FLAGS, ("--sim",)),
    "--memory-budget-gib": ("--sim", "--csv"),
    "--quiet": ("--sim",),
}


def _refuse_foreign(source: str, given: list[str]) -> None:
    """Refuse the options given (their flags) that ``source`` does not take, by name."""
    foreign = [flag for flag in given if flag in SOURCES and source not in SOURCES[flag]]
    if foreign:
        why = " (the catalog describes the objects)" if source == "--sim" else ""
        raise UsageError(f"{', '.join(foreign)} cannot be used with {source}{why}")


def _source(
    bag: str | None,
    csv: str | None,
    images: tuple[str, str] | None,
    sim: bool,
    inputs: list[str],
) -> tuple[str, str]:
    """The one source given (its flag and its value: a catalog for ``--sim``).

    Raises:
        UsageError: no source, several, or arguments the source does not take (exit 2).
    """
    if inputs and not sim and csv is None:
        raise UsageError(f"an argument ({inputs[0]!r}) needs --sim (a catalog) or --csv (files)")
    if sim and len(inputs) > 1:
        raise UsageError(f"--sim takes one catalog, got {len(inputs)}: {', '.join(inputs)}")
    catalog = inputs[0] if sim and inputs else None
    sources = {"--bag": bag, "--csv": csv, "--images": None if images is None else images[0]}
    sources["--sim"] = (catalog or "") if sim else None
    chosen = [(flag, value) for flag, value in sources.items() if value is not None]
    if len(chosen) != 1:
        what = (
            "several sources (" + ", ".join(f for f, _ in chosen) + ")" if chosen else "no source"
        )
        raise UsageError(f"{what}: give exactly one of {', '.join(sources)}")
    return chosen[0]


@translate_errors
@opt.with_sweep_options
def measure(
    inputs: Annotated[
        list[str] | None,
        typer.Argument(
            metavar="[CATALOG | FILE...]",
            help="--sim: the object catalog (CSV or Parquet, with material values); - for stdin. "
            "--csv: more CSV files (a shell glob after --csv: --csv data/*.csv).",
        ),
    ] = None,
    sim: Annotated[
        bool,
        typer.Option("--sim", help="Source: the simulator, squeezing every object of CATALOG."),
    ] = False,
    bag: rec.Bag = None,
    csv: rec.Csv = None,
    images: img.Images = None,
    wrench_topics: rec.WrenchTopics = [],  # noqa: B006 - typer copies the default
    position_topic: rec.PositionTopic = None,
    joint: rec.Joint = None,
    axis: rec.Axis = "x",
    position_is: rec.PositionIs = "palm",
    columns: rec.Columns = None,
    units: rec.Units = None,
    segment: rec.Segment = None,
    phase: rec.Phase = None,
    position_increases_when: rec.PositionIncreasesWhen = None,
    no_crc_check: rec.NoCrcCheck = False,
    skip_rows: csvo.SkipRows = None,
    delimiter: csvo.Delimiter = None,
    decimal: csvo.Decimal = None,
    thousands: csvo.Thousands = None,
    encoding: csvo.Encoding = None,
    force_sign: csvo.ForceSign = None,
    lag_s: csvo.LagS = None,
    objects_from: csvo.ObjectsFrom = None,
    marker_size_cm: img.MarkerSizeCm = None,
    marker_dict: img.MarkerDict = None,
    marker_id: img.MarkerId = None,
    checkerboard: img.Checkerboard = None,
    square_size_cm: img.SquareSizeCm = None,
    color_range: img.ColorRange = None,
    background: img.Background = None,
    debug_dir: img.DebugDir = None,
    append: img.Append = False,
    camera_matrix: img.CameraMatrix = None,
    object_id: rec.ObjectId = None,
    weight_n: rec.WeightN = None,
    size_cm: rec.SizeCm = None,
    friction_mu: rec.FrictionMu = None,
    output: Annotated[
        str,
        typer.Option(
            "-o",
            "--output",
            metavar="squeeze.mcap",
            help="The squeeze log to write (with --images: the catalog); - for stdout.",
        ),
    ] = ...,  # type: ignore[assignment]
    squeezes: sq.Squeezes = None,
    sim_preset: opt.SimPresetName = None,
    objects: opt.Objects = None,
    peak_force_n: sq.PeakForceN = None,
    strain: sq.Strain = None,
    ramp_s: sq.RampS = None,
    hold_s: sq.HoldS = None,
    floating: sq.Floating = None,
    alpha_cm: opt.AlphaCm = None,
    dt_s: opt.DtS = None,
    memory_budget_gib: sq.MemoryBudgetGib = None,
    seed: sq.Seed = None,
    noise_force_n: sq.NoiseForceN = None,
    noise_position_m: sq.NoisePositionM = None,
    log_epoch: opt.LogEpoch = None,
    scene_hz: SceneHz = None,
    quiet: Quiet = False,
    force: opt.Force = False,
    sweep: SweepOptions = opt.NO_SWEEP,
) -> None:
    """Turn a rig recording, or simulated squeezes of a catalog, into a squeeze log (MCAP).

    Force and position are aligned by timestamp (position interpolated onto the force samples),
    the compression d between the palms is formed, and the recording is cut into squeezes. The
    log stores the object's weight (and size, friction when given), the source sample rates,
    and provenance (input sha256, command line, settings).

    With --sim, every catalog object with material values is squeezed --squeezes times in the
    simulator (force ramp then hold; the largest squeeze's peak force is D x strain x size_x
    unless --peak-force-n is given), and the log stores each object's catalog row and the
    simulator settings and seed. With a dataset directory output (-o DIR/) the objects run in
    parallel (--workers, --scheduler; --resume) into DIR/_logs/part-*.mcap squeeze logs and a
    per-object summary DIR/part-*.parquet; characterize reads DIR/ directly.

    Example:

    \b
      deformctl measure --bag run.mcap --wrench-topic /left/wrench \\
        --position-topic /left/palm_pose --object-id sand --weight-n 2.9 -o squeeze.mcap
      deformctl measure datasets/paper/objects.csv --sim -o squeeze.mcap
    """
    sim_opts = _measure_sim.SimFlags(
        squeezes=squeezes, sim_preset=sim_preset, objects=objects, peak_force_n=peak_force_n,
        strain=strain, ramp_s=ramp_s, hold_s=hold_s, floating=floating, alpha_cm=alpha_cm,
        dt_s=dt_s, memory_budget_gib=memory_budget_gib, seed=seed, noise_force_n=noise_force_n,
        noise_position_m=noise_position_m, log_epoch=log_epoch, scene_hz=scene_hz,
    )  # fmt: skip
    image_opts = img.ImageOptions(
        marker_size_cm=marker_size_cm, marker_dict=marker_dict, marker_id=marker_id,
        checkerboard=checkerboard, square_size_cm=square_size_cm, color_range=color_range,
        background=background, debug_dir=debug_dir, append=append, camera_matrix=camera_matrix,
    )  # fmt: skip
    csv_flags = csvo.CsvFlags(
        skip_rows=skip_rows, delimiter=delimiter, decimal=decimal, thousands=thousands,
        encoding=encoding, force_sign=force_sign, lag_s=lag_s, objects_from=objects_from,
    )  # fmt: skip
    rig_opts = _measure_rig.RigOptions(
        object_id=object_id, wrench_topics=list(wrench_topics), position_topic=position_topic,
        joint=joint, axis=axis, position_is=position_is, columns=columns, units=units,
        segment=segment, phase=phase, position_increases_when=position_increases_when,
        crc_check=not no_crc_check,
    )  # fmt: skip
    object_flags = {"--weight-n": weight_n, "--size-cm": size_cm, "--friction-mu": friction_mu}
    given = [
        *rig_opts.given(), *(flag for flag, value in object_flags.items() if value is not None),
        *image_opts.given(), *sim_opts.given(), *csv_flags.given(),
        *(["--quiet"] if quiet else []),
    ]  # fmt: skip
    inputs = list(inputs or [])
    flag, source = _source(bag, csv, images, sim, inputs)
    _refuse_foreign(flag, given)
    if flag == "--sim":
        _measure_sim.run(source, sim_opts, output, force, sweep, stderr_console(), quiet)
        return
    if flag == "--csv":
        named = csvo.ObjectFlags(
            object_id=object_id, weight_n=weight_n, size_cm=size_cm, friction_mu=friction_mu
        )
        _measure_csv.run(
            [source, *inputs], csv_flags, rig_opts, named, memory_budget_gib, output, force, sweep
        )
        return
    if sweep.given():
        raise UsageError(f"{sweep.given()[0]} needs --sim or --csv")
    if object_id is None or weight_n is None:
        raise UsageError(f"{flag} needs --object-id and --weight-n")
    obj = _object(object_id, weight_n, size_cm=size_cm, friction_mu=friction_mu)
    if images is not None:
        _measure_images.measure_images(images, image_opts, obj, output=output, force=force)
        return
    _measure_rig.run(source, rig_opts, obj, output, force)
