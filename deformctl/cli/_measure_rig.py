"""``deformctl measure --bag``: one object's squeeze log from a rig recording, and the options
``--bag`` and ``--csv`` share (``--csv`` runs in :mod:`deformctl.cli._measure_csv`).

The bag reader (:func:`deformctl.measure.read_ros2_bag`) is behind :data:`READERS`, which checks
its own options and returns the recording and the settings the provenance records;
:func:`deformctl.measure.recording_log` writes the log.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Annotated, Any

import typer

from deformctl.artifacts import check_input_path, check_output_path
from deformctl.artifacts.io import is_stdio
from deformctl.catalog import object_record
from deformctl.errors import UsageError
from deformctl.measure import Recording, read_ros2_bag, recording_log

Bag = Annotated[
    str | None,
    typer.Option(
        "--bag", metavar="BAG.mcap", help="Source: a ROS 2 bag, one MCAP file (ros2msg/cdr)."
    ),
]
Csv = Annotated[
    str | None,
    typer.Option(
        "--csv",
        metavar="FILE",
        help="Source: CSV exports, one object each (more files follow as arguments; - for "
        "stdin): a preamble, the header, units in the names or a units row are found.",
    ),
]
WrenchTopics = Annotated[
    list[str],
    typer.Option(
        "--wrench-topic",
        metavar="TOPIC",
        help="Bag: geometry_msgs/msg/WrenchStamped topic; repeat for the second palm.",
    ),
]
PositionTopic = Annotated[
    str | None,
    typer.Option(
        "--position-topic",
        metavar="TOPIC",
        help="Bag: geometry_msgs/msg/PoseStamped or sensor_msgs/msg/JointState topic.",
    ),
]
Joint = Annotated[
    str | None,
    typer.Option("--joint", metavar="NAME", help="Bag: the JointState joint that is the position."),
]
Axis = Annotated[str, typer.Option("--axis", metavar="x|y|z", help="Bag: the squeeze axis.")]
PositionIs = Annotated[
    str,
    typer.Option(
        "--position-is",
        metavar="palm|gap",
        help="palm: one palm's travel, its partner mirrors it (d = 2 x travel); "
        "gap: the distance between the palms (d = gap(t0) - gap).",
    ),
]
Columns = Annotated[
    str | None,
    typer.Option(
        "--columns",
        metavar="time=COL,force=COL,compression=COL",
        help="CSV: the columns of these roles (the others are found by name: time, force, "
        "compression, position or gap); position may be gap=COL or compression=COL.",
    ),
]
Units = Annotated[
    str | None,
    typer.Option(
        "--units",
        metavar="time=s,force=N,compression=mm",
        help="CSV: units of the columns whose unit the file does not state (default s, N, m, "
        "with a warning); one that contradicts the file is an error.",
    ),
]
Segment = Annotated[
    bool | None,
    typer.Option(
        "--segment/--no-segment",
        help="Split the recording into squeezes by force (default: yes for bags, no for CSV).",
    ),
]
Phase = Annotated[
    str | None,
    typer.Option(
        "--phase",
        metavar="loading|unloading|all",
        help="Keep each squeeze up to its peak force, from it, or whole [default: all]. A "
        "squeeze that ruptures is always cut at the rupture (recorded in the log).",
    ),
]
PositionIncreasesWhen = Annotated[
    str | None,
    typer.Option(
        "--position-increases-when",
        metavar="closing|opening",
        help="The position grows as the gripper closes or opens [default: a gap grows when "
        "opening, a compression when closing; one palm's sign is found].",
    ),
]
ObjectId = Annotated[
    str | None,
    typer.Option("--object-id", metavar="ID", help="Id of the squeezed object (required)."),
]
WeightN = Annotated[
    float | None,
    typer.Option("--weight-n", metavar="W", help="Weight of the object, N (required)."),
]
SizeCm = Annotated[
    tuple[float, float, float] | None,
    typer.Option("--size-cm", metavar="X Y Z", help="Size of the object, cm (x = squeeze axis)."),
]
NoCrcCheck = Annotated[
    bool,
    typer.Option(
        "--no-crc-check",
        help="Bag: read a damaged bag anyway: chunks whatever their CRC, a cut file up to its "
        "last complete record (a warning says so).",
    ),
]
FrictionMu = Annotated[
    float | None,
    typer.Option("--friction-mu", metavar="MU", help="Palm-object friction coefficient."),
]


@dataclass(frozen=True)
class RigOptions:
    """The recording options as given on the command line (None / empty: not given)."""

    object_id: str | None
    wrench_topics: list[str]
    position_topic: str | None
    joint: str | None
    axis: str
    position_is: str
    columns: str | None
    units: str | None
    segment: bool | None
    phase: str | None = None
    position_increases_when: str | None = None
    crc_check: bool = True

    def given(self) -> dict[str, object]:
        """Flag → value of the source-specific options (for refusing them elsewhere)."""
        return {
            "--wrench-topic": self.wrench_topics,
            "--position-topic": self.position_topic,
            "--joint": self.joint,
            "--columns": self.columns,
            "--units": self.units,
            "--segment/--no-segment": self.segment,
            "--phase": self.phase,
            "--position-increases-when": self.position_increases_when,
            "--object-id": self.object_id,
            "--no-crc-check": not self.crc_check,
        }


def _from_bag(
    path: str, opts: RigOptions, size_x_cm: float | None
) -> tuple[Recording, dict[str, Any]]:
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
        "phase": opts.phase or "all",
        "position_increases_when": opts.position_increases_when,
    }
    if not opts.crc_check:  # recorded only when off: the logs of checked bags are unchanged
        settings["crc_check"] = False
    return _read(read_ros2_bag, path, opts, size_x_cm, settings), settings


def _read(
    reader: Callable[..., Recording],
    path: str,
    opts: RigOptions,
    size_x_cm: float | None,
    settings: dict[str, Any],
) -> Recording:
    """``reader`` with the recorded settings (all but ``source``) as its keyword arguments."""
    options = {k: v for k, v in settings.items() if k != "source"}
    return reader(path, object_id=str(opts.object_id), size_x_cm=size_x_cm, **options)


#: source option → its reader; exactly one source is given per run.
READERS: dict[str, Callable[[str, RigOptions, float | None], tuple[Recording, dict[str, Any]]]] = {
    "--bag": _from_bag,
}


def run(
    flag: str,
    source: str,
    opts: RigOptions,
    weight_n: float,
    size_cm: tuple[float, float, float] | None,
    friction_mu: float | None,
    output: str,
    force: bool,
) -> None:
    """Read the recording ``source`` of ``--bag`` / ``--csv`` and write its squeeze log."""
    if is_stdio(source):
        raise UsageError(f"{flag}: cannot read from stdin; give a file")
    object_id = str(opts.object_id)
    obj = object_record(object_id, weight_n, size_cm=size_cm, friction_mu=friction_mu)
    check_input_path(source)
    check_output_path(output, force)
    rec, settings = READERS[flag](source, opts, None if size_cm is None else size_cm[0])
    recording_log(source, rec, obj, settings, output=output, force=force)
    for line in rec.warnings:  # e.g. a bag read without CRC checks (each names the file)
        typer.echo(f"warning: {line}", err=True)
    for r in rec.ruptures:  # each squeeze is kept up to its rupture, recorded in the log
        warning = f"warning: {source}: object {object_id!r}: rupture in {r.describe()}: cut off"
        typer.echo(warning, err=True)
    duration_s = sum(float(s.time_s[-1]) for s in rec.squeezes)
    where = "stdout" if is_stdio(output) else output
    typer.echo(
        f"{where}: {len(rec.squeezes)} squeeze(s) of {object_id!r}, {duration_s:.1f} s, "
        f"force {_hz(rec.force_rate_hz)}, position {_hz(rec.position_rate_hz)}",
        err=True,
    )


def _hz(rate_hz: float) -> str:
    return f"{rate_hz:.4g} Hz" if math.isfinite(rate_hz) else "? Hz"
