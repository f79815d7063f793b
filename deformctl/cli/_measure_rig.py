"""``deformctl measure --bag``: one object's squeeze log from a rig recording, and the options
``--bag`` and ``--csv`` share (``--csv`` runs in :mod:`deformctl.cli._measure_csv`).

The flags become the library's options (:class:`~deformctl.catalog.MeasuredObject`, a
:class:`~deformctl.measure.options.BagSource` and a
:class:`~deformctl.measure.options.Segmentation`, each checked when built) and
:func:`deformctl.measure.stage.measure_recording` reads the recording and writes its log.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated

import typer

from deformctl.artifacts.io import is_stdio
from deformctl.errors import UsageError
from deformctl.measure.options import BagSource, Segmentation

if TYPE_CHECKING:  # pragma: no cover - the readers (pandas, MCAP) load when --bag/--csv runs
    from deformctl.catalog import MeasuredObject

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

    def given(self) -> list[str]:
        """The flags of the source-specific options given (to refuse them elsewhere)."""
        values = [
            ("--wrench-topic", self.wrench_topics),
            ("--position-topic", self.position_topic),
            ("--joint", self.joint),
            ("--columns", self.columns),
            ("--units", self.units),
            ("--segment/--no-segment", self.segment),
            ("--phase", self.phase),
            ("--position-increases-when", self.position_increases_when),
            ("--object-id", self.object_id),
            ("--no-crc-check", not self.crc_check),
        ]
        return [flag for flag, value in values if value not in (None, [], False)]


def bag_source(opts: RigOptions) -> BagSource:
    """The ``--bag`` source options.

    Raises:
        UsageError: a topic missing, or an option out of its rule (exit 2).
    """
    if not opts.wrench_topics:
        raise UsageError("--bag needs --wrench-topic (one, or two for two palms)")
    if opts.position_topic is None:
        raise UsageError("--bag needs --position-topic (PoseStamped or JointState)")
    return BagSource(
        wrench_topics=tuple(opts.wrench_topics),
        position_topic=opts.position_topic,
        joint=opts.joint,
        axis=opts.axis,  # type: ignore[arg-type]
        position_is=opts.position_is,  # type: ignore[arg-type]
        position_increases_when=opts.position_increases_when,  # type: ignore[arg-type]
        crc_check=opts.crc_check,
    )


def segmentation(opts: RigOptions) -> Segmentation:
    """How ``--bag`` and ``--csv`` cut their recording (``--segment``, ``--phase``)."""
    return Segmentation(segment=opts.segment, phase=opts.phase or "all")  # type: ignore[arg-type]


def run(
    path: str,
    opts: RigOptions,
    obj: MeasuredObject,
    output: str,
    force: bool,
) -> None:
    """Read the ``--bag`` recording ``path`` and write its squeeze log."""
    from deformctl.measure.stage import measure_recording

    if is_stdio(path):
        raise UsageError("--bag: cannot read from stdin; give a file")
    source = bag_source(opts)
    rec = measure_recording(
        path, source, obj, output=output, segmentation=segmentation(opts), force=force
    )
    for line in rec.warnings:  # e.g. a bag read without CRC checks (each names the file)
        typer.echo(f"warning: {line}", err=True)
    for r in rec.ruptures:  # each squeeze is kept up to its rupture, recorded in the log
        warning = f"warning: {path}: object {obj.object_id!r}: rupture in {r.describe()}: cut off"
        typer.echo(warning, err=True)
    duration_s = sum(float(s.time_s[-1]) for s in rec.squeezes)
    where = "stdout" if is_stdio(output) else output
    typer.echo(
        f"{where}: {len(rec.squeezes)} squeeze(s) of {obj.object_id!r}, {duration_s:.1f} s, "
        f"force {_hz(rec.force_rate_hz)}, position {_hz(rec.position_rate_hz)}",
        err=True,
    )


def _hz(rate_hz: float) -> str:
    return f"{rate_hz:.4g} Hz" if math.isfinite(rate_hz) else "? Hz"
