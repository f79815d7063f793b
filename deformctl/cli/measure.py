"""``deformctl measure``: squeeze logs from a source (a ROS 2 bag or a CSV export).

Exactly one source option is given per run; each source has a reader in :data:`_SOURCES` that
checks its own options and returns a :class:`~deformctl.measure.Recording`. The command then
writes the squeezes, the object's catalog-like row and the provenance as one squeeze log. A new
source (the simulator over a catalog) is one more option and one more reader. ``--images``
writes an object-catalog row instead (:mod:`deformctl.cli._measure_images`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import typer

from deformctl.artifacts import Provenance, check_input_path, check_output_path, write_squeeze_log
from deformctl.artifacts.io import is_stdio
from deformctl.cli import app
from deformctl.cli._common import translate_errors
from deformctl.cli._measure_images import ImageOptions, measure_images
from deformctl.errors import UsageError
from deformctl.measure import Recording, object_record, read_csv_export, read_ros2_bag


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
    }
    rec = read_csv_export(
        path,
        columns=columns,
        units=units,
        object_id=opts.object_id,
        position_is=opts.position_is,  # type: ignore[arg-type]
        segment=settings["segment"],
    )
    return rec, settings


#: source option → its reader; exactly one source is given per run.
_SOURCES: dict[str, Callable[[str, _Options], tuple[Recording, dict[str, Any]]]] = {
    "--bag": _from_bag,
    "--csv": _from_csv,
}
#: source options that write a catalog row instead (their own module, not a Recording reader).
_CATALOG_SOURCES = ("--images",)


def _choose_source(given: Mapping[str, str | None]) -> tuple[str, str]:
    chosen = [(flag, value) for flag, value in given.items() if value is not None]
    if len(chosen) != 1:
        what = (
            "no source"
            if not chosen
            else "several sources (" + ", ".join(f for f, _ in chosen) + ")"
        )
        raise UsageError(f"{what}: give exactly one of {', '.join([*_SOURCES, *_CATALOG_SOURCES])}")
    return chosen[0]


@app.command()
@translate_errors
def measure(
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
    force: bool = typer.Option(False, "--force", help="Overwrite an existing output."),
) -> None:
    """Turn a rig recording into a squeeze log (MCAP) of one object.

    Force and position are aligned by timestamp (position interpolated onto the force samples),
    the compression d between the palms is formed, and the recording is cut into squeezes. The
    log stores the object's weight (and size, friction when given), the source sample rates,
    and provenance (input sha256, command line, settings).

    Example:

    \b
      deformctl measure --bag run.mcap --wrench-topic /left/wrench \\
        --position-topic /left/palm_pose --object-id sand --weight-n 2.9 -o squeeze.mcap
    """
    image_opts = ImageOptions(
        marker_size_cm, marker_dict, marker_id, checkerboard, square_size_cm, color_range,
        background, debug_dir, append,
    )  # fmt: skip
    flag, source = _choose_source(
        {"--bag": bag, "--csv": csv, "--images": images[0] if images else None}
    )
    if object_id is None or weight_n is None:
        raise UsageError(f"{flag} needs --object-id and --weight-n")
    if images is not None:
        _refuse(
            {
                "--wrench-topic": wrench_topics, "--position-topic": position_topic,
                "--joint": joint, "--columns": columns, "--units": units,
                "--segment/--no-segment": segment, "--size-cm": size_cm,
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
    write_squeeze_log(output, [obj], rec.squeezes, provenance=provenance, force=force)
    duration_s = sum(float(s.time_s[-1]) for s in rec.squeezes)
    where = "stdout" if is_stdio(output) else output
    typer.echo(
        f"{where}: {len(rec.squeezes)} squeeze(s) of {object_id!r}, {duration_s:.1f} s, "
        f"force {_hz(rec.force_rate_hz)}, position {_hz(rec.position_rate_hz)}",
        err=True,
    )


def _hz(rate_hz: float) -> str:
    return f"{rate_hz:.4g} Hz" if math.isfinite(rate_hz) else "? Hz"
