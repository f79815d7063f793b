"""The ``measure`` stage: squeeze logs from a recording or from a catalog in the simulator.

:func:`recording_log` writes a rig recording's squeeze log (``--bag``, ``--csv``);
:func:`simulate_catalog_file` squeezes a catalog into one log and, at scale,
:class:`SimulateCatalogTask` is the sweep task of one object and :func:`simulate_catalog_sweep`
runs a catalog into a dataset directory.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import pandas as pd
import pyarrow as pa

from deformctl.artifacts import check_output_path, read_catalog, write_squeeze_log
from deformctl.artifacts.dataset import LogPartWriter, dataset_fingerprint
from deformctl.artifacts.io import check_input_path
from deformctl.artifacts.mcap import LOG_EPOCH_NS
from deformctl.artifacts.provenance import Provenance, input_digest
from deformctl.catalog import CatalogObject, MeasuredObject, catalog_objects, select_objects
from deformctl.errors import InputDataError, UsageError
from deformctl.measure.csv.options import CsvOptions
from deformctl.measure.csv.reader import read_csv
from deformctl.measure.options import (
    DEFAULT_SEGMENTATION,
    BagSource,
    Segmentation,
    SqueezeProtocol,
)
from deformctl.measure.recording import Recording
from deformctl.measure.ros2_bag import read_bag
from deformctl.measure.sim import (
    SqueezeProgress,
    check_squeeze_settings,
    squeeze_objects,
)
from deformctl.parallel import (
    SweepOptions,
    SweepSummary,
    TaskOutput,
    map_in_order,
    run_sweep,
    single_file_workers,
)
from deformctl.parallel.auto import AUTO, Auto
from deformctl.scene import DEFAULT_SCENE_HZ
from deformctl.series import SqueezeSeries

if TYPE_CHECKING:  # pragma: no cover - typing only; the simulator is imported when used
    from deformctl.sim import SimSettings
    from deformctl.sim.engine import RunPlan
    from deformctl.sim.objects import ObjectSpec


#: Rows of a ``measure --sim`` dataset: one per object squeezed (the series are in the logs).
MEASURE_SCHEMA = pa.schema(
    [
        pa.field("object_id", pa.string(), nullable=False),
        pa.field("squeezes", pa.int64(), nullable=False),
        pa.field("samples", pa.int64(), nullable=False),
        pa.field("duration_s", pa.float64(), nullable=False, metadata={"unit": "s"}),
        pa.field("peak_force_n", pa.float64(), nullable=False, metadata={"unit": "N"}),
    ]
)


@dataclass(frozen=True)
class SimulateCatalogTask:
    """``measure --sim`` for one catalog object (a picklable sweep task).

    The item carries the object's catalog row and its catalog position under
    ``"_position"``, or its parsed object and squeeze plan under ``"_planned"`` instead of the
    row (every row the caller could plan); the noise stream is derived from (seed, position) as in
    the serial run.

    Attributes:
        protocol: the squeezes (:class:`~deformctl.measure.options.SqueezeProtocol`: number,
            peak force or strain, ramp, hold, gravity, noise).
        settings: the :class:`~deformctl.sim.SimSettings` (a preset's object model).
        seed: the run's noise seed.
        sim_preset: the name of the preset ``settings`` came from (recorded in the log).
        log_epoch_ns: where the log's squeezes begin, ns since the Unix epoch (they are laid
            end to end from there).
        scene_hz: scene frames per simulated second in the log (:mod:`deformctl.scene`; 0:
            none).
    """

    #: loaded by the fork server of local workers (:mod:`deformctl.sim._warm_worker`)
    worker_preload: ClassVar[tuple[str, ...]] = ("deformctl.sim._warm_worker",)

    protocol: SqueezeProtocol
    settings: SimSettings
    seed: int = 0
    sim_preset: str | None = None
    log_epoch_ns: int = LOG_EPOCH_NS
    scene_hz: float = DEFAULT_SCENE_HZ

    def __post_init__(self) -> None:
        """Refuse a strain at or above the densification limit or a bad scene rate, once: the
        runs below take the task as checked.

        Raises:
            UsageError: either one (exit 2).
        """
        check_squeeze_settings(self.protocol, self.settings, self.scene_hz)

    def __call__(self, item: dict[str, Any]) -> TaskOutput:
        """Squeeze one object: its summary row, its (object row, squeezes) as the payload."""
        planned = item.get("_planned")  # (object, plan) parsed and planned once by the caller
        if planned is None:  # a row the caller could not plan: parsed here (and refused)
            row = {k: v for k, v in item.items() if k != "_position"}
            (obj,) = catalog_objects(pd.DataFrame([row]))
            planned = (obj, self.plan(obj.to_sim_spec()))
        objects, series = squeeze_objects(
            [planned[0]],
            [planned[1]],
            protocol=self.protocol,
            settings=self.settings,
            seed=self.seed,
            first_index=int(item["_position"]),
            scene_hz=self.scene_hz,
        )
        summary = {
            "object_id": str(objects[0]["object_id"]),
            "squeezes": len(series),
            "samples": int(sum(len(s.time_s) for s in series)),
            "duration_s": float(sum(float(s.time_s[-1]) for s in series)),
            "peak_force_n": float(objects[0]["sim_peak_force_n"]),
        }
        return TaskOutput(rows=[summary], payload=(objects[0], series))

    def plan(self, spec: ObjectSpec) -> RunPlan:
        """The plan of ``spec``'s squeezes under this task
        (:func:`deformctl.sim.protocols.plan_squeeze`: steps, scene frames, memory)."""
        from deformctl.sim.protocols import plan_squeeze

        p = self.protocol
        return plan_squeeze(
            spec, ramp_s=p.ramp_s, hold_s=p.hold_s, settings=self.settings, scene_hz=self.scene_hz
        )


def sim_provenance(
    catalog_path: str, task: SimulateCatalogTask, object_ids: list[str]
) -> Provenance:
    """The provenance of a ``measure --sim`` log: the catalog, the seed and every setting."""
    return Provenance.from_invocation(
        [catalog_path],
        seed=task.seed,
        settings={
            "source": "sim",
            **task.protocol.as_dict(),
            "scene_hz": task.scene_hz,
            "peak_force_rule": "peak_force_n"
            if task.protocol.peak_force_n is not None
            else "strain",
            "objects": object_ids,
            "sim_preset": task.sim_preset,
            "sim_settings": dataclasses.asdict(task.settings),
            "log_epoch_ns": task.log_epoch_ns,
        },
    )


#: Bytes one sample of a squeeze log held in memory costs: the series arrays and the JSON message
#: built from them before the log is written.
LOG_SAMPLE_BYTES = 400


def _plan(
    catalog: pd.DataFrame, task: SimulateCatalogTask, path: str, *, single_log: bool
) -> list[tuple[CatalogObject, RunPlan] | None]:
    """Each row parsed, with its squeeze's plan (:func:`deformctl.sim.protocols.plan_squeeze`:
    spec and steps worked out once), refusing before simulating a run above the memory budget.

    Each object's squeeze (model, steps, scene frames) must fit; a single-file squeeze log, built
    in memory (MCAP's summary comes at the end), must fit as a whole. With ``single_log`` a bad
    row is refused first (exit 65); in a dataset it is None here and fails alone in its worker.

    Raises:
        InputDataError: ``single_log`` and a row the simulator refuses (exit 65).
        UsageError: one line naming the estimate, the budget and the option (exit 2).
    """
    from deformctl.sim.engine import GIB

    settings, p = task.settings, task.protocol
    planned: list[tuple[CatalogObject, RunPlan] | None] = []
    for record in catalog.to_dict("records"):
        try:
            obj = CatalogObject.from_row(record)
            spec = obj.to_sim_spec(path=path)
        except InputDataError:
            if single_log:
                raise
            planned.append(None)  # a dataset's bad row fails alone, in its worker
            continue
        planned.append((obj, task.plan(spec)))
    samples = sum((plan.steps + 1.0) * p.squeezes for _, plan in filter(None, planned))
    estimate = samples * LOG_SAMPLE_BYTES
    if single_log and estimate > settings.memory_budget_gib * GIB:
        raise UsageError(
            f"one squeeze log of {len(catalog):,} objects x {p.squeezes} squeezes is "
            f"{samples:.3g} samples, an estimated {estimate / GIB:.3g} GiB in memory, above the "
            f"memory budget of {settings.memory_budget_gib:g} GiB; write a dataset directory "
            "(-o DIR/) or raise --memory-budget-gib"
        )
    return planned


def simulate_catalog_file(
    catalog_path: str,
    task: SimulateCatalogTask,
    *,
    output: str,
    object_ids: Sequence[str] | None = None,
    progress: SqueezeProgress | None = None,
    force: bool = False,
    workers: int | Auto | None = AUTO,
) -> tuple[list[dict[str, Any]], list[SqueezeSeries]]:
    """``measure CATALOG --sim -o LOG``: squeeze every (selected) object into one squeeze log.

    Every row is checked before anything is simulated (a row without material values is
    refused, naming the object). With ``workers`` > 1 the objects are squeezed on that many
    local processes (:func:`deformctl.parallel.map_in_order`, one :class:`SimulateCatalogTask`
    per object); each object's noise stream depends only on the seed and its position, so the
    log is byte for byte the one-process log. ``workers="auto"`` (or None): the count of least
    measured wall time (:mod:`deformctl.parallel.auto`; the first objects are squeezed here).

    Returns:
        The objects' rows and the squeezes written (see
        :func:`deformctl.measure.sim.simulate_squeezes`).

    Raises:
        OutputExistsError: ``output`` exists and ``force`` is false (exit 1).
        UsageError: an unknown object id, or a squeeze option out of range (exit 2).
        InputDataError: a row the simulator refuses (exit 65).
    """
    check_output_path(output, force)
    catalog = select_objects(read_catalog(catalog_path), object_ids)
    planned = [p for p in _plan(catalog, task, catalog_path, single_log=True) if p is not None]
    provenance = sim_provenance(catalog_path, task, list(catalog["object_id"]))
    n_workers = single_file_workers(workers, len(catalog))
    if n_workers != 1:
        items = [
            {"object_id": obj.object_id, "_position": i, "_planned": (obj, plan)}
            for i, (obj, plan) in enumerate(planned)
        ]
        objects, series = _squeeze_in_workers(items, task, n_workers, progress)
    else:
        objects, series = squeeze_objects(
            [obj for obj, _ in planned],
            [plan for _, plan in planned],
            protocol=task.protocol,
            settings=task.settings,
            seed=task.seed,
            progress=progress,
            scene_hz=task.scene_hz,
        )
    write_squeeze_log(
        output, objects, series, provenance=provenance, force=force, epoch_ns=task.log_epoch_ns
    )
    return objects, series


def _positioned_items(
    catalog: pd.DataFrame, planned: list[tuple[CatalogObject, RunPlan] | None]
) -> list[dict[str, Any]]:
    """The :class:`SimulateCatalogTask` items of ``catalog``: each row's object with its plan
    (the row itself where it has none) and its ``_position``."""
    return [
        {**rec, "_position": i}
        if plan is None
        else {"object_id": rec["object_id"], "_position": i, "_planned": plan}
        for i, (rec, plan) in enumerate(zip(catalog.to_dict("records"), planned, strict=True))
    ]


def _squeeze_in_workers(
    items: list[dict[str, Any]],
    task: SimulateCatalogTask,
    workers: int | Auto,
    progress: SqueezeProgress | None,
) -> tuple[list[dict[str, Any]], list[SqueezeSeries]]:
    """The squeezes of ``items`` (each an object with its spec) with one task per object on
    local processes."""
    finished = [0]

    def done(i: int, _: object) -> None:
        finished[0] += 1
        if progress is not None:
            progress(str(items[i]["object_id"]), finished[0], len(items))

    outputs = map_in_order(task, items, workers=workers, on_result=done)
    objects = [out.payload[0] for out in outputs]
    series = [s for out in outputs for s in out.payload[1]]
    return objects, series


def simulate_catalog_sweep(
    catalog_path: str,
    task: SimulateCatalogTask,
    *,
    output: str,
    sweep: SweepOptions,
    object_ids: Sequence[str] | None = None,
    force: bool = False,
) -> SweepSummary:
    """``measure --sim -o DIR/``: one object per task; part ``k``'s squeezes in ``DIR/_logs/``.

    The rows of a part are :data:`MEASURE_SCHEMA` summaries; the squeezes are byte for byte
    those of the serial run (each object's noise stream depends on the seed and its position).
    A row the simulator refuses fails alone (``DIR/_failures/``).

    Args:
        catalog_path: the catalog (``-`` for stdin), hashed into the fingerprint.
        task: the squeeze and simulator settings and the seed.
        output: the dataset directory.
        sweep: where to run (workers, scheduler), partition size, resume.
        object_ids: these objects, in this order (None: all).
        force: overwrite the sweep files of an existing directory.
    """
    catalog = select_objects(read_catalog(catalog_path), object_ids)
    planned = _plan(catalog, task, catalog_path, single_log=False)
    provenance = sim_provenance(catalog_path, task, list(catalog["object_id"]))
    items = _positioned_items(catalog, planned)
    settings = {**task.protocol.as_dict(), "sim_settings": dataclasses.asdict(task.settings)}
    if task.log_epoch_ns != LOG_EPOCH_NS:  # (the default keeps older directories resumable)
        settings["log_epoch_ns"] = task.log_epoch_ns
    fingerprint = dataset_fingerprint(
        "measure", "squeeze_log", settings, {"catalog": input_digest(catalog_path)}, task.seed
    )
    return run_sweep(
        task,
        items,
        out_dir=output,
        schema=MEASURE_SCHEMA,
        fingerprint=fingerprint,
        part_writer=LogPartWriter("squeeze_log", provenance, task.log_epoch_ns),
        force=force,
        **sweep.run_kwargs(),
    )


def recording_log(
    source: str,
    recording: Recording,
    obj: Mapping[str, object],
    settings: Mapping[str, Any],
    *,
    output: str,
    force: bool = False,
) -> None:
    """Write a rig recording's squeezes as a squeeze log (``measure --bag`` / ``--csv``).

    Args:
        source: the recording file (hashed into the provenance).
        recording: what :func:`read_recording` read.
        obj: the object's row (:func:`deformctl.catalog.object_record`); the source sample
            rates are added, as they are to the provenance's ``settings``, with the source,
            phase and ruptures (:meth:`Recording.log_fields`).
        settings: the reader's options.
        output: the squeeze log (``-`` for stdout).
        force: overwrite an existing output.
    """
    rates = {
        "force_rate_hz": recording.force_rate_hz,
        "position_rate_hz": recording.position_rate_hz,
    }
    provenance = Provenance.from_invocation([source], settings={**settings, **rates})
    write_squeeze_log(
        output,
        [{**obj, **recording.log_fields()}],
        recording.squeezes,
        provenance=provenance,
        force=force,
    )


def read_recording(
    path: str | PathLike[str],
    source: BagSource | CsvOptions,
    obj: MeasuredObject | str,
    segmentation: Segmentation = DEFAULT_SEGMENTATION,
) -> Recording:
    """One object's recording: a ROS 2 bag or a CSV export, read with the options the command
    builds (``measure bag`` / ``measure csv``).

    Args:
        path: the recording: a bag (one ``.mcap`` file, or a rosbag2 folder), or a CSV file
            (``-``: stdin).
        source: where and what the streams are: a :class:`BagSource` (topics, axis, position
            signal; :mod:`~deformctl.measure.ros2_bag`) or a :class:`CsvOptions` (dialect,
            columns, units, force sign, lag; :mod:`deformctl.measure.csv`).
        obj: the object measured (:class:`~deformctl.catalog.MeasuredObject`: its id is
            written into every squeeze, its size along the squeeze axis bounds the
            compression), or only its id when its size is not known.
        segmentation: how the recording is cut into squeezes and which phase is kept; its
            ``segment=None`` is the source's default (a bag is split, a CSV export is one
            squeeze).

    Returns:
        The squeezes in SI, the source sample rates, the ruptures cut off, the recording's
        defects and what was found in the file (:class:`Recording`).

    Raises:
        MissingInputError: the file (or a file a rosbag2 folder lists) does not exist (exit 66).
        InputDataError: a file that cannot be read as the source, a stream or column not found,
            NaN samples, time going back, no squeeze, or an implausible recording (a sample
            rate, peak force or compression a unit mistake explains); the message names the
            file and the likely fix (exit 65).
        UsageError: a CSV's ambiguous columns, a unit contradicting the file, a file above the
            memory budget; a JointState topic without a joint (exit 2).
    """
    object_id, size_x_cm = (obj, None) if isinstance(obj, str) else (obj.object_id, obj.size_x_cm)
    if isinstance(source, BagSource):
        return read_bag(path, source, object_id, segmentation, size_x_cm)
    return read_csv(path, source, object_id, segmentation, size_x_cm)


def measure_recording(
    path: str,
    source: BagSource | CsvOptions,
    obj: MeasuredObject,
    *,
    output: str,
    segmentation: Segmentation = DEFAULT_SEGMENTATION,
    force: bool = False,
) -> Recording:
    """``measure --bag | --csv``: read one object's recording and write its squeeze log.

    The provenance records the source's and the segmentation's options (their ``as_dict``, the
    segmentation with the source's default resolved) and the recording's sample rates.

    Args:
        path: the recording (a bag or a CSV file; not stdin).
        source: what and where the streams are (:class:`BagSource`, :class:`CsvOptions`).
        obj: the object measured (its id, weight and, when known, size and friction).
        output: the squeeze log (``-`` for stdout).
        segmentation: how the recording is cut into squeezes.
        force: overwrite an existing output.

    Returns:
        What was read (the squeezes, the sample rates, the ruptures cut off).

    Raises:
        MissingInputError (66), OutputExistsError (1), InputDataError (65), UsageError (2): see
        the readers.
    """
    if not (isinstance(source, BagSource) and Path(path).is_dir()):  # a rosbag2 folder
        check_input_path(path)
    check_output_path(output, force)
    recording = read_recording(path, source, obj, segmentation)
    settings = {
        "source": source.kind,
        **source.as_dict(),
        **segmentation.as_dict(isinstance(source, BagSource)),
    }
    recording_log(path, recording, obj.record(), settings, output=output, force=force)
    return recording
