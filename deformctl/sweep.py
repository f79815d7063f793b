"""Per-object sweeps of ``measure --sim``, ``characterize`` and ``lift --sim`` at scale.

The stage commands hand their per-object work to :func:`deformctl.parallel.run_sweep` when the
output is a *dataset directory* (see :func:`is_dataset_output`): local worker processes
(``--workers N``, default every core) or a running Dask cluster (``--scheduler``). Each stage has
one picklable task object here (:class:`LiftTask`, :class:`MeasureTask`,
:class:`CharacterizeTask`) that computes one object exactly as the serial command does, so a
sweep gives the serial rows, row for row, whatever the number of workers or partitions:

* ``lift --sim``: rows of the ``lift_results`` spec; part ``k`` has its attempt log
  ``part-k.mcap`` (a lift log). A search that does not converge keeps its row (``converged =
  false``, ``error``) and is counted and recorded as failed.
* ``measure --sim``: one summary row per object (:data:`MEASURE_SCHEMA`); part ``k`` has its
  squeeze log ``part-k.mcap``. The noise stream of an object depends on its catalog position
  and the seed only.
* ``characterize DIR``: reads a ``measure`` directory's squeeze logs; rows of the
  ``coefficients`` spec.

A catalog row the simulator refuses, or an object that cannot be fitted, fails alone: the
failures part records it and the sweep goes on. Every stage also reads such directories:
:func:`read_table_any` (a table file or a dataset directory) and :func:`squeeze_log_parts`.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import pandas as pd
import pyarrow as pa

from deformctl import __version__
from deformctl.artifacts.schema import load_table_spec, validate_frame
from deformctl.errors import InputDataError, SchemaError, UsageError
from deformctl.parallel import (
    MANIFEST_NAME,
    PartPayloads,
    TaskOutput,
    iter_dataset_parts,
    read_dataset,
)

__all__ = [
    "MEASURE_SCHEMA",
    "CharacterizeTask",
    "LiftTask",
    "MeasureTask",
    "SweepOptions",
    "characterize_items",
    "dataset_fingerprint",
    "describe_dataset",
    "is_dataset_output",
    "read_table_any",
    "squeeze_log_parts",
    "table_schema",
]

_ARROW_TYPES = {
    "string": pa.string(),
    "float64": pa.float64(),
    "int64": pa.int64(),
    "bool": pa.bool_(),
}

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
#: The dataset kind each sweeping command writes (stored in the manifest's fingerprint).
COMMAND_KINDS = {"measure": "squeeze_log", "characterize": "coefficients", "lift": "lift_results"}


# --------------------------------------------------------------------------- options


@dataclass(frozen=True)
class SweepOptions:
    """The scale-out flags of a stage command, as given (None: not given).

    Attributes:
        workers: ``--workers N`` local processes.
        scheduler: ``--scheduler tcp://HOST:PORT`` of a running Dask scheduler.
        connect_timeout_s: ``--connect-timeout S``.
        partition_size: ``--partition-size N`` objects per part.
        resume: ``--resume``.
    """

    workers: int | None = None
    scheduler: str | None = None
    connect_timeout_s: float | None = None
    partition_size: int | None = None
    resume: bool = False

    def given(self) -> list[str]:
        """The flags given on the command line."""
        flags = [
            ("--workers", self.workers),
            ("--scheduler", self.scheduler),
            ("--connect-timeout", self.connect_timeout_s),
            ("--partition-size", self.partition_size),
        ]
        out = [flag for flag, value in flags if value is not None]
        return out + (["--resume"] if self.resume else [])

    def check(self, output: str) -> bool:
        """Check the flags against the output; True when the output is a dataset directory.

        Raises:
            UsageError: a sweep flag with a single-file output, ``--workers`` < 1, both
                ``--workers`` and ``--scheduler``, ``--connect-timeout`` without
                ``--scheduler`` or <= 0, ``--partition-size`` < 1.
        """
        dataset = is_dataset_output(output)
        if not dataset and self.given():
            raise UsageError(
                f"{self.given()[0]} needs a dataset directory output "
                f"(end -o with /, e.g. -o {output.rstrip('/') or 'out'}/)"
            )
        if self.workers is not None and self.workers < 1:
            raise UsageError(f"--workers must be >= 1, got {self.workers}")
        if self.workers is not None and self.scheduler is not None:
            raise UsageError("give either --workers (local processes) or --scheduler, not both")
        if self.connect_timeout_s is not None:
            if self.scheduler is None:
                raise UsageError("--connect-timeout needs --scheduler")
            if not (math.isfinite(self.connect_timeout_s) and self.connect_timeout_s > 0):
                raise UsageError(f"--connect-timeout must be > 0 s, got {self.connect_timeout_s}")
        if self.partition_size is not None and self.partition_size < 1:
            raise UsageError(f"--partition-size must be >= 1, got {self.partition_size}")
        return dataset

    def run_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :func:`deformctl.parallel.run_sweep` for these flags."""
        kwargs: dict[str, Any] = {
            "workers": self.workers,
            "scheduler": self.scheduler,
            "resume": self.resume,
        }
        if self.connect_timeout_s is not None:
            kwargs["connect_timeout_s"] = self.connect_timeout_s
        if self.partition_size is not None:
            kwargs["partition_size"] = self.partition_size
        return kwargs


def is_dataset_output(path: str) -> bool:
    """The rule for a partitioned dataset output: a path ending in ``/`` or an existing directory.

    Everything else (``x.parquet``, ``x.mcap``, ``-``) is a single file, written as before.
    """
    return path != "-" and (path.endswith(("/", os.sep)) or os.path.isdir(path))


def dataset_fingerprint(
    command: str, settings: Mapping[str, Any], inputs: Mapping[str, str], seed: int | None = None
) -> dict[str, Any]:
    """What a resume must match: command, output kind and schema version, settings, inputs."""
    kind = COMMAND_KINDS[command]
    version = load_table_spec(kind).version if kind != "squeeze_log" else 1
    return {
        "command": command,
        "kind": kind,
        "schema_version": version,
        "tool_version": __version__,
        "settings": dict(settings),
        "inputs": dict(inputs),
        "seed": seed,
    }


def table_schema(kind: str) -> pa.Schema:
    """The Arrow schema of a table kind's spec columns, in spec order, with unit metadata."""
    spec = load_table_spec(kind)
    return pa.schema(
        [
            pa.field(
                col.name,
                _ARROW_TYPES[col.dtype],
                metadata={"unit": col.unit or "", "description": col.description},
            )
            for col in spec.columns
        ]
    )


def _spec_rows(df: pd.DataFrame, kind: str) -> pa.Table:
    """A validated frame as a table of :func:`table_schema` (spec columns only, None for NaN)."""
    norm = validate_frame(df, kind)
    schema = table_schema(kind)
    arrays = []
    for fld in schema:
        if fld.name in norm.columns:
            values = list(norm[fld.name])
            if pa.types.is_string(fld.type):
                values = [None if v is None or (isinstance(v, float) and v != v) else v
                          for v in values]  # fmt: skip
            arrays.append(pa.array(values, type=fld.type, from_pandas=True))
        else:
            arrays.append(pa.nulls(len(norm), type=fld.type))
    return pa.Table.from_arrays(arrays, schema=schema)


# --------------------------------------------------------------------------- lift --sim


@dataclass(frozen=True)
class LiftTask:
    """``lift --sim`` for one catalog object (a picklable sweep task).

    Attributes:
        profile: the :class:`~deformctl.sim.LiftProfile`.
        settings: the :class:`~deformctl.sim.SimSettings`.
        criterion: the :class:`~deformctl.sim.SlipCriterion`.
        protocol, growth, tolerance_rel, max_attempts: the search options.
    """

    profile: Any
    settings: Any
    criterion: Any
    protocol: str = "refine"
    growth: float = 1.2
    tolerance_rel: float = 0.01
    max_attempts: int = 50

    def __call__(self, item: dict[str, Any]) -> TaskOutput:
        """One object's search: its lift_results row, its attempts as the payload.

        Raises:
            InputDataError: the object cannot be lifted or simulated (recorded as failed).
        """
        from deformctl.lift import lift_catalog
        from deformctl.lift_sim import sim_runner_factory

        factory = sim_runner_factory(
            profile=self.profile, settings=self.settings, criterion=self.criterion
        )
        run = lift_catalog(
            pd.DataFrame([item]),
            factory,
            protocol=self.protocol,  # type: ignore[arg-type]
            growth=self.growth,
            tolerance_rel=self.tolerance_rel,
            max_attempts=self.max_attempts,
        )
        error = run.error_message()
        return TaskOutput(
            rows=_spec_rows(run.table, "lift_results"),
            payload=(run.objects[0], list(run.attempts)),
            error=error,
            error_type="NotConverged" if error else "ObjectFailed",
        )


@dataclass(frozen=True)
class LiftLogWriter:
    """Part writer of a lift sweep: the part's attempts as one lift log ``part-k.mcap``.

    It runs in a local worker process (``in_workers``): encoding a part's messages is the
    sweep's largest serial cost when done by the client.
    """

    provenance: Any
    in_workers: ClassVar[bool] = True

    def __call__(self, part: PartPayloads) -> None:
        """Write ``part``'s attempt log atomically."""
        from deformctl.artifacts import write_lift_log

        objects = [p[0] for _, p in part.payloads]
        attempts = [a for _, p in part.payloads for a in p[1]]
        write_lift_log(
            part.path(".mcap"), objects, attempts, provenance=self.provenance, force=True
        )


# --------------------------------------------------------------------------- measure --sim


@dataclass(frozen=True)
class MeasureTask:
    """``measure --sim`` for one catalog object (a picklable sweep task).

    The item carries the object's catalog row and its catalog position under
    ``"_position"``; the noise stream is derived from (seed, position) as in the serial run.
    """

    simulate: Mapping[str, Any]
    settings: Any
    seed: int = 0

    def __call__(self, item: dict[str, Any]) -> TaskOutput:
        """Squeeze one object: its summary row, its (object row, squeezes) as the payload."""
        from deformctl.measure import simulate_squeezes

        rec = {k: v for k, v in item.items() if k != "_position"}
        objects, series = simulate_squeezes(
            pd.DataFrame([rec]),
            settings=self.settings,
            seed=self.seed,
            first_index=int(item["_position"]),
            **self.simulate,
        )
        row = {
            "object_id": str(rec["object_id"]),
            "squeezes": len(series),
            "samples": int(sum(len(s.time_s) for s in series)),
            "duration_s": float(sum(float(s.time_s[-1]) for s in series)),
            "peak_force_n": float(objects[0]["sim_peak_force_n"]),
        }
        return TaskOutput(rows=[row], payload=(objects[0], series))


@dataclass(frozen=True)
class SqueezeLogWriter:
    """Part writer of a measure sweep: the part's squeezes as one squeeze log ``part-k.mcap``.

    It runs in a local worker process (``in_workers``), as :class:`LiftLogWriter` does.
    """

    provenance: Any
    in_workers: ClassVar[bool] = True

    def __call__(self, part: PartPayloads) -> None:
        """Write ``part``'s squeeze log atomically."""
        from deformctl.artifacts import write_squeeze_log

        objects = [p[0] for _, p in part.payloads]
        series = [s for _, p in part.payloads for s in p[1]]
        write_squeeze_log(
            part.path(".mcap"), objects, series, provenance=self.provenance, force=True
        )


# --------------------------------------------------------------------------- characterize


def squeeze_log_parts(path: str | os.PathLike[str]) -> list[Path]:
    """The squeeze logs ``part-*.mcap`` of a ``measure`` dataset directory, in part order.

    Raises:
        InputDataError: no logs, or a part of the sweep missing (rerun with --resume).
    """
    d = Path(path)
    logs = sorted(d.glob("part-*.mcap"))
    manifest_path = d / MANIFEST_NAME
    if manifest_path.is_file():
        try:
            n_parts = len(json.loads(manifest_path.read_text())["parts"])
        except (OSError, ValueError, KeyError, TypeError):
            raise InputDataError(f"unreadable {MANIFEST_NAME}", path=d) from None
        names = {p.name for p in logs}
        missing = [
            f"part-{k:05d}.mcap" for k in range(n_parts) if f"part-{k:05d}.mcap" not in names
        ]
        if missing:
            raise InputDataError(
                f"incomplete sweep: {len(missing)} of {n_parts} squeeze logs missing "
                f"(first {missing[0]}); rerun measure with --resume",
                path=d,
            )
    if not logs:
        raise InputDataError("no part-*.mcap squeeze logs in the directory", path=d)
    return logs


def characterize_items(path: str | os.PathLike[str]) -> list[dict[str, Any]]:
    """One item per object of a ``measure`` dataset: ``object_id`` and its log's absolute path.

    The objects are those with rows in the dataset (failed objects have no squeezes).
    """
    d = Path(path).resolve()
    logs = squeeze_log_parts(d)
    items: list[dict[str, Any]] = []
    if (d / MANIFEST_NAME).is_file() and any(d.glob("part-*.parquet")):
        for k, table in enumerate(iter_dataset_parts(d)):
            part_log = str(d / f"part-{k:05d}.mcap")
            items.extend(
                {"object_id": oid, "log_path": part_log} for oid in table["object_id"].to_pylist()
            )
        return items
    from deformctl.artifacts import read_squeeze_log

    for log in logs:  # no manifest: ask each log for its objects
        objects, _ = read_squeeze_log(log)
        items.extend({"object_id": str(o["object_id"]), "log_path": str(log)} for o in objects)
    return items


_LOG_CACHE: dict[tuple[str, int], tuple[dict[str, Any], dict[str, list[Any]]]] = {}


def _read_log_cached(path: str) -> tuple[dict[str, Any], dict[str, list[Any]]]:
    """A squeeze log's objects and squeezes by object id; the last log read is kept per process.

    Items arrive in catalog order, so a worker reads each part's log about once.
    """
    from deformctl.artifacts import read_squeeze_log

    key = (path, os.stat(path).st_mtime_ns)
    if key not in _LOG_CACHE:
        objects, squeezes = read_squeeze_log(path)
        by_object: dict[str, list[Any]] = {}
        for s in squeezes:
            by_object.setdefault(s.object_id, []).append(s)
        _LOG_CACHE.clear()
        _LOG_CACHE[key] = ({str(o["object_id"]): o for o in objects}, by_object)
    return _LOG_CACHE[key]


@dataclass(frozen=True)
class CharacterizeTask:
    """``characterize`` for one object of a squeeze-log directory (a picklable sweep task)."""

    method: str = "lsq"
    window_s: float | None = None

    def __call__(self, item: dict[str, Any]) -> pa.Table:
        """Fit one object; its coefficients row.

        Raises:
            InputDataError: the object has no squeezes or cannot be fitted (recorded as failed).
        """
        from deformctl.characterize import characterize, default_window_s

        oid, log = str(item["object_id"]), str(item["log_path"])
        meta, by_object = _read_log_cached(log)
        group = by_object.get(oid)
        if not group:
            raise InputDataError(f"object {oid!r} has no squeezes", path=log)
        rate = meta.get(oid, {}).get("position_rate_hz")
        rate_hz = (
            float(rate) if isinstance(rate, int | float) and not isinstance(rate, bool) else None
        )
        window = self.window_s if self.window_s is not None else default_window_s(rate_hz)
        try:
            df = characterize({oid: group}, self.method, window_s=window)  # type: ignore[arg-type]
        except InputDataError as err:
            if err.path is None:
                raise InputDataError(err.message, path=log) from err
            raise
        return _spec_rows(df, "coefficients")


# --------------------------------------------------------------------------- reading


def _manifest(path: Path) -> dict[str, Any] | None:
    try:
        data = json.loads((path / MANIFEST_NAME).read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def read_table_any(path: str, kind: str) -> pd.DataFrame:
    """Read a table of ``kind``: a Parquet file (:func:`~deformctl.artifacts.read_table`) or a
    sweep dataset directory (parts concatenated in order, validated against the spec).

    Raises:
        SchemaError: a directory of another kind (exit 65).
        InputDataError: an incomplete or damaged directory (exit 65).
    """
    from deformctl.artifacts import read_table

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
    from deformctl.parallel import FAILURES_DIR

    d = Path(path)
    manifest = _manifest(d)
    parts = sorted(d.glob("part-*.parquet"))
    if manifest is None and not parts:
        raise InputDataError("not a deformctl dataset directory (no _sweep.json, no parts)", path=d)
    fingerprint = (manifest or {}).get("fingerprint", {})
    expected = len((manifest or {}).get("parts", [])) or len(parts)
    rows = 0
    failed = 0
    import pyarrow.parquet as pq

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
        "logs": len(list(d.glob("part-*.mcap"))),
        "columns": columns,
        "settings": fingerprint.get("settings"),
        "seed": fingerprint.get("seed"),
        "tool_version": fingerprint.get("tool_version"),
    }
