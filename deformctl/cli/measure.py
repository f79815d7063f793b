"""``deformctl measure sim|csv|bag|images``: squeeze logs (or a catalog row) from one source.

One subcommand per source, each building its library options from its options (the groups
several share are declared once, :class:`deformctl.cli._options.OptionGroup`) and running in its
own module: :mod:`deformctl.cli._measure_sim` (the simulator), :mod:`deformctl.cli._measure_csv`
(CSV exports), :mod:`deformctl.cli._measure_rig` (a ROS 2 bag),
:mod:`deformctl.cli._measure_images` (a catalog row from two images). The old flag forms
(``measure --csv FILE``) still run, with a deprecation line (:mod:`deformctl.cli._sources`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated

import typer

from deformctl.cli import _image_options as img
from deformctl.cli import _measure_csv, _measure_images, _measure_rig, _measure_sim
from deformctl.cli import _options as opt
from deformctl.cli._common import translate_errors
from deformctl.cli._sources import MeasureGroup, source_group
from deformctl.cli._summary import Quiet, stderr_console
from deformctl.errors import UsageError
from deformctl.parallel import SweepOptions

if TYPE_CHECKING:  # pragma: no cover - the library's options load when a source runs
    from deformctl.measure.csv.batch import CsvFileTask
    from deformctl.measure.csv.options import CsvOptions
    from deformctl.measure.options import BagSource, Segmentation
    from deformctl.measure.stage import SimulateCatalogTask

Output = Annotated[
    str,
    typer.Option("-o", "--output", metavar="squeeze.mcap", help="The squeeze log; - for stdout."),
]


def measure() -> None:
    """Turn simulated squeezes, CSV exports or a ROS 2 bag into a squeeze log (MCAP).

    One subcommand per source. The log stores each object's weight (and size, friction when
    given), the source sample rates and provenance (input sha256, command line, settings).
    measure images writes an object's catalog row from two photos instead.

    Example: deformctl measure sim datasets/paper/objects.csv -o squeeze.mcap
    """


@translate_errors
@opt.with_options(_measure_sim.TASK, opt.SWEEP)
def sim(
    catalog: Annotated[
        str,
        typer.Argument(
            metavar="CATALOG",
            help="Object catalog with material values, CSV or Parquet; - for stdin.",
        ),
    ],
    output: Annotated[
        str,
        typer.Option("-o", "--output", metavar="squeeze.mcap|DIR/", help="The squeeze log."),
    ],
    objects: opt.Objects = None,
    quiet: Quiet = False,
    force: opt.Force = False,
    task: SimulateCatalogTask = None,  # type: ignore[assignment]  # built by the option group
    sweep: SweepOptions = opt.NO_SWEEP,
) -> None:
    """Squeeze every catalog object --squeezes times in the simulator (force ramp, then hold).

    The log stores each object's catalog row, the settings and the seed. A dataset output
    (-o DIR/) runs the objects in parallel into DIR/_logs/ and DIR/part-*.parquet.

    Example: deformctl measure sim objects.csv -o squeeze.mcap
    """
    _measure_sim.run(catalog, task, objects, output, force, sweep, stderr_console(), quiet)


@translate_errors
@opt.with_options(_measure_csv.READ, _measure_rig.CUT, _measure_rig.OBJECT, opt.SWEEP)
def csv(
    files: Annotated[
        list[str],
        typer.Argument(metavar="FILE...", help="CSV exports, one object each; - for stdin."),
    ],
    output: Annotated[
        str | None,
        typer.Option(
            "-o",
            "--output",
            metavar="squeeze.mcap|DIR/",
            help="The squeeze log (needed unless --dry-run).",
        ),
    ] = None,
    dry_run: _measure_csv.DryRun = False,
    objects_from: _measure_csv.ObjectsFrom = None,
    quiet: Quiet = False,
    force: opt.Force = False,
    options: CsvOptions = None,  # type: ignore[assignment]  # built by the option groups
    cut: Segmentation = None,  # type: ignore[assignment]
    named: _measure_rig.ObjectFlags = None,  # type: ignore[assignment]
    sweep: SweepOptions = opt.NO_SWEEP,
) -> None:
    """Read CSV exports (one object each) into one squeeze log, or a dataset (-o DIR/).

    A preamble, the header and units in the names or in a units row are found; what was found
    is printed once per distinct line. --dry-run prints what would be detected in each file
    (header row, preamble, delimiter, decimal mark, units, column roles, the position's
    reading, the force sign) and writes nothing.

    Example: deformctl measure csv data/*.csv --position-is gap -o squeeze.mcap
    """
    from deformctl.measure.csv.batch import CsvFileTask

    task: CsvFileTask = CsvFileTask(options, cut)
    if dry_run:
        _measure_csv.dry_run(files, task, objects_from, named, sweep)
        return
    if output is None:
        raise UsageError("measure csv needs -o/--output (or --dry-run)")
    _measure_csv.run(files, task, objects_from, named, output, force, sweep, quiet)


@translate_errors
@opt.with_options(_measure_rig.BAG, _measure_rig.CUT, _measure_rig.OBJECT)
def bag(
    path: Annotated[
        str,
        typer.Argument(
            metavar="BAG.mcap|BAG/",
            help="A ROS 2 bag: one MCAP file, or a rosbag2 folder (metadata.yaml, .mcap files).",
        ),
    ],
    output: Output,
    quiet: Quiet = False,
    force: opt.Force = False,
    source: BagSource = None,  # type: ignore[assignment]  # built by the option groups
    cut: Segmentation = None,  # type: ignore[assignment]
    named: _measure_rig.ObjectFlags = None,  # type: ignore[assignment]
) -> None:
    """Read a ROS 2 bag (wrench and position topics) into one object's squeeze log.

    Force and position are aligned by timestamp, the compression d between the palms is
    formed and the recording is cut into squeezes.

    Example: deformctl measure bag run.mcap --wrench-topic /left/wrench
    --position-topic /left/palm_pose --object-id sand --weight-n 2.9 -o squeeze.mcap
    """
    obj = named.measured("measure bag")
    _measure_rig.run(path, source, cut, obj, output, force, quiet)


@translate_errors
@opt.with_options(img.IMAGE, _measure_rig.IMAGE_OBJECT)
def images(
    top: Annotated[str, typer.Argument(help="The top view, with a scale reference.")],
    side: Annotated[str, typer.Argument(help="The side view, with a scale reference.")],
    output: Annotated[
        str,
        typer.Option("-o", "--output", metavar="catalog.csv", help="The catalog; - for stdout."),
    ],
    quiet: Quiet = False,
    force: opt.Force = False,
    opts: img.ImageOptions = None,  # type: ignore[assignment]  # built by the option groups
    named: _measure_rig.ObjectFlags = None,  # type: ignore[assignment]
) -> None:
    """Measure an object's size in a top and a side image; write its catalog row.

    Example: deformctl measure images top.png side.png --marker-size-cm 4 --object-id cup
    --weight-n 2.9 -o catalog.csv
    """
    obj = named.measured("measure images")
    _measure_images.measure_images((top, side), opts, obj, output=output, force=force, quiet=quiet)


#: ``measure`` and its subcommands (registered on the root app as one group).
GROUP = source_group(MeasureGroup, measure, (sim, csv, bag, images))
measure.group = GROUP  # type: ignore[attr-defined]
