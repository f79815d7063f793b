"""Identify an artifact and summarise it (the library behind ``deformctl inspect``).

:func:`detect_kind` tells which artifact a file is from its bytes: the MCAP ``deformctl``
metadata record (or its topics), the Parquet ``deformctl`` schema metadata (or, for tables written
by other tools, the spec whose required columns it has), or a CSV header with the catalog's
columns. :func:`describe` reads the file through the matching reader, so everything ``inspect``
reports has passed the same validation the pipeline applies, and returns a JSON-serialisable dict.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from deformctl.artifacts.io import PathArg, display_name, is_stdio, read_input_bytes
from deformctl.artifacts.mcap import (
    KIND_LIFT,
    KIND_SQUEEZE,
    MCAP_MAGIC,
    McapContents,
    decode_objects,
    decode_provenance,
    lift_attempts_from_contents,
    load_mcap,
    squeezes_from_contents,
    topic_schema,
)
from deformctl.artifacts.provenance import Provenance
from deformctl.artifacts.schema import (
    TABLE_KINDS,
    load_json_schema,
    load_table_spec,
    schema_version,
)
from deformctl.artifacts.tables import (
    PARQUET_MAGIC,
    _frame_from_arrow,
    read_catalog_bytes,
    read_parquet_bytes,
)
from deformctl.blas import blas_record
from deformctl.errors import DeformctlError, InputDataError, SchemaError
from deformctl.series import SqueezeSeries, ruptures_from_object
from deformctl.units import NS_PER_S

GENERIC_MCAP = "mcap"  #: kind of an MCAP file deformctl did not write (e.g. a ROS 2 bag)
ZIP_MAGIC = b"PK"  #: a skops model file is a zip archive
KIND_MODEL = "model"  #: kind of a model file written by ``train``


def sniff_format(data: bytes) -> str:
    """``"mcap"``, ``"parquet"``, ``"skops"`` (a zip archive) or ``"csv"`` from the first bytes."""
    if data.startswith(MCAP_MAGIC):
        return "mcap"
    if data.startswith(PARQUET_MAGIC):
        return "parquet"
    if data.startswith(ZIP_MAGIC):
        return "skops"
    return "csv"


def _table_kind_from_columns(columns: list[str], name: str) -> str:
    """The table kind whose required columns ``columns`` has (the most specific one)."""
    best: tuple[int, str] | None = None
    for kind in TABLE_KINDS:
        required = load_table_spec(kind).required
        if set(required) <= set(columns) and (best is None or len(required) > best[0]):
            best = (len(required), kind)
    if best is None:
        raise SchemaError("columns match no deformctl table spec", path=name)
    return best[1]


def _csv_header(data: bytes, name: str) -> list[str]:
    try:
        first = data.decode("utf-8-sig").splitlines()[0] if data.strip() else ""
    except UnicodeDecodeError as err:
        raise InputDataError(f"not UTF-8 text (byte {err.start})", path=name) from None
    return [c.strip() for c in first.split(",")]


def _detect(data: bytes, path: PathArg) -> tuple[str, str]:
    name = display_name(path)
    fmt = sniff_format(data)
    if fmt == "mcap":
        contents = load_mcap(data, path)
        contents.check_declared_kind()  # inspect shows no log under a false label
        return fmt, contents.kind or GENERIC_MCAP
    if fmt == "skops":
        _load_model_bytes(data, path)
        return fmt, KIND_MODEL
    if fmt == "parquet":
        table, meta = read_parquet_bytes(data, path)
        if meta is not None:
            return fmt, str(meta["kind"])
        return fmt, _table_kind_from_columns(table.column_names, name)
    if not data.strip():
        raise InputDataError("empty file", path=name)
    header = _csv_header(data, name)
    if set(load_table_spec("catalog").required) <= set(header):
        return fmt, "catalog"
    raise InputDataError(
        "not a deformctl artifact (not MCAP, not Parquet, no catalog header)", path=name
    )


def detect_kind(path: PathArg) -> str:
    """Which artifact ``path`` is.

    Returns:
        A table kind (``catalog``, ``coefficients``, ``lift_results``, ``index_table``,
        ``predictions``), ``squeeze_log``, ``lift_log``, ``model`` (a model file, loaded through
        the allow-list of :func:`~deformctl.artifacts.model.load_model`), or ``mcap`` for
        another MCAP file.

    Raises:
        MissingInputError: ``path`` does not exist (exit 66).
        InputDataError, SchemaError: the file is damaged or is no artifact deformctl knows (65).
    """
    return _detect(read_input_bytes(path), path)[1]


def _clean(value: Any) -> Any:
    """JSON-safe copy: NaN/inf → None, numpy scalars → Python."""
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_clean(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, str | bytes):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _dtype_name(series: pd.Series) -> str:
    """A spec-style dtype name for a column the spec does not list."""
    if pd.api.types.is_bool_dtype(series):
        return "bool"
    if pd.api.types.is_integer_dtype(series):
        return "int64"
    if pd.api.types.is_float_dtype(series):
        return "float64"
    if pd.api.types.is_string_dtype(series):
        return "string"
    return str(series.dtype)


def _model_provenance(prov: Any, name: str) -> dict[str, Any] | None:
    """A model file's provenance as a dict, or None (none stored, or a malformed record)."""
    if prov is None:
        return None
    try:
        return Provenance.from_dict(prov, path=name).to_dict()
    except SchemaError:
        return None


def _table_summary(df: pd.DataFrame, kind: str) -> dict[str, Any]:
    spec = load_table_spec(kind)
    columns = []
    attrs = df.attrs
    # pandas deep-copies ``attrs`` (a unit per column) into every column and row it hands out:
    # read them once and iterate a frame without them (10,000 columns: 8 s -> linear)
    df = df.copy(deep=False)
    df.attrs = {}
    units = attrs.get("units", {})
    for c in df.columns:
        col = spec.column(str(c))
        columns.append(
            {
                "name": str(c),
                "dtype": col.dtype if col else _dtype_name(df[c]),
                "unit": units.get(str(c)),
                "required": bool(col.required) if col else False,
                "description": col.description if col else "",
            }
        )
    prov = attrs.get("provenance")
    out: dict[str, Any] = {
        "kind": kind,
        "schema": {"name": spec.name, "version": attrs.get("schema_version", spec.version)},
        "rows": len(df),
        "columns": columns,
        "provenance": None if prov is None else prov.to_dict(),
    }
    if kind == "catalog":
        out["objects"] = df.to_dict("records")
    if kind == "coefficients":
        out["coefficients"] = coefficient_rows(df)
    return out


#: The per-object numbers ``inspect`` shows for a coefficients table.
COEFFICIENT_SUMMARY = ("object_id", "deformability_n_per_cm", "damping_ns_per_cm", "r2", "quality")


def coefficient_rows(df: pd.DataFrame) -> list[dict[str, Any]]:
    """Per object: D, λ, R² and quality (None where a table written before v2 has no column)."""
    return [{key: row.get(key) for key in COEFFICIENT_SUMMARY} for row in df.to_dict("records")]


def squeeze_summaries(
    objects: list[dict[str, Any]], squeezes: list[SqueezeSeries]
) -> list[dict[str, Any]]:
    """Per object of a squeeze log: squeezes, peak force and compression, rates, phase, ruptures,
    and for a CSV recording its columns and the recording's defects.

    The sample rates are those ``measure`` stored (``force_rate_hz``, ``position_rate_hz``), or
    the squeezes' own median rate when the log does not say.
    """
    meta = {str(o.get("object_id")): o for o in objects}
    by_object: dict[str, list[SqueezeSeries]] = {}
    for sq in squeezes:
        by_object.setdefault(sq.object_id, []).append(sq)
    out = []
    for oid, group in by_object.items():
        obj = meta.get(oid, {})
        steps = np.concatenate([np.diff(s.time_s) for s in group])
        own_rate = float(1.0 / np.median(steps)) if steps.size else None
        out.append(
            {
                "object_id": oid,
                "squeezes": len(group),
                "peak_force_n": max(float(np.max(s.force_n)) for s in group),
                "peak_compression_m": max(float(np.max(s.compression_m)) for s in group),
                "force_rate_hz": obj.get("force_rate_hz", own_rate),
                "position_rate_hz": obj.get("position_rate_hz", own_rate),
                "phase": obj.get("phase", "all"),
                "ruptures": [r.to_record() for r in ruptures_from_object(obj)],
                "columns": _csv_columns(obj),
                "recording_flags": list(obj.get("recording_flags") or []),
            }
        )
    return out


def _csv_columns(obj: dict[str, Any]) -> str | None:
    """A CSV recording's columns as ``measure`` read them: ``time='Time (s)' [s], ...``."""
    csv = obj.get("csv")
    columns = csv.get("columns") if isinstance(csv, dict) else None
    if not isinstance(columns, dict):
        return None
    return ", ".join(
        f"{role}={c.get('column')!r} [{c.get('unit')}]"
        for role, c in columns.items()
        if isinstance(c, dict)
    )


def _fields(schema_name: str) -> list[dict[str, Any]]:
    schema = load_json_schema(schema_name)
    required = set(schema.get("required", []))
    fields = []
    for key, prop in schema["properties"].items():
        typ = prop.get("type")
        fields.append(
            {
                "name": key,
                "type": typ if isinstance(typ, str) else "|".join(typ),
                "unit": prop.get("x-unit"),
                "required": key in required,
                "description": prop.get("description", ""),
            }
        )
    return fields


def _mcap_summary(contents: McapContents) -> dict[str, Any]:
    kind = contents.kind or GENERIC_MCAP
    extra: dict[str, Any] = {}
    if kind == KIND_SQUEEZE:
        squeezes = squeezes_from_contents(contents)
        per_object: dict[str, int] = {}
        for sq in squeezes:
            per_object[sq.object_id] = per_object.get(sq.object_id, 0) + 1
        extra = {
            "squeezes": len(squeezes),
            "squeezes_per_object": per_object,
            "squeeze_summary": squeeze_summaries(decode_objects(contents), squeezes),
        }
    elif kind == KIND_LIFT:
        attempts = lift_attempts_from_contents(contents)
        per_object = {}
        for att in attempts:
            per_object[att.object_id] = per_object.get(att.object_id, 0) + 1
        extra = {
            "attempts": len(attempts),
            "attempts_per_object": per_object,
            "lifted": sum(att.outcome.lifted for att in attempts),
        }
        starts = [  # a seeded run (lift --start-model): each object's prediction and outcome
            {"object_id": o["object_id"], **o["start"]}
            for o in decode_objects(contents)
            if isinstance(o.get("start"), dict)
        ]
        if starts:
            extra["starts"] = starts
    objects = decode_objects(contents) if kind != GENERIC_MCAP else []
    counts = contents.message_counts()
    channels = []
    for channel in contents.channels.values():
        schema = contents.schemas.get(channel.schema_id)
        entry: dict[str, Any] = {
            "topic": channel.topic,
            "message_encoding": channel.message_encoding,
            "schema": None if schema is None else schema.name,
            "schema_encoding": None if schema is None else schema.encoding,
            "messages": counts.get(channel.topic, 0),
        }
        found = topic_schema(channel.topic)
        if kind != GENERIC_MCAP and found is not None:
            name = found[0]
            entry["schema_version"] = schema_version(load_json_schema(name))
            entry["fields"] = _fields(name)
        channels.append(entry)
    rng = contents.time_range_ns()
    prov = decode_provenance(contents) if kind != GENERIC_MCAP else None
    return {
        "kind": kind,
        "schema": None if kind == GENERIC_MCAP else {"name": kind, "version": 1},
        "messages": len(contents.messages),
        "channels": channels,
        "time_range": None
        if rng is None
        else {
            "start_ns": rng[0],
            "end_ns": rng[1],
            "duration_s": (rng[1] - rng[0]) / NS_PER_S,
        },
        "metadata": sorted({n for n, _ in contents.metadata}),
        "objects": objects,
        **extra,
        "provenance": None if prov is None else prov.to_dict(),
    }


def _load_model_bytes(data: bytes, path: PathArg) -> tuple[Any, dict[str, Any]]:
    """:func:`~deformctl.artifacts.model.load_model` on a path, or on stdin bytes via a temp file.

    The import is deferred: it pulls in scikit-learn, which ``inspect`` on other files never needs.
    """
    from deformctl.artifacts.model import load_model

    if not is_stdio(path):
        return load_model(path)
    with tempfile.TemporaryDirectory(prefix="deformctl-") as tmpdir:
        tmp = Path(tmpdir) / "stdin.skops"
        tmp.write_bytes(data)
        try:
            return load_model(tmp)
        except DeformctlError as err:  # name stdin, not the temporary file
            raise InputDataError(err.message, path=display_name(path)) from None


def _float_pair(lo: Any, hi: Any) -> list[float] | None:
    try:
        return [float(lo), float(hi)]
    except (TypeError, ValueError):
        return None


def _model_summary(data: bytes, path: PathArg) -> dict[str, Any]:
    """Summary of a model file. Nothing in it is trusted: every field is type-checked here."""
    model, meta = _load_model_bytes(data, path)
    name = display_name(path)
    names = getattr(model, "feature_names_in_", None)
    feats = meta.get("features")
    if names is not None and len(names) > 0:
        features = [str(f) for f in names]
    elif isinstance(feats, list):
        features = [str(f) for f in feats]
    else:
        features = []
    lo, hi = getattr(model, "feature_min_", None), getattr(model, "feature_max_", None)
    training_range: dict[str, list[float] | None] = {}
    if lo is not None and hi is not None and len(lo) == len(hi) == len(features):
        training_range = {f: _float_pair(a, b) for f, a, b in zip(features, lo, hi, strict=True)}
    stored = meta.get("training_range")  # format 2: the checked ranges, inputs and groups
    if isinstance(stored, dict) and all(
        isinstance(v, list) and len(v) == 2 for v in stored.values()
    ):
        training_range.update({str(k): _float_pair(*v) for k, v in stored.items()})
    conformal = {}
    if isinstance(meta.get("conformal"), dict):
        for p, entry in meta["conformal"].items():
            if isinstance(entry, dict):
                conformal[str(p)] = {
                    k: v for k, v in entry.items() if isinstance(v, int | float) or v is None
                }
    raw_notes = meta.get("notes")
    notes: dict[Any, Any] = raw_notes if isinstance(raw_notes, dict) else {}
    metrics = {}
    for key in ("model", "baseline_nearest", "baseline_f_w", "baseline_constant_ratio"):
        entry = meta.get(key)
        if isinstance(entry, dict):
            metrics[key] = {
                split: {k: v for k, v in entry[split].items() if isinstance(v, int | float)}
                for split in ("train", "test")
                if isinstance(entry.get(split), dict)
            }
    prov = meta.get("provenance")
    seed = meta.get("seed")
    fmt_name, _, fmt_version = str(meta.get("format", "")).rpartition("/")
    return {
        "kind": KIND_MODEL,
        "schema": {
            "name": fmt_name,
            "version": int(fmt_version) if fmt_version.isdigit() else fmt_version,
        },
        "features": features,
        "target": meta.get("target") if isinstance(meta.get("target"), str) else None,
        "training_range": training_range,
        "seed": seed if isinstance(seed, int) and not isinstance(seed, bool) else None,
        "hyperparameters": meta.get("hyperparameters")
        if isinstance(meta.get("hyperparameters"), dict)
        else None,
        "form": str(meta.get("form", "paper")),
        "n_train": meta.get("n_train") if isinstance(meta.get("n_train"), int) else None,
        "n_calibration": meta.get("n_calibration")
        if isinstance(meta.get("n_calibration"), int)
        else 0,
        "n_test": meta.get("n_test") if isinstance(meta.get("n_test"), int) else None,
        "metrics": metrics,
        "conformal": conformal,
        "notes": {str(k): str(v) for k, v in notes.items()},
        "adapted": meta.get("adapted") if isinstance(meta.get("adapted"), dict) else None,
        "laws": law_summary(meta),
        "tool_version": str(meta.get("tool_version", "unknown")),
        "blas": blas_record(meta.get("blas")),
        # predict never reads it, so a malformed record is shown as missing, not refused: the
        # same file gets the same verdict from inspect and predict (grip.modelfile)
        "provenance": _model_provenance(prov, name),
    }


def law_summary(meta: dict[str, Any]) -> dict[str, Any] | None:
    """A grip model's material law mix, ranges and per-law figures (None: none stated)."""
    from deformctl.grip.laws import law_summary as summary

    return summary(meta)


def describe(path: PathArg, *, data: bytes | None = None) -> dict[str, Any]:
    """Read, validate and summarise any artifact (``data``: its bytes, when already read).

    Returns:
        A JSON-serialisable dict: ``path``, ``format``, ``kind``, ``schema`` (name, version),
        ``provenance``; for tables ``rows`` and ``columns`` (name, dtype, unit, required,
        description) and, for a catalog, ``objects``; for MCAP logs ``messages``, ``channels``
        (topic, schema, message count, fields with units), ``time_range`` and ``objects``;
        for a squeeze log ``squeeze_summary`` (per object: squeezes, peak force and compression,
        sample rates, phase, ruptures); for a coefficients table ``coefficients`` (per object: D,
        λ, R², quality); for a model file (kind ``model``) ``features``, ``target``,
        ``training_range`` (feature, and for a grip model group, -> [min, max]), ``seed``,
        ``hyperparameters``, ``form``, ``n_train``, ``n_calibration``, ``n_test``, ``metrics``
        (model and baselines, train and test), ``conformal`` (the bound's coverage and margins
        on the test rows), ``notes``, ``tool_version`` and ``blas`` (the BLAS libraries, kernels
        and thread count of the fit; None for older files).

    Raises:
        MissingInputError: ``path`` does not exist (exit 66).
        InputDataError, SchemaError: damaged or invalid (exit 65).
    """
    data = read_input_bytes(path) if data is None else data
    name = display_name(path)
    fmt = sniff_format(data)
    if fmt == "mcap":
        contents = load_mcap(data, path)
        contents.check_declared_kind()  # no log shown under a false label
        summary = _mcap_summary(contents)
    elif fmt == "skops":
        summary = _model_summary(data, path)
    elif fmt == "parquet":
        table, meta = read_parquet_bytes(data, path)
        kind = str(meta["kind"]) if meta else _table_kind_from_columns(table.column_names, name)
        if kind not in TABLE_KINDS:
            raise SchemaError(f"unknown table kind {kind!r}", path=name, field="kind")
        if kind == "catalog":
            summary = _table_summary(read_catalog_bytes(data, path), kind)
        else:
            summary = _table_summary(_frame_from_arrow(table, meta, kind, path), kind)
    else:
        _detect(data, path)  # refuses a CSV without the catalog header
        summary = _table_summary(read_catalog_bytes(data, path), "catalog")
    return _clean({"path": name, "format": fmt, **summary})
