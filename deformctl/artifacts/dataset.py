"""The partitioned dataset a sweep writes: manifest, parts, failures, part logs, and its readers.

A *dataset directory* holds the rows of one stage run over many objects, split into parts by
catalog position::

    out_dir/
      _sweep.json                    manifest, written first: fingerprint, schema, ids per part
      part-00000.parquet             rows of the objects of part 0 that have rows, in order
      _logs/part-00000.mcap          the part's log (a squeeze or lift log), when the stage has one
      _failures/part-00000.parquet   one row per failed object: id, cause, error_message

Only the rows are Parquet files at the top level and everything else has a ``_`` name, which
Parquet readers skip (pyarrow, pandas, Spark, Polars), so ``pandas.read_parquet(out_dir)``,
``pyarrow.dataset.dataset(out_dir)`` and DuckDB's ``read_parquet('out_dir/*.parquet')`` see
exactly the rows, with the declared schema. Directories of the first layout, with the logs
``part-00000.mcap`` beside the rows, are still read, and a ``--resume`` moves their logs into
``_logs/``.

A part is committed in three atomic steps (temporary file + rename, through
:func:`deformctl.artifacts.io.atomic_output`): its failures file, its log (a ``part_writer``
hook), then its rows file, which marks the part complete. Each part file carries the part's
ids and a digest of the manifest in its Parquet metadata, so a resumed sweep can tell a
complete, valid part from a partial or stale one (:meth:`DatasetWriter.plan`).

:class:`DatasetWriter` is what the executor (:func:`deformctl.parallel.run_sweep`) writes
through; it knows nothing of processes or clusters. The readers (:func:`read_dataset`,
:func:`read_table_any`, :func:`dataset_part_paths`, :func:`describe_dataset`) let every stage
read a directory where it reads a file.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import pyarrow as pa
import pyarrow.parquet as pq

from deformctl import jsonsafe
from deformctl.artifacts.io import atomic_output, atomic_write_bytes
from deformctl.artifacts.schema import load_table_spec, validate_frame
from deformctl.artifacts.tables import read_table, table_schema
from deformctl.errors import InputDataError, MissingInputError, OutputExistsError, SchemaError
from deformctl.version import version_string

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "FAILURES_DIR",
    "LOGS_DIR",
    "MANIFEST_NAME",
    "DatasetWriter",
    "LogPartWriter",
    "ObjectResult",
    "PartPayloads",
    "dataset_fingerprint",
    "dataset_log_paths",
    "dataset_part_paths",
    "describe_dataset",
    "failure_schema",
    "is_dataset_output",
    "iter_dataset_parts",
    "part_log_path",
    "read_dataset",
    "read_failures",
    "read_table_any",
    "rows_to_table",
    "spec_rows",
    "table_schema",
]

SWEEP_FORMAT = "deformctl-sweep/1"
MANIFEST_NAME = "_sweep.json"
FAILURES_DIR = "_failures"
LOGS_DIR = "_logs"  #: the parts' logs (any part artifact that is not its rows)
_META_KEY = b"deformctl.sweep"


def _one_line(text: str) -> str:
    return " ".join(text.split())


def part_name(index: int, suffix: str = ".parquet") -> str:
    """``part-NNNNN<suffix>``, the file name of part ``index``."""
    return f"part-{index:05d}{suffix}"


def is_dataset_output(path: str) -> bool:
    """The rule for a partitioned dataset output: a path ending in ``/`` or an existing directory.

    Everything else (``x.parquet``, ``x.mcap``, ``-``) is a single file, written as before.
    """
    return path != "-" and (path.endswith(("/", os.sep)) or os.path.isdir(path))


# --------------------------------------------------------------------------- schemas and rows


def spec_rows(df: pd.DataFrame, kind: str) -> pa.Table:
    """A validated frame as a table of :func:`table_schema` (spec columns only, None for NaN)."""
    norm = validate_frame(df, kind)
    schema = table_schema(kind)
    arrays = []
    for fld in schema:
        if fld.name in norm.columns:
            values = list(norm[fld.name])
            if pa.types.is_string(fld.type):
                values = [
                    None if v is None or (isinstance(v, float) and v != v) else v for v in values
                ]
            arrays.append(pa.array(values, type=fld.type, from_pandas=True))
        else:
            arrays.append(pa.nulls(len(norm), type=fld.type))
    return pa.Table.from_arrays(arrays, schema=schema)


def dataset_fingerprint(
    command: str,
    kind: str,
    settings: Mapping[str, Any],
    inputs: Mapping[str, str],
    seed: int | None = None,
) -> dict[str, Any]:
    """What a resume must match: command, output kind and schema version, settings, inputs.

    Args:
        command: the stage command (``measure``, ``characterize``, ``lift``).
        kind: the kind of the rows (a table kind, or ``squeeze_log`` for measure's summaries).
        settings: the stage's settings, JSON-serialisable.
        inputs: input name → sha256.
        seed: the run's seed, when it has one.
    """
    version = load_table_spec(kind).version if kind != "squeeze_log" else 1
    return {
        "command": command,
        "kind": kind,
        "schema_version": version,
        "tool_version": version_string(),
        "settings": dict(settings),
        "inputs": dict(inputs),
        "seed": seed,
    }


#: The causes a failures row names (docs/reference/exit-codes.md lists them): the kind of the
#: error that stopped the object, never the class of an exception.
FAILURE_CAUSES: dict[str, str] = {
    "bad_input": "the object's input is not valid data (exit 65 alone)",
    "missing_input": "an input file the object needs does not exist (exit 66 alone)",
    "bad_option": "an option cannot work for this object (exit 2 alone)",
    "output_exists": "an output exists already (exit 1 alone)",
    "not_converged": "a lifting-force search that failed or did not converge",
    "simulation_failed": "the simulator could not produce a valid result",
    "rig_failed": "an external rig crashed, timed out or answered garbage",
    "object_failed": "the object's run ended without a result",
    "out_of_memory": "the object ran out of memory",
    "internal_error": "a defect of deformctl (please report it with the message)",
}
#: Error types (class names, or the names a task gives) → cause; subclasses of
#: :class:`~deformctl.errors.DeformctlError` by their nearest listed base.
_CAUSE_OF_TYPE: dict[str, str] = {
    "InputDataError": "bad_input",
    "MissingInputError": "missing_input",
    "UsageError": "bad_option",
    "OutputExistsError": "output_exists",
    "SearchError": "not_converged",
    "NotConverged": "not_converged",
    "SimulationError": "simulation_failed",
    "RigError": "rig_failed",
    "ObjectFailed": "object_failed",
    "DeformctlError": "object_failed",
    "MemoryError": "out_of_memory",
}


def failure_cause(error_type: str) -> str:
    """The cause (:data:`FAILURE_CAUSES`) of an error type: a cause as it is, a class of
    :mod:`deformctl.errors` (or a subclass) by its kind, anything else ``internal_error``."""
    if error_type in FAILURE_CAUSES:
        return error_type
    if error_type in _CAUSE_OF_TYPE:
        return _CAUSE_OF_TYPE[error_type]
    from deformctl.errors import DeformctlError

    todo: list[type] = [DeformctlError]
    while todo:
        cls = todo.pop()
        if cls.__name__ == error_type:
            for base in cls.__mro__:
                if base.__name__ in _CAUSE_OF_TYPE:
                    return _CAUSE_OF_TYPE[base.__name__]
        todo.extend(cls.__subclasses__())
    return "internal_error"


def failure_schema(schema: pa.Schema, id_column: str) -> pa.Schema:
    """The schema of the failures part: the id column (same type), the cause
    (:data:`FAILURE_CAUSES`) and the one-line message."""
    return pa.schema(
        [
            schema.field(id_column),
            pa.field("cause", pa.string(), nullable=False),
            pa.field("error_message", pa.string(), nullable=False),
        ]
    )


def rows_to_table(rows: Any, schema: pa.Schema, id_column: str, item_id: Any) -> pa.Table:
    """One object's rows (dicts, a DataFrame or a table) as a table of ``schema``.

    The id column is filled in when absent.

    Raises:
        ValueError: a row of another object, or columns that do not match the schema.
    """
    if isinstance(rows, pa.Table):
        records = rows.to_pylist()
    elif hasattr(rows, "to_dict") and hasattr(rows, "columns"):  # pandas DataFrame
        records = rows.to_dict("records")
    elif isinstance(rows, Mapping):
        records = [dict(rows)]
    else:
        records = [dict(r) for r in rows]
    names = set(schema.names)
    for rec in records:
        rec.setdefault(id_column, item_id)
        if rec[id_column] != item_id:
            raise ValueError(f"row has {id_column}={rec[id_column]!r}, expected {item_id!r}")
        keys = set(rec)
        if keys != names:
            missing = sorted(names - keys)
            extra = sorted(keys - names)
            raise ValueError(
                f"row columns do not match the schema: missing {missing}, extra {extra}"
            )
    return pa.Table.from_pylist(records, schema=schema)


@dataclass
class ObjectResult:
    """What one object of a sweep produced: its rows, its payload for the part writer, or why not.

    Attributes:
        item_id: the object's id.
        table: its rows (None when it failed without rows).
        payload: anything picklable for the part writer (e.g. the object's time series).
        error_type, error_message: set when the object failed (it may still have rows).
    """

    item_id: Any
    table: pa.Table | None
    payload: Any
    error_type: str | None = None
    error_message: str | None = None

    def without_payload(self) -> ObjectResult:
        """The same result without its payload (once the part's log is written)."""
        return ObjectResult(self.item_id, self.table, None, self.error_type, self.error_message)


@dataclass(frozen=True)
class PartPayloads:
    """The payloads of one finished part, in catalog order, handed to a ``part_writer`` hook.

    The hook runs before the part's Parquet file is committed, so a committed part always has
    its artifacts (write them atomically, e.g. with
    :func:`deformctl.artifacts.io.atomic_write_bytes`). It runs in the client process, unless it
    is picklable and has a true ``in_workers`` attribute and the sweep runs on local processes:
    then it runs as a job of the worker pool and the rows are committed after that job has
    finished. A Dask sweep always runs it in the client (the workers may not share the client's
    file system).
    """

    index: int
    out_dir: Path
    item_ids: list[Any]
    payloads: list[tuple[Any, Any]]

    def path(self, suffix: str) -> Path:
        """The conventional artifact path of this part, e.g. ``path(".mcap")``:
        ``out_dir/_logs/part-NNNNN<suffix>`` (only the rows are at the top level; the folder
        is created on first use)."""
        logs = self.out_dir / LOGS_DIR
        logs.mkdir(exist_ok=True)
        return logs / part_name(self.index, suffix)


@dataclass(frozen=True)
class LogPartWriter:
    """Part writer of a stage with a log: the part's payloads as one MCAP log ``part-k.mcap``.

    Each payload is ``(object_record, items)``: the object's catalog row and its squeezes
    (``kind = "squeeze_log"``) or lift attempts (``kind = "lift_log"``). It runs in a local
    worker process (``in_workers``): encoding a part's messages is the sweep's largest serial
    cost when done by the client.
    """

    kind: str
    provenance: Any
    epoch_ns: int | None = None  #: where the log begins (None: the writers' default)
    in_workers: ClassVar[bool] = True

    def __call__(self, part: PartPayloads) -> None:
        """Write ``part``'s log atomically."""
        from deformctl.artifacts.mcap import write_lift_log, write_squeeze_log

        objects = [p[0] for _, p in part.payloads]
        items = [item for _, p in part.payloads for item in p[1]]
        path = part.path(".mcap")
        epoch = {} if self.epoch_ns is None else {"epoch_ns": self.epoch_ns}
        write = write_squeeze_log if self.kind == "squeeze_log" else write_lift_log
        write(path, objects, items, provenance=self.provenance, force=True, **epoch)


# --------------------------------------------------------------------------- writing


def _normalize(obj: Any) -> Any:
    return json.loads(json.dumps(obj, sort_keys=True, default=str))


def _schema_spec(schema: pa.Schema) -> list[dict[str, Any]]:
    return [{"name": f.name, "type": str(f.type), "nullable": f.nullable} for f in schema]


def _write_table(table: pa.Table, target: Path) -> None:
    with atomic_output(target, force=True, durable=True) as tmp:
        pq.write_table(table, tmp)


def _part_metadata(table: pa.Table) -> dict[str, Any] | None:
    raw = (table.schema.metadata or {}).get(_META_KEY)
    return None if raw is None else jsonsafe.loads(raw, allow_nan=True)


def _is_temp_file(name: str) -> bool:
    """A temporary file of a killed run (``.part-00000.parquet.<random>.tmp``, ``._sweep.json...``
    or an older ``.part-00000.parquet.tmp-<pid>-<random>``)."""
    return name.startswith((".part-", f".{MANIFEST_NAME}")) and ".tmp" in name


class DatasetWriter:
    """Writes one sweep's dataset directory: plan (what to keep on resume), open, commit parts.

    Args:
        out_dir: the dataset directory.
        ids: the object ids, in catalog order (unique str or int).
        schema: the row schema of every part; must contain ``id_column``.
        fingerprint: JSON-serialisable description of what produced the data; a resume must
            present the same one.
        id_column: the row column identifying an object.
        partition_size: objects per part (>= 1).
    """

    def __init__(
        self,
        out_dir: str | os.PathLike[str],
        ids: Sequence[Any],
        *,
        schema: pa.Schema,
        fingerprint: Mapping[str, Any],
        id_column: str,
        partition_size: int,
    ) -> None:
        self.out = Path(out_dir)
        self.schema = schema
        self.id_column = id_column
        self.partition_size = partition_size
        self.fail_schema = failure_schema(schema, id_column)
        self.parts = [list(ids[i : i + partition_size]) for i in range(0, len(ids), partition_size)]
        self.manifest = {
            "format": SWEEP_FORMAT,
            "fingerprint": _normalize(dict(fingerprint)),
            "schema": _schema_spec(schema),
            "id_column": id_column,
            "partition_size": partition_size,
            "n_items": len(ids),
            "parts": self.parts,
        }
        text = json.dumps(self.manifest, sort_keys=True).encode()
        self.digest = hashlib.sha256(text).hexdigest()[:16]
        self._existing = False
        self._resume = False

    @property
    def manifest_path(self) -> Path:
        """``out_dir/_sweep.json``."""
        return self.out / MANIFEST_NAME

    def plan(self, *, resume: bool, force: bool) -> dict[int, int]:
        """Check the directory without writing; the parts to keep (index → failed objects).

        Raises:
            OutputExistsError: ``out_dir`` is a file, or a non-empty directory without
                ``resume`` or ``force``.
            InputDataError: ``resume`` of a directory that is not this sweep's.
        """
        out = self.out
        if out.exists() and not out.is_dir():
            raise OutputExistsError(out)
        self._existing = out.is_dir() and any(out.iterdir())
        self._resume = resume
        kept: dict[int, int] = {}
        if self._existing and resume:
            if not self.manifest_path.is_file():
                raise InputDataError(
                    f"cannot resume: no {MANIFEST_NAME} in the directory", path=out
                )
            try:
                old = jsonsafe.loads(self.manifest_path.read_bytes(), allow_nan=True)
            except (OSError, ValueError):
                raise InputDataError(
                    f"cannot resume: unreadable {MANIFEST_NAME}", path=out
                ) from None
            self._compare_manifest(old)
            for k in range(len(self.parts)):
                n_failed = self._valid_part(k)
                if n_failed is not None:
                    kept[k] = n_failed
        elif self._existing and not force:
            raise OutputExistsError(out)
        return kept

    def open(self) -> None:
        """Prepare the directory: clean a resumed one, or clear an overwritten one; manifest."""
        if self._existing and self._resume:
            self._clean_temp_files()
        elif self._existing:
            self._remove_sweep_files()
        self.out.mkdir(parents=True, exist_ok=True)
        (self.out / FAILURES_DIR).mkdir(exist_ok=True)
        if self._existing and self._resume:
            self._move_old_layout_logs()
        if not (self._resume and self._existing):
            atomic_write_bytes(self.manifest_path, json.dumps(self.manifest, indent=1).encode())

    def commit_failures(self, index: int, results: Sequence[ObjectResult]) -> bytes:
        """Write a finished part's failures file (first step of its commit); the part metadata."""
        failed = [r for r in results if r.error_type is not None]
        meta = json.dumps(
            {
                "part": index,
                "digest": self.digest,
                "item_ids": self.parts[index],
                "failed_ids": [r.item_id for r in failed],
            }
        ).encode()
        rows = [
            {
                self.id_column: r.item_id,
                "cause": failure_cause(str(r.error_type)),
                "error_message": r.error_message,
            }
            for r in failed
        ]
        fail_table = pa.Table.from_pylist(rows, schema=self.fail_schema)
        _write_table(
            fail_table.replace_schema_metadata({_META_KEY: meta}),
            self.out / FAILURES_DIR / part_name(index),
        )
        return meta

    def payloads(self, index: int, results: Sequence[ObjectResult]) -> PartPayloads:
        """The payloads of a finished part, for its part writer."""
        payloads = [(r.item_id, r.payload) for r in results if r.payload is not None]
        return PartPayloads(index, self.out, list(self.parts[index]), payloads)

    def commit_rows(self, index: int, results: Sequence[ObjectResult], meta: bytes) -> None:
        """Write a part's rows file: the last step of its commit (after failures and log)."""
        tables = [r.table for r in results if r.table is not None]
        rows = pa.concat_tables(tables) if tables else self.schema.empty_table()
        _write_table(rows.replace_schema_metadata({_META_KEY: meta}), self.out / part_name(index))

    # ---- resume checks

    def _valid_part(self, index: int) -> int | None:
        """Failed objects of a complete, valid part; ``None`` when it must be recomputed."""
        ids = self.parts[index]
        try:
            rows = pq.read_table(self.out / part_name(index))
            fails = pq.read_table(self.out / FAILURES_DIR / part_name(index))
        except (OSError, pa.ArrowException):
            return None
        meta_rows, meta_fails = _part_metadata(rows), _part_metadata(fails)
        if meta_rows is None or meta_rows != meta_fails:
            return None
        if meta_rows.get("digest") != self.digest or meta_rows.get("item_ids") != ids:
            return None
        if not rows.schema.equals(self.schema, check_metadata=False):
            return None
        if not fails.schema.equals(self.fail_schema, check_metadata=False):
            return None
        failed_ids = meta_rows.get("failed_ids", [])
        if fails.column(self.id_column).to_pylist() != failed_ids:
            return None
        # rows only of this part's objects (a failed object may keep rows)
        if not set(rows.column(self.id_column).to_pylist()) <= set(ids):
            return None
        return len(failed_ids)

    def _compare_manifest(self, old: Mapping[str, Any]) -> None:
        new, out = self.manifest, self.out
        if old.get("format") != SWEEP_FORMAT:
            raise InputDataError(
                "not a deformctl sweep directory (unknown manifest format)", path=out
            )
        if old.get("fingerprint") != new["fingerprint"]:
            keys = sorted(
                k
                for k in set(old.get("fingerprint", {})) | set(new["fingerprint"])
                if old.get("fingerprint", {}).get(k) != new["fingerprint"].get(k)
            )
            raise InputDataError(
                f"cannot resume: made by a different command or settings (differs in {keys})",
                path=out,
            )
        if old.get("schema") != new["schema"] or old.get("id_column") != new["id_column"]:
            raise InputDataError("cannot resume: made with a different schema", path=out)
        if old.get("parts") != new["parts"]:
            raise InputDataError(
                "cannot resume: made for a different list of objects or partition size", path=out
            )

    def _move_old_layout_logs(self) -> None:
        """Move the logs of a first-layout directory (``part-00000.mcap``) into ``_logs/``."""
        for p in self.out.glob("part-*"):
            if p.is_file() and p.suffix != ".parquet":
                (self.out / LOGS_DIR).mkdir(exist_ok=True)
                os.replace(p, self.out / LOGS_DIR / p.name)

    def _clean_temp_files(self) -> None:
        for sub in (self.out, self.out / FAILURES_DIR, self.out / LOGS_DIR):
            if sub.is_dir():
                for p in sub.iterdir():
                    if p.is_file() and _is_temp_file(p.name):
                        p.unlink(missing_ok=True)

    def _remove_sweep_files(self) -> None:
        """Remove what a sweep writes (manifest, parts, failures, part logs), nothing else."""
        for p in self.out.iterdir():
            if p.is_file() and (
                p.name == MANIFEST_NAME or p.name.startswith("part-") or _is_temp_file(p.name)
            ):
                p.unlink()
        for sub in (FAILURES_DIR, LOGS_DIR):
            sub_dir = self.out / sub
            if sub_dir.is_dir():
                for p in sub_dir.iterdir():
                    if p.is_file():
                        p.unlink()
                with contextlib.suppress(OSError):
                    sub_dir.rmdir()


# --------------------------------------------------------------------------- reading


def _manifest(path: Path) -> dict[str, Any] | None:
    try:
        data = jsonsafe.loads((path / MANIFEST_NAME).read_bytes(), allow_nan=True)
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def dataset_part_paths(
    path: str | os.PathLike[str],
    suffix: str = ".parquet",
    *,
    sub: str = "",
    what: str = "parts",
    rerun: str = "the sweep",
) -> list[Path]:
    """The files ``part-*<suffix>`` of a dataset directory (or its ``sub`` folder), in order.

    With a manifest, every part it lists must be there: a missing one means an interrupted
    sweep.

    Args:
        path: the dataset directory.
        suffix: ``.parquet`` (rows or failures) or ``.mcap`` (part logs).
        sub: a folder inside the directory (``_failures``).
        what, rerun: words for the message (``"squeeze logs"``, ``"measure"``).

    Raises:
        InputDataError: an unreadable manifest, missing parts, or no parts and no manifest.
    """
    d = Path(path)
    base = d / sub if sub else d
    files = sorted(base.glob(f"part-*{suffix}")) if base.is_dir() else []
    if (d / MANIFEST_NAME).is_file():
        try:
            n_parts = len(jsonsafe.loads((d / MANIFEST_NAME).read_bytes(), allow_nan=True)["parts"])
        except (OSError, ValueError, KeyError, TypeError):
            raise InputDataError(f"unreadable {MANIFEST_NAME}", path=d) from None
        present = {p.name for p in files}
        missing = [part_name(k, suffix) for k in range(n_parts)]
        missing = [name for name in missing if name not in present]
        if missing:
            raise InputDataError(
                f"incomplete sweep: {len(missing)} of {n_parts} {what} missing "
                f"(first {missing[0]}); rerun {rerun} with --resume",
                path=d,
            )
    if not files:
        if suffix == ".parquet":
            if not (d / MANIFEST_NAME).is_file():
                raise InputDataError("no part-*.parquet files and no sweep manifest", path=d)
        else:
            raise InputDataError(f"no part-*{suffix} {what} in the directory", path=d)
    return files


def _logs_base(path: Path) -> str:
    """Where a directory's part logs are: ``_logs/``, or beside the rows (first layout)."""
    if (path / LOGS_DIR).is_dir() or not any(path.glob("part-*.mcap")):
        return LOGS_DIR
    return ""


def dataset_log_paths(
    path: str | os.PathLike[str],
    suffix: str = ".mcap",
    *,
    what: str = "logs",
    rerun: str = "the sweep",
) -> list[Path]:
    """The part logs ``_logs/part-*<suffix>`` of a dataset directory, in part order.

    A directory of the first layout (logs beside the rows) gives its top-level logs.

    Raises:
        InputDataError: see :func:`dataset_part_paths`.
    """
    d = Path(path)
    return dataset_part_paths(d, suffix, sub=_logs_base(d), what=what, rerun=rerun)


def part_log_path(path: str | os.PathLike[str], index: int, suffix: str = ".mcap") -> Path:
    """The log of part ``index`` of a dataset directory (either layout)."""
    d = Path(path)
    base = _logs_base(d)
    return (d / base if base else d) / part_name(index, suffix)


def iter_dataset_parts(path: str | os.PathLike[str]) -> Iterator[pa.Table]:
    """Yield the tables of a Parquet file (one) or of a sweep directory (one per part, in order).

    Raises:
        MissingInputError: ``path`` does not exist.
        InputDataError: not Parquet, an incomplete sweep, or parts with different schemas.
    """
    p = Path(path)
    if not p.exists():
        raise MissingInputError("no such file or directory", path=p)
    files = dataset_part_paths(p) if p.is_dir() else [p]
    first: pa.Schema | None = None
    for f in files:
        table = _read_parquet(f)
        if first is None:
            first = table.schema
        elif not table.schema.equals(first):
            raise InputDataError("part schema differs from the first part's", path=f)
        yield table


def _read_parquet(path: Path) -> pa.Table:
    try:
        return pq.read_table(path).replace_schema_metadata(None)
    except (OSError, pa.ArrowException) as err:
        raise InputDataError(
            f"not a readable Parquet file ({_one_line(str(err))[:160]})", path=path
        ) from None


def read_dataset(path: str | os.PathLike[str]) -> pd.DataFrame:
    """Read a single Parquet file or a sweep directory (parts concatenated in order).

    Returns:
        The rows as a DataFrame with a fresh RangeIndex.
    """
    import pandas as pd

    tables = list(iter_dataset_parts(path))
    return pa.concat_tables(tables).to_pandas() if tables else pd.DataFrame()


def read_failures(path: str | os.PathLike[str]) -> pd.DataFrame:
    """The failed objects of a sweep directory: id column, ``cause`` (:data:`FAILURE_CAUSES`),
    ``error_message`` (the parts of older versions' ``error_type`` read as their cause)."""
    p = Path(path)
    if not p.is_dir():
        raise MissingInputError("no such sweep directory", path=p)
    tables = []
    for f in dataset_part_paths(p, sub=FAILURES_DIR):
        t = _read_parquet(f)
        if "error_type" in t.column_names:
            causes = [failure_cause(str(v)) for v in t.column("error_type").to_pylist()]
            i = t.column_names.index("error_type")
            t = t.set_column(i, pa.field("cause", pa.string(), nullable=False), pa.array(causes))
        tables.append(t.replace_schema_metadata(None))
    return pa.concat_tables(tables).to_pandas()


def read_table_any(path: str, kind: str) -> pd.DataFrame:
    """Read a table of ``kind``: a Parquet file (:func:`~deformctl.artifacts.read_table`) or a
    sweep dataset directory (parts concatenated in order, validated against the spec).

    Raises:
        SchemaError: a directory of another kind (exit 65).
        InputDataError: an incomplete or damaged directory (exit 65).
    """
    if not os.path.isdir(path):
        return read_table(path, kind)
    d = Path(path)
    manifest = _manifest(d)
    found = None if manifest is None else manifest.get("fingerprint", {}).get("kind")
    if found is not None and found != kind:
        raise SchemaError(f"is a {found} dataset, expected {kind}", path=d, field="kind")
    df = validate_frame(read_dataset(d), kind, path=d)
    df.attrs = {"kind": kind, "provenance": None}
    return df


def describe_dataset(path: str | os.PathLike[str]) -> dict[str, Any]:
    """A summary of a sweep directory: kind, command, parts (done / expected), rows, failures.

    Raises:
        InputDataError: not a sweep directory (no readable manifest and no parts).
    """
    d = Path(path)
    manifest = _manifest(d)
    parts = sorted(d.glob("part-*.parquet"))
    if manifest is None and not parts:
        raise InputDataError("not a deformctl dataset directory (no _sweep.json, no parts)", path=d)
    fingerprint = (manifest or {}).get("fingerprint", {})
    expected = len((manifest or {}).get("parts", [])) or len(parts)
    rows = 0
    failed = 0
    for p in parts:
        rows += pq.ParquetFile(p).metadata.num_rows
        f = d / FAILURES_DIR / p.name
        if f.is_file():
            failed += pq.ParquetFile(f).metadata.num_rows
    columns = [] if not parts else [
        {"name": f.name, "type": str(f.type), "unit": (f.metadata or {}).get(b"unit", b"").decode()}
        for f in pq.read_schema(parts[0])
    ]  # fmt: skip
    return {
        "path": str(d),
        "format": "dataset",
        "kind": fingerprint.get("kind"),
        "command": fingerprint.get("command"),
        "parts": len(parts),
        "parts_expected": expected,
        "complete": len(parts) == expected,
        "objects": (manifest or {}).get("n_items"),
        "rows": rows,
        "failed": failed,
        "logs": len(list((d / _logs_base(d)).glob("part-*.mcap"))),
        "columns": columns,
        "settings": fingerprint.get("settings"),
        "seed": fingerprint.get("seed"),
        "tool_version": fingerprint.get("tool_version"),
    }
