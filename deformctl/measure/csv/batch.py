"""Many CSV exports in one ``measure --csv`` call: one object per file, one log or a dataset.

``measure --csv a.csv b.csv …`` reads every file with the same options (one
:class:`CsvFileTask`); each file is one object, its id the file's stem unless an
``--objects-from`` mapping (:func:`read_objects_from`) names it and gives its weight, size and
friction. A file that cannot be read does not stop the others: it is recorded with its reason
(``_failures``) and the run exits non-zero.

* :func:`measure_csv_files` writes one squeeze log with every object (the files read on
  ``workers`` processes, in order); the failures are recorded in its provenance
  (``settings["_failures"]``);
* :func:`measure_csv_sweep` writes a dataset directory (``-o DIR/``, as ``measure --sim``):
  a part log ``DIR/_logs/part-k.mcap`` per part, a summary row per object
  (:data:`CSV_MEASURE_SCHEMA`) and the failures in ``DIR/_failures/``. ``characterize`` reads
  either unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pyarrow as pa

from deformctl.artifacts import check_output_path, write_squeeze_log
from deformctl.artifacts.dataset import LogPartWriter, dataset_fingerprint, failure_cause
from deformctl.artifacts.io import display_name
from deformctl.artifacts.provenance import Provenance, input_digest
from deformctl.catalog import (
    COLUMN_QUANTITIES,
    SIZE_COLUMNS,
    check_object_values,
    object_record,
)
from deformctl.errors import EXIT_FAILURE, DeformctlError, InputDataError, UsageError
from deformctl.measure.csv.options import CsvOptions
from deformctl.measure.csv.reader import read_csv
from deformctl.measure.options import DEFAULT_SEGMENTATION, Segmentation
from deformctl.measure.recording import Recording
from deformctl.measure.stage import LOG_SAMPLE_BYTES, MEASURE_SCHEMA
from deformctl.parallel import SweepOptions, SweepSummary, TaskOutput, map_in_order, run_sweep
from deformctl.parallel.auto import AUTO, Auto
from deformctl.reprs import short_repr
from deformctl.series import SqueezeSeries
from deformctl.units import GIB

#: Rows of a ``measure --csv -o DIR/`` dataset: :data:`MEASURE_SCHEMA` and, per object, its
#: file, the columns and units read, the recording's flags and warnings, and its notices
#: (:attr:`Recording.notices`: sign flips, the position's reading, ruptures and warnings, one
#: per line), which the many-files form prints as the single-file form does.
CSV_MEASURE_SCHEMA = pa.schema(
    [
        *MEASURE_SCHEMA,
        pa.field("source_file", pa.string(), nullable=False),
        pa.field("columns", pa.string(), nullable=False),
        pa.field("recording_flags", pa.string(), nullable=False),
        pa.field("warnings", pa.string(), nullable=False),
        pa.field("notices", pa.string(), nullable=False),
    ]
)
#: Columns of an ``--objects-from`` mapping besides ``file``.
MAPPING_COLUMNS: tuple[str, ...] = ("object_id", "weight_n", *SIZE_COLUMNS, "friction_mu")


@dataclass(frozen=True)
class CsvFile:
    """One file of a run and the object it is: its catalog-like row (id, weight, size, μ)."""

    path: str
    row: Mapping[str, Any]

    @property
    def object_id(self) -> str:
        """The object's id."""
        return str(self.row["object_id"])


def _number(value: Any) -> float | None:
    if value is None or (isinstance(value, float) and math.isnan(value)) or value == "":
        return None
    return float(value)


def read_objects_from(path: str) -> dict[str, dict[str, Any]]:
    """An ``--objects-from`` mapping: file (as given, its name or its stem) → object values.

    The CSV has a ``file`` column and any of ``object_id``, ``weight_n``, ``size_x_cm``,
    ``size_y_cm``, ``size_z_cm`` (all three or none) and ``friction_mu``; empty cells take
    the command line's values.

    Raises:
        MissingInputError: no such file (exit 66).
        InputDataError: no ``file`` column, an unknown column, a file twice, or a value that
            is not a number or outside its quantity's rule (:data:`deformctl.catalog.
            COLUMN_QUANTITIES`); the message names the row (exit 65).
    """
    import pandas as pd

    from deformctl.artifacts.io import check_input_path

    check_input_path(path)
    try:
        table = pd.read_csv(path, dtype=str, keep_default_na=False, skipinitialspace=True)
    except (ValueError, pd.errors.ParserError, UnicodeDecodeError) as err:
        raise InputDataError(f"not a readable CSV mapping: {err}", path=path) from None
    table.columns = [str(c).strip() for c in table.columns]
    if "file" not in table.columns:
        raise InputDataError(
            f"--objects-from needs a 'file' column; columns: {', '.join(table.columns)}", path=path
        )
    unknown = [c for c in table.columns if c not in ("file", *MAPPING_COLUMNS)]
    if unknown:
        raise InputDataError(
            f"unknown column {unknown[0]!r}; known: file, {', '.join(MAPPING_COLUMNS)}", path=path
        )
    out: dict[str, dict[str, Any]] = {}
    for n, rec in enumerate(table.to_dict("records"), start=2):
        key = str(rec.pop("file")).strip()
        if not key:
            raise InputDataError(f"line {n}: empty file name", path=path)
        if key in out:
            raise InputDataError(f"line {n}: file {key!r} given twice", path=path)
        values: dict[str, Any] = {}
        for column, text in rec.items():
            text = str(text).strip()
            if not text:
                continue
            if column == "object_id":
                values[column] = text
                continue
            try:
                value = float(text)
            except ValueError:
                raise InputDataError(
                    f"line {n}: {column} = {text!r} is not a number", path=path
                ) from None
            # the catalog column's rule, as a value read from a file (exit 65)
            values[column] = COLUMN_QUANTITIES[column].check_data(
                value, where=f"line {n}", path=path
            )
        out[key] = values
    return out


def _mapping_for(path: str, mapping: Mapping[str, Mapping[str, Any]]) -> Mapping[str, Any]:
    p = Path(path)
    for key in (path, p.name, p.stem):
        if key in mapping:
            return mapping[key]
    return {}


def csv_objects(
    paths: Sequence[str],
    *,
    object_id: str | None = None,
    weight_n: float | None = None,
    size_cm: Sequence[float] | None = None,
    friction_mu: float | None = None,
    objects_from: str | None = None,
) -> list[CsvFile]:
    """The object each file is: id = stem (or ``object_id`` for one file, or the mapping's).

    Raises:
        UsageError: ``object_id`` with several files, a file without a weight (neither
            ``weight_n`` nor the mapping), stdin with several files or without ``object_id``,
            two files with one id, or a value out of range (exit 2).
        InputDataError, MissingInputError: a bad mapping file (:func:`read_objects_from`).
    """
    if not paths:
        raise UsageError("--csv needs at least one file")
    if object_id is not None and len(paths) > 1:
        raise UsageError(
            f"--object-id names one object, but {len(paths)} files are given (each file's id is "
            "its stem, or give --objects-from FILE)"
        )
    if "-" in paths and len(paths) > 1:
        raise UsageError("--csv -: stdin is one file; give it alone")
    check_object_values(size_cm, friction_mu, weight_n)  # the flags' own lines, once
    mapping = read_objects_from(objects_from) if objects_from is not None else {}
    files: list[CsvFile] = []
    seen: dict[str, str] = {}
    for path in paths:
        given = _mapping_for(path, mapping)
        oid = given.get("object_id") or object_id
        if oid is None:
            if path == "-":
                raise UsageError("--csv - (stdin) needs --object-id")
            oid = Path(path).stem
        weight = _number(given.get("weight_n"))
        weight = weight if weight is not None else weight_n
        if weight is None:
            raise UsageError(
                f"{display_name(path)}: no weight for object {oid!r}: give --weight-n or a "
                "weight_n column in --objects-from"
            )
        sizes = [_number(given.get(c)) for c in SIZE_COLUMNS]
        size = (
            tuple(float(s) for s in sizes if s is not None)
            if any(s is not None for s in sizes)
            else size_cm
        )
        if size is not None and len(size) != 3:
            raise UsageError(
                f"{objects_from}: object {oid!r}: give all of {', '.join(SIZE_COLUMNS)}"
            )
        mu = _number(given.get("friction_mu"))
        try:
            row = object_record(
                str(oid), weight, size_cm=size, friction_mu=mu if mu is not None else friction_mu
            )
        except UsageError as err:
            raise UsageError(f"{display_name(path)}: object {oid!r}: {err.message}") from None
        if str(oid) in seen:
            raise UsageError(
                f"files {seen[str(oid)]} and {path} are both object {oid!r}; give --objects-from "
                "FILE with an object_id column"
            )
        seen[str(oid)] = path
        files.append(CsvFile(path, row))
    return files


@dataclass(frozen=True)
class CsvFileTask:
    """Read one CSV file as one object (picklable: the sweep and the workers run it).

    Attributes:
        options: how to read every file (:class:`CsvOptions`).
        segmentation: how each file is cut into squeezes (one squeeze per file unless
            ``segmentation.segment``).
    """

    options: CsvOptions
    segmentation: Segmentation = DEFAULT_SEGMENTATION

    def read(self, file: CsvFile) -> Recording:
        """The file's recording (raises what :func:`read_csv` raises)."""
        size = file.row.get(SIZE_COLUMNS[0])
        size_x_cm = None if size is None else float(size)
        return read_csv(file.path, self.options, file.object_id, self.segmentation, size_x_cm)

    def __call__(self, item: Mapping[str, Any]) -> TaskOutput:
        """One sweep item (``object_id``, ``path``, ``row``): its summary row and its log."""
        file = CsvFile(str(item["path"]), item["row"])
        rec = self.read(file)
        obj = {**file.row, **rec.log_fields()}
        return TaskOutput(rows=[summary_row(file, rec)], payload=(obj, rec.squeezes))

    def settings(self) -> dict[str, Any]:
        """What the provenance records of the options."""
        return {"source": "csv", **self.options.as_dict(), **self.segmentation.as_dict(False)}


def summary_row(file: CsvFile, rec: Recording) -> dict[str, Any]:
    """A :data:`CSV_MEASURE_SCHEMA` row of one file's recording."""
    columns = rec.details.get("columns", {})
    return {
        "object_id": file.object_id,
        "squeezes": len(rec.squeezes),
        "samples": int(sum(len(s.time_s) for s in rec.squeezes)),
        "duration_s": float(sum(float(s.time_s[-1]) for s in rec.squeezes)),
        "peak_force_n": float(max(float(s.force_n.max()) for s in rec.squeezes)),
        "source_file": file.path,
        "columns": ", ".join(f"{r}={c['column']!r} [{c['unit']}]" for r, c in columns.items()),
        "recording_flags": ",".join(rec.flags) or "ok",
        "warnings": "\n".join(rec.warnings),
        "notices": "\n".join(rec.notices),
    }


@dataclass(frozen=True)
class FileOutcome:
    """What became of one file: its recording, or the error it raised."""

    __repr__ = short_repr

    file: CsvFile
    recording: Recording | None = None
    error: str = ""
    exit_code: int = 0
    cause: str = ""


@dataclass(frozen=True)
class _Catching:
    """Run a :class:`CsvFileTask` on one file and return its outcome instead of raising."""

    task: CsvFileTask

    def __call__(self, file: CsvFile) -> FileOutcome:
        try:
            return FileOutcome(file, self.task.read(file))
        except DeformctlError as err:
            cause = failure_cause(type(err).__name__)
            return FileOutcome(file, error=str(err), exit_code=err.exit_code, cause=cause)
        except Exception as err:  # a defect: recorded as one, the other files go on
            message = f"{display_name(file.path)}: internal error: {' '.join(str(err).split())}"
            return FileOutcome(file, error=message, exit_code=EXIT_FAILURE, cause="internal_error")


def file_notices(outcome: FileOutcome) -> list[str]:
    """One file's lines for stderr, each naming the file: its notices
    (:attr:`Recording.notices`), or its error line."""
    name = display_name(outcome.file.path)
    if outcome.recording is None:
        return [f"error: {outcome.error}"]
    lines = []
    for line in outcome.recording.notices:
        if line.startswith("warning: "):
            text = line.removeprefix("warning: ")
            lines.append(f"warning: {name}: object {outcome.file.object_id!r}: {text}")
        else:
            lines.append(f"{name}: {line}")
    return lines


def dataset_notices(rows: Any) -> list[str]:
    """The lines of :func:`file_notices` from a ``measure --csv -o DIR/`` dataset's rows (a
    DataFrame of :data:`CSV_MEASURE_SCHEMA`; rows written before the ``notices`` column give
    their warnings)."""
    lines = []
    for rec in rows.to_dict("records"):
        name, oid = rec["source_file"], rec["object_id"]
        text = rec.get("notices")
        if not isinstance(text, str):
            text = "\n".join(f"warning: {w}" for w in str(rec.get("warnings") or "").split("\n"))
        for line in filter(None, text.split("\n")):
            if line.startswith("warning: "):
                lines.append(f"warning: {name}: object {oid!r}: {line.removeprefix('warning: ')}")
            else:
                lines.append(f"{name}: {line}")
    return lines


@dataclass(frozen=True)
class CsvBatchResult:
    """The files read into one squeeze log, and those that failed."""

    __repr__ = short_repr

    outcomes: list[FileOutcome]

    @property
    def read(self) -> list[FileOutcome]:
        """The files that were read."""
        return [o for o in self.outcomes if o.recording is not None]

    @property
    def failed(self) -> list[FileOutcome]:
        """The files that failed, with their error lines."""
        return [o for o in self.outcomes if o.recording is None]

    @property
    def exit_code(self) -> int:
        """0; 1 when some files failed; the first failure's code when all did."""
        if not self.failed:
            return 0
        return EXIT_FAILURE if self.read else self.failed[0].exit_code


def measure_csv_files(
    files: Sequence[CsvFile],
    task: CsvFileTask,
    *,
    output: str,
    force: bool = False,
    workers: int | Auto = AUTO,
) -> CsvBatchResult:
    """``measure --csv FILES… -o LOG``: every file's object in one squeeze log.

    One file's errors are raised as they are (exit 65, 66 or 2, nothing written). With several,
    a file that fails is recorded (its one-line error in the log's provenance,
    ``settings["_failures"]``) and the others are written; when every file fails nothing is
    written. The files are read on ``workers`` local processes (``"auto"``: the count of least
    measured wall time, :mod:`deformctl.parallel.auto`), in order.

    Raises:
        OutputExistsError: ``output`` exists and not ``force`` (exit 1).
        UsageError: the squeezes of all files above the memory budget (exit 2).
        DeformctlError: the one file's error.
    """
    check_output_path(output, force)
    if len(files) == 1:
        outcomes = [FileOutcome(files[0], task.read(files[0]))]
    else:
        outcomes = map_in_order(_Catching(task), list(files), workers=workers)
    result = CsvBatchResult(outcomes)
    if not result.read:
        return result
    recordings = [o.recording for o in result.read if o.recording is not None]
    samples = sum(len(s.time_s) for rec in recordings for s in rec.squeezes)
    if samples * LOG_SAMPLE_BYTES > task.options.memory_budget_gib * GIB:
        raise UsageError(
            f"one squeeze log of {len(result.read)} recordings is {samples:,} samples, an "
            f"estimated {samples * LOG_SAMPLE_BYTES / GIB:.3g} GiB in memory, above the memory "
            f"budget of {task.options.memory_budget_gib:g} GiB; write a dataset directory "
            "(-o DIR/) or raise --memory-budget-gib"
        )
    objects: list[dict[str, Any]] = []
    squeezes: list[SqueezeSeries] = []
    for o in result.read:
        rec = o.recording
        assert rec is not None
        objects.append({**o.file.row, **rec.log_fields()})
        squeezes.extend(rec.squeezes)
    settings = task.settings()
    if len(files) == 1:
        rec = result.read[0].recording
        assert rec is not None
        settings.update(force_rate_hz=rec.force_rate_hz, position_rate_hz=rec.position_rate_hz)
    if result.failed:
        settings["_failures"] = [
            {
                "file": o.file.path,
                "object_id": o.file.object_id,
                "cause": o.cause,
                "error": o.error,
            }
            for o in result.failed
        ]
    provenance = Provenance.from_invocation([o.file.path for o in result.read], settings=settings)
    write_squeeze_log(output, objects, squeezes, provenance=provenance, force=force)
    return result


def measure_csv_sweep(
    files: Sequence[CsvFile],
    task: CsvFileTask,
    *,
    output: str,
    sweep: SweepOptions,
    force: bool = False,
) -> SweepSummary:
    """``measure --csv FILES… -o DIR/``: one object per file into a dataset directory.

    A file that fails is recorded in ``DIR/_failures/`` with its reason; the summary's exit
    code is 1 when any did (:func:`deformctl.parallel.run_sweep`).
    """
    if any(f.path == "-" for f in files):
        raise UsageError("--csv - (stdin) cannot be written to a dataset directory; use -o LOG")
    items = [{"object_id": f.object_id, "path": f.path, "row": dict(f.row)} for f in files]
    provenance = Provenance.from_invocation([f.path for f in files], settings=task.settings())
    fingerprint = dataset_fingerprint(
        "measure",
        "squeeze_log",
        task.settings(),
        {f.path: input_digest(f.path) for f in files},
    )
    return run_sweep(
        task,
        items,
        out_dir=output,
        schema=CSV_MEASURE_SCHEMA,
        fingerprint=fingerprint,
        part_writer=LogPartWriter("squeeze_log", provenance),
        force=force,
        **sweep.run_kwargs(),
    )
