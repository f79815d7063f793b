"""``deformctl measure``: squeeze logs from a source (a ROS 2 bag, a CSV export, the simulator).

Exactly one source option is given per run; each recording source has a reader in
:data:`_SOURCES` that checks its own options and returns a :class:`~deformctl.measure.Recording`.
The command then writes the squeezes, the object's catalog-like row and the provenance as one
squeeze log. ``--sim`` (the simulator over a catalog, many objects) is handled by
:func:`_measure_sim` over :func:`deformctl.measure.simulate_squeezes`. ``--images`` writes an
object-catalog row instead (:mod:`deformctl.cli._measure_images`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from deformctl.artifacts import (
    Provenance,
    check_input_path,
    check_output_path,
    read_catalog,
    write_squeeze_log,
)
from deformctl.artifacts.io import is_stdio
from deformctl.catalog import catalog_objects, object_record, select_objects
from deformctl.cli import app
from deformctl.cli._common import translate_errors
from deformctl.cli._measure_images import ImageOptions, measure_images
from deformctl.cli._sweep import (
    SweepOptions,
    connect_timeout_option,
    finish,
    partition_size_option,
    resume_option,
    scheduler_option,
    workers_option,
)
from deformctl.errors import UsageError
from deformctl.measure import (
    DEFAULT_SIM_HOLD_S,
    DEFAULT_SIM_RAMP_S,
    DEFAULT_SIM_SQUEEZES,
    DEFAULT_SQUEEZE_STRAIN,
    Recording,
    SimulateCatalogTask,
    read_csv_export,
    read_ros2_bag,
    simulate_catalog_sweep,
    simulate_squeezes,
)


@dataclass(frozen=True)
class _Options:
    """The source-specific options as given on the command line (None / empty: not given)."""

    object_id: str
    wrench_topics: list[str]
    position_topic: str | None
    joint: str | None
    axis: str
    position_is: str
    columns: str | None
    units: str | None
    segment: bool | None
    phase: str = "all"
    position_increases_when: str | None = None
    size_x_cm: float | None = None

    def recording(self) -> dict[str, Any]:
        """The reader options both rig sources take (phase, position direction, size)."""
        return {
            "phase": self.phase,
            "position_increases_when": self.position_increases_when,
            "size_x_cm": self.size_x_cm,
        }


def parse_mapping(text: str, option: str) -> dict[str, str]:
    """Parse ``key=value,key=value`` (``--columns``, ``--units``) into a dict.

    Raises:
        UsageError: an item without ``=``, an empty key or value, or a repeated key.
    """
    out: dict[str, str] = {}
    for item in text.split(","):
        key, sep, value = item.partition("=")
        key, value = key.strip(), value.strip()
        if not sep or not key or not value:
            raise UsageError(f"{option}: expected key=value[,key=value...], got {item!r}")
        if key in out:
            raise UsageError(f"{option}: {key!r} given twice")
        out[key] = value
    return out


def _refuse(given: Mapping[str, object], source: str) -> None:
    """Refuse options that belong to another source."""
    extra = [flag for flag, value in given.items() if value not in (None, [], False)]
    if extra:
        raise UsageError(f"{', '.join(extra)} cannot be used with {source}")


def _from_bag(path: str, opts: _Options) -> tuple[Recording, dict[str, Any]]:
    _refuse({"--columns": opts.columns, "--units": opts.units}, "--bag")
    if not opts.wrench_topics:
        raise UsageError("--bag needs --wrench-topic (one, or two for two palms)")
    if opts.position_topic is None:
        raise UsageError("--bag needs --position-topic (PoseStamped or JointState)")
    settings: dict[str, Any] = {
        "source": "ros2_bag",
        "wrench_topics": opts.wrench_topics,
        "position_topic": opts.position_topic,
        "joint": opts.joint,
        "axis": opts.axis,
        "position_is": opts.position_is,
        "segment": True if opts.segment is None else opts.segment,
        "phase": opts.phase,
        "position_increases_when": opts.position_increases_when,
    }
    rec = read_ros2_bag(
        path,
        wrench_topics=opts.wrench_topics,
        position_topic=opts.position_topic,
        object_id=opts.object_id,
        axis=opts.axis,  # type: ignore[arg-type]
        joint=opts.joint,
        position_is=opts.position_is,  # type: ignore[arg-type]
        segment=settings["segment"],
        **opts.recording(),
    )
    return rec, settings


def _from_csv(path: str, opts: _Options) -> tuple[Recording, dict[str, Any]]:
    _refuse(
        {
            "--wrench-topic": opts.wrench_topics,
            "--position-topic": opts.position_topic,
            "--joint": opts.joint,
        },
        "--csv",
    )
    if opts.columns is None:
        raise UsageError("--csv needs --columns time=COL,force=COL,position=COL")
    columns = parse_mapping(opts.columns, "--columns")
    units = parse_mapping(opts.units, "--units") if opts.units is not None else {}
    settings: dict[str, Any] = {
        "source": "csv",
        "columns": columns,
        "units": units,
        "position_is": opts.position_is,
        "segment": False if opts.segment is None else opts.segment,
        "phase": opts.phase,
        "position_increases_when": opts.position_increases_when,
    }
    rec = read_csv_export(
        path,
        columns=columns,
        units=units,
        object_id=opts.object_id,
        position_is=opts.position_is,  # type: ignore[arg-type]
        segment=settings["segment"],
        **opts.recording(),
    )
    return rec, settings


#: source option → its reader; exactly one source is given per run.
_SOURCES: dict[str, Callable[[str, _Options], tuple[Recording, dict[str, Any]]]] = {
    "--bag": _from_bag,
    "--csv": _from_csv,
}


def _choose_source(given: Mapping[str, str | None]) -> tuple[str, str]:
    chosen = [(flag, value) for flag, value in given.items() if value is not None]
    if len(chosen) != 1:
        what = (
            "no source"
            if not chosen
            else "several sources (" + ", ".join(f for f, _ in chosen) + ")"
        )
        raise UsageError(f"{what}: give exactly one of {', '.join(given)}")
    return chosen[0]


@dataclass(frozen=True)
class _SimOptions:
    """The ``--sim`` options as given (None: not given, the documented default applies)."""

    squeezes: int | None
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

    def given(self) -> dict[str, object]:
        """Option flag → value for the options given on the command line."""
        return {
            "--" + name.replace("_", "-"): value
            for name, value in vars(self).items()
            if value is not None
        }


def _squeeze_progress_bar(console: Console, total: int) -> Progress | None:
    if total < 2 or not console.is_terminal:
        return None
    return Progress(
        TextColumn("squeeze {task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=console,
        transient=True,
    )


def _measure_sim(
    catalog_path: str,
    opts: _SimOptions,
    output: str,
    force: bool,
    sweep: SweepOptions | None = None,
) -> None:
    """``measure CATALOG --sim``: simulated squeezes of every (selected) catalog object.

    With a dataset directory output the objects run through the sweep executor (``sweep``).
    """
    from deformctl.sim import SimSettings

    if opts.peak_force_n is not None and opts.strain is not None:
        raise UsageError("give --peak-force-n or --strain, not both")
    squeezes = DEFAULT_SIM_SQUEEZES if opts.squeezes is None else opts.squeezes
    if squeezes < 1:
        raise UsageError(f"--squeezes must be >= 1, got {squeezes}")
    settings = SimSettings(
        alpha_cm=opts.alpha_cm,
        dt_s=SimSettings.dt_s if opts.dt_s is None else opts.dt_s,
        memory_budget_gib=(
            SimSettings.memory_budget_gib
            if opts.memory_budget_gib is None
            else opts.memory_budget_gib
        ),
    )
    ids = None if opts.objects is None else [part.strip() for part in opts.objects.split(",")]
    sweep = sweep or SweepOptions()
    dataset = sweep.check(output)
    if not dataset:
        check_output_path(output, force)
    catalog = select_objects(read_catalog(catalog_path), ids)
    if not dataset:  # a sweep records such rows as failed objects and goes on
        for obj in catalog_objects(catalog, path=catalog_path):  # refuse them first
            obj.to_sim_spec(path=catalog_path)
    seed = 0 if opts.seed is None else opts.seed
    strain = DEFAULT_SQUEEZE_STRAIN if opts.strain is None else opts.strain
    kwargs: dict[str, Any] = {
        "squeezes": squeezes,
        "peak_force_n": opts.peak_force_n,
        "strain": strain,
        "ramp_s": DEFAULT_SIM_RAMP_S if opts.ramp_s is None else opts.ramp_s,
        "hold_s": DEFAULT_SIM_HOLD_S if opts.hold_s is None else opts.hold_s,
        "gravity": not opts.floating,
        "noise_force_n": opts.noise_force_n or 0.0,
        "noise_position_m": opts.noise_position_m or 0.0,
    }
    provenance = Provenance.from_invocation(
        [catalog_path],
        seed=seed,
        settings={
            "source": "sim",
            **kwargs,
            "peak_force_rule": "peak_force_n" if opts.peak_force_n is not None else "strain",
            "objects": list(catalog["object_id"]),
            "sim_settings": dataclasses.asdict(settings),
        },
    )
    if dataset:
        sim_task = SimulateCatalogTask(kwargs, settings, seed)
        summary = simulate_catalog_sweep(
            catalog, sim_task, catalog_path=catalog_path, output=output, provenance=provenance,
            sweep=sweep, force=force,
        )  # fmt: skip
        finish(summary, "measure")
        return
    console = Console(stderr=True)
    total = squeezes * len(catalog)
    bar = _squeeze_progress_bar(console, total)
    if bar is None:
        objects, series = simulate_squeezes(
            catalog, settings=settings, seed=seed, path=catalog_path, **kwargs
        )
    else:
        with bar:
            task = bar.add_task("", total=total)

            def advance(object_id: str, done: int, total_squeezes: int) -> None:
                bar.update(task, completed=done, description=object_id)

            objects, series = simulate_squeezes(
                catalog, settings=settings, seed=seed, progress=advance, path=catalog_path, **kwargs
            )
    write_squeeze_log(output, objects, series, provenance=provenance, force=force)
    where = "stdout" if is_stdio(output) else output
    duration_s = sum(float(s.time_s[-1]) for s in series)
    typer.echo(
        f"{where}: {len(series)} simulated squeeze(s) of {len(objects)} object(s) "
        f"({squeezes} each), {duration_s:.1f} s, dt {settings.dt_s:g} s",
        err=True,
    )


@app.command()
@translate_errors
def measure(
    catalog: str | None = typer.Argument(
        None,
        metavar="[CATALOG]",
        help="--sim: the object catalog (CSV or Parquet, with material values); - for stdin.",
    ),
    sim: bool = typer.Option(
        False, "--sim", help="Source: the simulator, squeezing every object of CATALOG."
    ),
    bag: str | None = typer.Option(
        None, "--bag", metavar="BAG.mcap", help="Source: a ROS 2 bag, one MCAP file (ros2msg/cdr)."
    ),
    csv: str | None = typer.Option(
        None,
        "--csv",
        metavar="FILE",
        help="Source: a CSV export, plain or with a units row under the names.",
    ),
    images: tuple[str, str] | None = typer.Option(
        None,
        "--images",
        metavar="TOP SIDE",
        help="Source: a top and a side image with a scale reference; writes a catalog row "
        "(object size from the images) instead of a squeeze log.",
    ),
    wrench_topics: list[str] = typer.Option(  # noqa: B008
        [],
        "--wrench-topic",
        metavar="TOPIC",
        help="Bag: geometry_msgs/msg/WrenchStamped topic; repeat for the second palm.",
    ),
    position_topic: str | None = typer.Option(
        None,
        "--position-topic",
        metavar="TOPIC",
        help="Bag: geometry_msgs/msg/PoseStamped or sensor_msgs/msg/JointState topic.",
    ),
    joint: str | None = typer.Option(
        None, "--joint", metavar="NAME", help="Bag: the JointState joint that is the position."
    ),
    axis: str = typer.Option("x", "--axis", metavar="x|y|z", help="Bag: the squeeze axis."),
    position_is: str = typer.Option(
        "palm",
        "--position-is",
        metavar="palm|gap",
        help="palm: one palm's travel, its partner mirrors it (d = 2 x travel); "
        "gap: the distance between the palms (d = gap(t0) - gap).",
    ),
    columns: str | None = typer.Option(
        None,
        "--columns",
        metavar="time=COL,force=COL,position=COL",
        help="CSV: the columns; position may be gap=COL or compression=COL instead.",
    ),
    units: str | None = typer.Option(
        None,
        "--units",
        metavar="time=s,force=N,position=mm",
        help="CSV: units of columns whose unit the file does not state (default s, N, m).",
    ),
    segment: bool | None = typer.Option(
        None,
        "--segment/--no-segment",
        help="Split the recording into squeezes by force (default: yes for bags, no for CSV).",
    ),
    phase: str | None = typer.Option(
        None,
        "--phase",
        metavar="loading|unloading|all",
        help="Bag/CSV: keep each squeeze up to its peak force, from it, or whole [default: all]. "
        "A squeeze that ruptures is always cut at the rupture (recorded in the log).",
    ),
    position_increases_when: str | None = typer.Option(
        None,
        "--position-increases-when",
        metavar="closing|opening",
        help="Bag/CSV: the position grows as the gripper closes or opens [default: a gap grows "
        "when opening, a compression when closing, one palm's sign is found].",
    ),
    marker_size_cm: float | None = typer.Option(
        None,
        "--marker-size-cm",
        metavar="S",
        help="Images: side of the ArUco marker's black square, cm.",
    ),
    marker_dict: str | None = typer.Option(
        None,
        "--marker-dict",
        metavar="DICT",
        help="Images: ArUco dictionary [default: DICT_4X4_50].",
    ),
    marker_id: int | None = typer.Option(
        None,
        "--marker-id",
        metavar="N",
        help="Images: use the marker with this id (others ignored).",
    ),
    checkerboard: str | None = typer.Option(
        None,
        "--checkerboard",
        metavar="COLSxROWS",
        help="Images: a checkerboard (inner corners) instead of a marker.",
    ),
    square_size_cm: float | None = typer.Option(
        None, "--square-size-cm", metavar="S", help="Images: the checkerboard's square side, cm."
    ),
    color_range: str | None = typer.Option(
        None,
        "--color-range",
        metavar="H,S,V:H,S,V",
        help="Images: the object is this HSV range (OpenCV, H 0-179).",
    ),
    background: tuple[str, str] | None = typer.Option(
        None,
        "--background",
        metavar="TOP_BG SIDE_BG",
        help="Images: the empty scenes; the object is what differs.",
    ),
    debug_dir: str | None = typer.Option(
        None,
        "--debug-dir",
        metavar="DIR",
        help="Images: write annotated images (marker, contour, sizes) here.",
    ),
    append: bool = typer.Option(
        False, "--append", help="Images: add the row to the catalog -o (created if missing)."
    ),
    object_id: str | None = typer.Option(
        None, "--object-id", metavar="ID", help="Id of the squeezed object (required)."
    ),
    weight_n: float | None = typer.Option(
        None, "--weight-n", metavar="W", help="Weight of the object, N (required)."
    ),
    size_cm: tuple[float, float, float] | None = typer.Option(
        None, "--size-cm", metavar="X Y Z", help="Size of the object, cm (x = squeeze axis)."
    ),
    friction_mu: float | None = typer.Option(
        None, "--friction-mu", metavar="MU", help="Palm-object friction coefficient."
    ),
    output: str = typer.Option(
        ...,
        "-o",
        "--output",
        metavar="squeeze.mcap",
        help="The squeeze log to write (with --images: the catalog); - for stdout.",
    ),
    squeezes: int | None = typer.Option(
        None,
        "--squeezes",
        metavar="X",
        help=f"Sim: squeezes per object, at 0.5..1 x the peak force [default: "
        f"{DEFAULT_SIM_SQUEEZES}, the paper's].",
    ),
    objects: str | None = typer.Option(
        None, "--objects", metavar="ID,...", help="Sim: these catalog objects [default: all]."
    ),
    peak_force_n: float | None = typer.Option(
        None,
        "--peak-force-n",
        metavar="F",
        help="Sim: peak force of the largest squeeze, N, for every object [default: the "
        "strain rule, D x strain x size_x].",
    ),
    strain: float | None = typer.Option(
        None,
        "--strain",
        metavar="E",
        help=f"Sim: the default rule's static strain [default: {DEFAULT_SQUEEZE_STRAIN:g}].",
    ),
    ramp_s: float | None = typer.Option(
        None, "--ramp-s", help=f"Sim: force ramp, s [default: {DEFAULT_SIM_RAMP_S:g}]."
    ),
    hold_s: float | None = typer.Option(
        None, "--hold-s", help=f"Sim: hold at the peak force, s [default: {DEFAULT_SIM_HOLD_S:g}]."
    ),
    floating: bool | None = typer.Option(
        None,
        "--floating",
        help="Sim: squeeze without gravity and table (a material test) [default: on the table].",
    ),
    alpha_cm: float | None = typer.Option(
        None,
        "--alpha-cm",
        help="Sim: lattice spacing, cm [default: longest side / 4, 5 particles].",
    ),
    dt_s: float | None = typer.Option(None, "--dt-s", help="Sim: time step, s [default: 0.001]."),
    memory_budget_gib: float | None = typer.Option(
        None,
        "--memory-budget-gib",
        help="Sim: refuse a lattice whose estimated memory exceeds this, GiB [default: 2].",
    ),
    seed: int | None = typer.Option(None, "--seed", help="Sim: noise seed [default: 0].", min=0),
    noise_force_n: float | None = typer.Option(
        None, "--noise-force-n", help="Sim: force noise std, N [default: 0]."
    ),
    noise_position_m: float | None = typer.Option(
        None, "--noise-position-m", help="Sim: noise std of each palm position, m [default: 0]."
    ),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing output."),
    workers: int | None = workers_option(),
    scheduler: str | None = scheduler_option(),
    connect_timeout: float | None = connect_timeout_option(),
    partition_size: int | None = partition_size_option(),
    resume: bool = resume_option(),
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
    parallel (--workers, --scheduler; --resume) into DIR/part-*.mcap squeeze logs and a
    per-object summary DIR/part-*.parquet; characterize reads DIR/ directly.

    Example:

    \b
      deformctl measure --bag run.mcap --wrench-topic /left/wrench \\
        --position-topic /left/palm_pose --object-id sand --weight-n 2.9 -o squeeze.mcap
      deformctl measure datasets/paper/objects.csv --sim -o squeeze.mcap
    """
    sweep = SweepOptions(workers, scheduler, connect_timeout, partition_size, resume)
    sim_opts = _SimOptions(
        squeezes=squeezes,
        objects=objects,
        peak_force_n=peak_force_n,
        strain=strain,
        ramp_s=ramp_s,
        hold_s=hold_s,
        floating=floating,
        alpha_cm=alpha_cm,
        dt_s=dt_s,
        memory_budget_gib=memory_budget_gib,
        seed=seed,
        noise_force_n=noise_force_n,
        noise_position_m=noise_position_m,
    )
    image_opts = ImageOptions(
        marker_size_cm, marker_dict, marker_id, checkerboard, square_size_cm, color_range,
        background, debug_dir, append,
    )  # fmt: skip
    if catalog is not None and not sim:
        raise UsageError(f"a catalog argument ({catalog!r}) needs --sim")
    flag, source = _choose_source(
        {
            "--bag": bag,
            "--csv": csv,
            "--images": images[0] if images else None,
            "--sim": (catalog or "") if sim else None,
        }
    )
    if flag == "--sim":
        _refuse(
            {
                "--wrench-topic": wrench_topics,
                "--position-topic": position_topic,
                "--joint": joint,
                "--columns": columns,
                "--units": units,
                "--segment/--no-segment": segment,
                "--phase": phase,
                "--position-increases-when": position_increases_when,
                "--object-id": object_id,
                "--weight-n": weight_n,
                "--size-cm": size_cm,
                "--friction-mu": friction_mu,
                **image_opts.given(),
            },
            "--sim (the catalog describes the objects)",
        )
        if not source:
            raise UsageError("--sim needs a CATALOG argument (the objects to squeeze)")
        _measure_sim(source, sim_opts, output, force, sweep)
        return
    _refuse(sim_opts.given(), flag)
    if sweep.given():
        raise UsageError(f"{sweep.given()[0]} needs --sim")
    if object_id is None or weight_n is None:
        raise UsageError(f"{flag} needs --object-id and --weight-n")
    if images is not None:
        _refuse(
            {
                "--wrench-topic": wrench_topics, "--position-topic": position_topic,
                "--joint": joint, "--columns": columns, "--units": units,
                "--segment/--no-segment": segment, "--size-cm": size_cm,
                "--phase": phase, "--position-increases-when": position_increases_when,
            },
            "--images",
        )  # fmt: skip
        measure_images(
            images, image_opts, object_id=object_id, weight_n=weight_n,
            friction_mu=friction_mu, output=output, force=force,
        )  # fmt: skip
        return
    _refuse(image_opts.given(), flag)
    if is_stdio(source):
        raise UsageError(f"{flag}: cannot read from stdin; give a file")
    object_record(object_id, weight_n, size_cm=size_cm, friction_mu=friction_mu)  # check early
    check_input_path(source)
    check_output_path(output, force)
    opts = _Options(
        object_id=object_id,
        wrench_topics=list(wrench_topics),
        position_topic=position_topic,
        joint=joint,
        axis=axis,
        position_is=position_is,
        columns=columns,
        units=units,
        segment=segment,
        phase="all" if phase is None else phase,
        position_increases_when=position_increases_when,
        size_x_cm=None if size_cm is None else size_cm[0],
    )
    rec, settings = _SOURCES[flag](source, opts)
    settings["force_rate_hz"] = rec.force_rate_hz
    settings["position_rate_hz"] = rec.position_rate_hz
    obj = object_record(
        object_id,
        weight_n,
        size_cm=size_cm,
        friction_mu=friction_mu,
        force_rate_hz=rec.force_rate_hz,
        position_rate_hz=rec.position_rate_hz,
    )
    provenance = Provenance.from_invocation([source], settings=settings)
    obj = {**obj, **rec.log_fields()}
    write_squeeze_log(output, [obj], rec.squeezes, provenance=provenance, force=force)
    for r in rec.ruptures:
        typer.echo(
            f"warning: {source}: object {object_id!r}: rupture in {r.describe()}: cut off there "
            "(recorded in the log)",
            err=True,
        )
    duration_s = sum(float(s.time_s[-1]) for s in rec.squeezes)
    where = "stdout" if is_stdio(output) else output
    typer.echo(
        f"{where}: {len(rec.squeezes)} squeeze(s) of {object_id!r}, {duration_s:.1f} s, "
        f"force {_hz(rec.force_rate_hz)}, position {_hz(rec.position_rate_hz)}",
        err=True,
    )


def _hz(rate_hz: float) -> str:
    return f"{rate_hz:.4g} Hz" if math.isfinite(rate_hz) else "? Hz"
