"""``deformctl measure bag``: one object's squeeze log from a ROS 2 bag, and the options
``bag``, ``csv`` and ``images`` share (``csv`` runs in :mod:`deformctl.cli._measure_csv`).

The options become the library's (:class:`~deformctl.catalog.MeasuredObject`, a
:class:`~deformctl.measure.options.BagSource` and a
:class:`~deformctl.measure.options.Segmentation`, each checked when built, each from its
:class:`~deformctl.cli._options.OptionGroup`) and
:func:`deformctl.measure.stage.measure_recording` reads the recording and writes its log.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated

import typer

from deformctl.artifacts.io import is_stdio
from deformctl.cli._options import OptionGroup
from deformctl.errors import UsageError
from deformctl.measure.options import BagSource, Segmentation

if TYPE_CHECKING:  # pragma: no cover - the readers (pandas, MCAP) load when a recording is read
    from deformctl.catalog import MeasuredObject

WrenchTopics = Annotated[
    list[str],
    typer.Option("--wrench-topic", metavar="TOPIC", help="WrenchStamped topic; twice: two palms."),
]
PositionTopic = Annotated[
    str | None,
    typer.Option("--position-topic", metavar="TOPIC", help="PoseStamped or JointState topic."),
]
Joint = Annotated[
    str | None, typer.Option("--joint", metavar="NAME", help="The JointState joint to read.")
]
Axis = Annotated[str, typer.Option("--axis", metavar="x|y|z", help="The squeeze axis.")]
PositionIs = Annotated[
    str,
    typer.Option(
        "--position-is",
        metavar="travel|palm|gap",
        help="d = the column's travel, 2 x one palm's travel, or gap(t0) - gap.",
    ),
]
Columns = Annotated[
    str | None,
    typer.Option(
        "--columns",
        metavar="ROLE=COL,...",
        help="Columns of time, force, compression|position|gap [default: by name].",
    ),
]
Units = Annotated[
    str | None,
    typer.Option(
        "--units",
        metavar="ROLE=UNIT,...",
        help="Units the file does not state [default: s, N, m].",
    ),
]
Segment = Annotated[
    bool | None,
    typer.Option(
        "--segment/--no-segment",
        help="Cut into squeezes by force [default: bag yes, CSV no].",
    ),
]
Phase = Annotated[
    str | None,
    typer.Option(
        "--phase",
        metavar="PHASE",
        help="loading, unloading or all [default: all]; ruptures are cut.",
    ),
]
PositionIncreasesWhen = Annotated[
    str | None,
    typer.Option(
        "--position-increases-when",
        metavar="WHEN",
        help="closing or opening [default: found].",
    ),
]
ObjectId = Annotated[str | None, typer.Option("--object-id", metavar="ID", help="The object's id.")]
WeightN = Annotated[
    float | None, typer.Option("--weight-n", metavar="W", help="The object's weight, N.")
]
SizeCm = Annotated[
    tuple[float, float, float] | None,
    typer.Option("--size-cm", metavar="X Y Z", help="The object's size, cm (x: squeeze axis)."),
]
NoCrcCheck = Annotated[
    bool,
    typer.Option("--no-crc-check", help="Read a damaged or cut bag anyway, with a warning."),
]
FrictionMu = Annotated[
    float | None,
    typer.Option("--friction-mu", metavar="MU", help="Palm-object friction coefficient."),
]


@dataclass(frozen=True)
class ObjectFlags:
    """What the command line says of the object (for ``measure csv``, each file's
    ``--objects-from`` row wins); checked when the object is built
    (:class:`deformctl.catalog.MeasuredObject`, :func:`deformctl.measure.csv_objects`)."""

    object_id: str | None = None
    weight_n: float | None = None
    size_cm: tuple[float, float, float] | None = None
    friction_mu: float | None = None

    def measured(self, command: str) -> MeasuredObject:
        """The one object ``command`` (``measure bag``, ``measure images``) measures.

        Raises:
            UsageError: no ``--object-id`` or no ``--weight-n`` (exit 2).
        """
        from deformctl.catalog import MeasuredObject

        if self.object_id is None or self.weight_n is None:
            raise UsageError(f"{command} needs --object-id and --weight-n")
        return MeasuredObject(
            self.object_id, self.weight_n, size_cm=self.size_cm, friction_mu=self.friction_mu
        )


#: ``--object-id``, ``--weight-n``, ``--size-cm``, ``--friction-mu`` as one ``ObjectFlags``.
OBJECT = OptionGroup(
    "named",
    (
        ("object_id", ObjectId, None),
        ("weight_n", WeightN, None),
        ("size_cm", SizeCm, None),
        ("friction_mu", FrictionMu, None),
    ),
    ObjectFlags,
)
#: The same without ``--size-cm`` (``measure images`` measures the size).
IMAGE_OBJECT = OptionGroup(
    "named", tuple(o for o in OBJECT.options if o[0] != "size_cm"), ObjectFlags
)


def segmentation(*, segment: bool | None, phase: str | None) -> Segmentation:
    """How ``measure bag`` and ``measure csv`` cut their recording (``--segment``, ``--phase``)."""
    return Segmentation(segment=segment, phase=phase or "all")  # type: ignore[arg-type]


#: ``--segment/--no-segment`` and ``--phase`` as one :class:`Segmentation`.
CUT = OptionGroup("cut", (("segment", Segment, None), ("phase", Phase, None)), segmentation)


def bag_source(
    *,
    wrench_topics: list[str],
    position_topic: str | None,
    joint: str | None,
    axis: str,
    position_is: str,
    position_increases_when: str | None,
    no_crc_check: bool,
) -> BagSource:
    """The bag's topics and how to read them.

    Raises:
        UsageError: a topic missing, or an option out of its rule (exit 2).
    """
    if not wrench_topics:
        raise UsageError("measure bag needs --wrench-topic (one, or two for two palms)")
    if position_topic is None:
        raise UsageError("measure bag needs --position-topic (PoseStamped or JointState)")
    return BagSource(
        wrench_topics=tuple(wrench_topics),
        position_topic=position_topic,
        joint=joint,
        axis=axis,  # type: ignore[arg-type]
        position_is=position_is,  # type: ignore[arg-type]
        position_increases_when=position_increases_when,  # type: ignore[arg-type]
        crc_check=not no_crc_check,
    )


#: The bag's topics and reading options as one :class:`BagSource`.
BAG = OptionGroup(
    "source",
    (
        ("wrench_topics", WrenchTopics, []),
        ("position_topic", PositionTopic, None),
        ("joint", Joint, None),
        ("axis", Axis, "x"),
        ("position_is", PositionIs, "palm"),
        ("position_increases_when", PositionIncreasesWhen, None),
        ("no_crc_check", NoCrcCheck, False),
    ),
    bag_source,
)


def run(
    path: str,
    source: BagSource,
    cut: Segmentation,
    obj: MeasuredObject,
    output: str,
    force: bool,
    quiet: bool = False,
) -> None:
    """Read the bag ``path`` and write its squeeze log (with its summary line unless
    ``quiet``)."""
    from deformctl.measure.stage import measure_recording

    if is_stdio(path):
        raise UsageError("measure bag: cannot read from stdin; give a file")
    rec = measure_recording(path, source, obj, output=output, segmentation=cut, force=force)
    for line in rec.warnings:  # e.g. a bag read without CRC checks (each names the file)
        typer.echo(f"warning: {line}", err=True)
    for r in rec.ruptures:  # each squeeze is kept up to its rupture, recorded in the log
        warning = f"warning: {path}: object {obj.object_id!r}: rupture in {r.describe()}: cut off"
        typer.echo(warning, err=True)
    if quiet:
        return
    duration_s = sum(float(s.time_s[-1]) for s in rec.squeezes)
    where = "stdout" if is_stdio(output) else output
    typer.echo(
        f"{where}: {len(rec.squeezes)} squeeze(s) of {obj.object_id!r}, {duration_s:.1f} s, "
        f"force {_hz(rec.force_rate_hz)}, position {_hz(rec.position_rate_hz)}",
        err=True,
    )


def _hz(rate_hz: float) -> str:
    return f"{rate_hz:.4g} Hz" if math.isfinite(rate_hz) else "? Hz"
