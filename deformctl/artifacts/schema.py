"""Load the contracts in ``schemas/`` and check data against them.

Two kinds of contract live in the installed package ``deformctl.schemas``:

* ``<kind>.columns.json``: the column spec of a Parquet table (``catalog``, ``coefficients``,
  ``lift_results``, ``index_table``, ``predictions``): for each column its name, dtype
  (``string``, ``float64``, ``int64``, ``bool``), unit, whether it is required, and optional
  constraints (``minimum``, ``exclusive_minimum``, ``unique``, ``nullable``).
* ``<name>.schema.json``: a JSON Schema (draft 2020-12) per MCAP message type and for the rig
  protocol; its ``x-deformctl`` keyword carries the schema's name and version.

:func:`validate_frame` checks a :class:`pandas.DataFrame` against a column spec and returns a
normalised copy; every violation is a :class:`~deformctl.errors.SchemaError` naming the file and
the field.
"""

from __future__ import annotations

import functools
import json
import math
import operator
from collections.abc import Callable
from dataclasses import dataclass
from importlib.resources import files
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from deformctl.artifacts.io import PathArg
from deformctl.errors import SchemaError

if TYPE_CHECKING:  # pragma: no cover - jsonschema loads when a message needs it
    import jsonschema

TABLE_KINDS = ("catalog", "coefficients", "lift_results", "index_table", "predictions")
MESSAGE_SCHEMAS = (
    "squeeze_sample",
    "lift_attempt_sample",
    "lift_attempt_result",
    "rig_request",
    "rig_response",
    "palm_contact",
)
DTYPES = ("string", "float64", "int64", "bool")


@dataclass(frozen=True)
class ColumnSpec:
    """One column of a table spec.

    Attributes:
        name: column name, with its unit in the name (``weight_n``).
        dtype: one of ``string``, ``float64``, ``int64``, ``bool``.
        unit: the unit as text (``"N/cm"``), None for dimensionless or non-numeric columns.
        required: whether every file must have the column.
        description: one sentence for humans (shown by ``inspect``).
        minimum: values must be >= this, when set.
        exclusive_minimum: values must be > this, when set.
        maximum: values must be <= this, when set (physical bounds, e.g. the catalog's).
        unique: no two rows may share a value.
        nullable: missing values (NaN / null) are allowed.
    """

    name: str
    dtype: str
    unit: str | None
    required: bool
    description: str
    minimum: float | None = None
    exclusive_minimum: float | None = None
    maximum: float | None = None
    unique: bool = False
    nullable: bool = False


@dataclass(frozen=True)
class TableSpec:
    """A Parquet table's column spec (``schemas/<name>.columns.json``)."""

    name: str
    version: int
    description: str
    columns: tuple[ColumnSpec, ...]

    def column(self, name: str) -> ColumnSpec | None:
        """The spec of column ``name``, or None when the spec does not list it."""
        for col in self.columns:
            if col.name == name:
                return col
        return None

    @property
    def required(self) -> tuple[str, ...]:
        """Names of the required columns, in spec order."""
        return tuple(c.name for c in self.columns if c.required)

    @property
    def units(self) -> dict[str, str | None]:
        """Column name → unit for every column of the spec."""
        return {c.name: c.unit for c in self.columns}


def _read_schema_file(filename: str) -> Any:
    return json.loads(files("deformctl.schemas").joinpath(filename).read_text(encoding="utf-8"))


@functools.cache
def load_table_spec(kind: str) -> TableSpec:
    """Load ``schemas/<kind>.columns.json``.

    Raises:
        ValueError: ``kind`` is not one of :data:`TABLE_KINDS` (a programming error).
    """
    if kind not in TABLE_KINDS:
        raise ValueError(f"unknown table kind {kind!r}; expected one of {TABLE_KINDS}")
    raw = _read_schema_file(f"{kind}.columns.json")
    cols = []
    for c in raw["columns"]:
        if c["dtype"] not in DTYPES:
            raise ValueError(f"{kind}: column {c['name']} has unknown dtype {c['dtype']}")
        cols.append(
            ColumnSpec(
                name=c["name"],
                dtype=c["dtype"],
                unit=c.get("unit"),
                required=bool(c["required"]),
                description=c.get("description", ""),
                minimum=c.get("minimum"),
                exclusive_minimum=c.get("exclusive_minimum"),
                maximum=c.get("maximum"),
                unique=bool(c.get("unique", False)),
                nullable=bool(c.get("nullable", False)),
            )
        )
    return TableSpec(
        name=raw["name"],
        version=int(raw["version"]),
        description=raw.get("description", ""),
        columns=tuple(cols),
    )


@functools.cache
def load_json_schema(name: str) -> dict[str, Any]:
    """Load ``schemas/<name>.schema.json`` (a JSON Schema, draft 2020-12)."""
    if name not in MESSAGE_SCHEMAS:
        raise ValueError(f"unknown message schema {name!r}; expected one of {MESSAGE_SCHEMAS}")
    schema: dict[str, Any] = _read_schema_file(f"{name}.schema.json")
    return schema


def json_schema_bytes(name: str) -> bytes:
    """The exact bytes of ``schemas/<name>.schema.json`` (embedded in MCAP schema records)."""
    load_json_schema(name)  # validates the name
    return files("deformctl.schemas").joinpath(f"{name}.schema.json").read_bytes()


def schema_version(schema: dict[str, Any]) -> int:
    """The ``x-deformctl.version`` of a JSON Schema (0 when absent)."""
    meta = schema.get("x-deformctl")
    if isinstance(meta, dict) and isinstance(meta.get("version"), int):
        return int(meta["version"])
    return 0


@functools.cache
def json_validator(name: str) -> jsonschema.protocols.Validator:
    """A compiled, cached validator for ``schemas/<name>.schema.json`` (jsonschema is imported
    here: a valid message passes :func:`fast_check` without it)."""
    import jsonschema

    schema = load_json_schema(name)
    cls = jsonschema.validators.validator_for(schema)
    cls.check_schema(schema)
    validator: jsonschema.protocols.Validator = cls(schema)
    return validator


Check = Callable[[Any], bool]
_ANNOTATIONS = {"description", "title", "$schema", "$id", "$comment", "x-unit", "x-deformctl"}


def _is_number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool)


def _is_integer(v: Any) -> bool:
    # JSON Schema counts 1.0 as an integer, so does this check.
    return (isinstance(v, int) and not isinstance(v, bool)) or (
        isinstance(v, float) and v.is_integer()
    )


_TYPE_CHECKS: dict[str, Check] = {
    "object": lambda v: isinstance(v, dict),
    "string": lambda v: isinstance(v, str),
    "number": _is_number,
    "integer": _is_integer,
    "boolean": lambda v: isinstance(v, bool),
    "null": lambda v: v is None,
    "array": lambda v: isinstance(v, list),
}


def _compile(schema: Any) -> Check | None:
    """Compile the small JSON Schema subset deformctl uses into a fast predicate.

    Handles ``type`` (a name or a list), ``properties``, ``required``,
    ``additionalProperties: false``, ``minimum``, ``maximum``, ``exclusiveMinimum``,
    ``minLength``, ``items``, ``minItems``, ``maxItems``, ``dependentRequired`` and ``anyOf``;
    returns None for a schema using anything else, so the caller falls back to
    :mod:`jsonschema`. The predicate answers only "valid or not"; error messages always come
    from :mod:`jsonschema`.
    """
    if not isinstance(schema, dict):
        return None
    known = _ANNOTATIONS | {
        "type",
        "properties",
        "required",
        "additionalProperties",
        "minimum",
        "maximum",
        "exclusiveMinimum",
        "minLength",
        "items",
        "minItems",
        "maxItems",
        "dependentRequired",
        "anyOf",
    }
    if set(schema) - known:
        return None
    checks: list[Check] = []
    typ = schema.get("type")
    if typ is not None:
        names = [typ] if isinstance(typ, str) else list(typ)
        if any(n not in _TYPE_CHECKS for n in names):
            return None
        type_checks = [_TYPE_CHECKS[n] for n in names]
        checks.append(lambda v: any(c(v) for c in type_checks))
    if "minimum" in schema:
        low = schema["minimum"]
        checks.append(lambda v: not _is_number(v) or v >= low)
    if "maximum" in schema:
        high = schema["maximum"]
        checks.append(lambda v: not _is_number(v) or v <= high)
    if "exclusiveMinimum" in schema:
        above = schema["exclusiveMinimum"]
        checks.append(lambda v: not _is_number(v) or v > above)
    if "minLength" in schema:
        n = schema["minLength"]
        checks.append(lambda v: not isinstance(v, str) or len(v) >= n)
    if "minItems" in schema:
        min_items = schema["minItems"]
        checks.append(lambda v: not isinstance(v, list) or len(v) >= min_items)
    if "maxItems" in schema:
        max_items = schema["maxItems"]
        checks.append(lambda v: not isinstance(v, list) or len(v) <= max_items)
    if "items" in schema:
        item_check = _compile(schema["items"])
        if item_check is None:
            return None
        checks.append(lambda v: not isinstance(v, list) or all(item_check(x) for x in v))
    if "anyOf" in schema:
        alternatives = [_compile(sub) for sub in schema["anyOf"]]
        if any(a is None for a in alternatives):
            return None
        checks.append(lambda v: any(a(v) for a in alternatives if a is not None))
    dependent: dict[str, tuple[str, ...]] = {
        k: tuple(deps) for k, deps in schema.get("dependentRequired", {}).items()
    }
    if dependent:
        checks.append(
            lambda v: (
                not isinstance(v, dict)
                or all(d in v for k, deps in dependent.items() if k in v for d in deps)
            )
        )
    props: dict[str, Check] = {}
    for key, sub in schema.get("properties", {}).items():
        compiled = _compile(sub)
        if compiled is None:
            return None
        props[key] = compiled
    required = tuple(schema.get("required", ()))
    additional = schema.get("additionalProperties", True)
    if additional not in (True, False):
        return None
    if props or required or additional is False:

        def check_object(v: Any) -> bool:
            if not isinstance(v, dict):
                return True
            if any(r not in v for r in required):
                return False
            if additional is False and any(k not in props for k in v):
                return False
            return all(c(v[k]) for k, c in props.items() if k in v)

        checks.append(check_object)
    return lambda v: all(c(v) for c in checks)


@functools.cache
def fast_check(name: str) -> Check | None:
    """The compiled predicate of ``schemas/<name>.schema.json`` (None if not compilable)."""
    return _compile(load_json_schema(name))


#: What :func:`message_columns` understands: a flat object of strings, integers and numbers.
_COLUMN_KEYWORDS = _ANNOTATIONS | {"type", "minimum", "maximum", "minLength"}
_COLUMN_TYPES = ("string", "integer", "number")

ColumnPlan = tuple[tuple[tuple[str, str, dict[str, Any]], ...], frozenset[str]]


@functools.cache
def _column_plan(name: str) -> ColumnPlan | None:
    """``(properties as (key, type, subschema), required keys)`` of a flat message schema, or
    None when the schema uses more than :func:`message_columns` checks."""
    schema = load_json_schema(name)
    top = _ANNOTATIONS | {"type", "properties", "required", "additionalProperties"}
    if set(schema) - top or schema.get("type") != "object":
        return None
    if schema.get("additionalProperties") is not False:
        return None
    props = []
    for key, sub in schema.get("properties", {}).items():
        if not isinstance(sub, dict) or set(sub) - _COLUMN_KEYWORDS:
            return None
        if sub.get("type") not in _COLUMN_TYPES:
            return None
        props.append((key, sub["type"], sub))
    required = frozenset(schema.get("required", ()))
    if not required <= {p[0] for p in props}:
        return None
    return tuple(props), required


def message_columns(name: str, messages: list[Any]) -> dict[str, Any] | None:
    """Check many decoded messages against the JSON Schema ``name`` at once; their columns.

    For a flat schema (an object of ``string`` / ``integer`` / ``number`` properties with
    ``minLength``, ``minimum``, ``maximum``, ``required`` and ``additionalProperties: false``,
    as the MCAP sample schemas are) the checks run per column: the Python type of every value,
    then the bounds with numpy. A message they accept is one :func:`validate_message` accepts.

    Returns:
        Key → column when every message is valid: a list of str for a string property, an int64
        array for an integer one, a float64 array for a number (ints converted as
        ``np.fromiter(..., float64)`` does), None for a property no message has, and a
        :class:`numpy.ma.MaskedArray` (masked where absent) for a number property some messages
        have. None when this cannot vouch for every message (a schema it does not understand, a
        string or integer property in some messages only, any invalid message): then
        :func:`validate_message` judges each message and names what is wrong.
    """
    plan = _column_plan(name)
    if plan is None:
        return None
    props, required = plan
    n = len(messages)
    if n and set(map(type, messages)) != {dict}:
        return None
    out: dict[str, Any] = {}
    seen = 0
    for key, typ, sub in props:
        present: np.ndarray | None = None
        try:
            col = list(map(operator.itemgetter(key), messages))
        except KeyError:  # in some messages or none
            if key in required and n:
                return None
            mask = [key in m for m in messages]
            if not any(mask):
                out[key] = None
                continue
            if typ != "number":
                return None
            present = np.array(mask, dtype=bool)
            col = [m[key] for m in messages if key in m]
        seen += len(col)
        types = set(map(type, col))
        values: Any
        if typ == "string":
            if types != {str} or min(map(len, col)) < sub.get("minLength", 0):
                return None
            out[key] = col
            continue
        try:
            if typ == "integer":
                if types != {int}:
                    return None
                values = np.array(col, dtype=np.int64)
            else:
                if not types <= {int, float}:
                    return None
                values = np.array(col, dtype=np.float64)
        except OverflowError:
            return None
        if "minimum" in sub and not np.all(values >= sub["minimum"]):
            return None
        if "maximum" in sub and not np.all(values <= sub["maximum"]):
            return None
        if present is not None:
            full = np.full(n, np.nan)
            full[present] = values
            values = np.ma.MaskedArray(full, mask=~present)
        out[key] = values
    if sum(map(len, messages)) != seen:  # a key the schema does not list
        return None
    return out


def validate_message(
    name: str, message: object, *, path: PathArg | None = None, where: str = ""
) -> None:
    """Check one decoded message against the JSON Schema ``name``.

    A compiled predicate (:func:`fast_check`) accepts valid messages quickly; anything it does
    not accept is judged by :mod:`jsonschema`, which also writes the error message.

    Raises:
        SchemaError: naming the field (JSON path) that does not match.
    """
    check = fast_check(name)
    if check is not None and check(message):
        return
    import jsonschema

    error = jsonschema.exceptions.best_match(json_validator(name).iter_errors(message))
    if error is not None:
        field = ".".join(str(p) for p in error.absolute_path) or None
        prefix = f"{where}: " if where else ""
        raise SchemaError(f"{prefix}{name}: {error.message}", path=path, field=field)


def _row_label(df: pd.DataFrame, i: int) -> str:
    if "object_id" in df.columns:
        oid = df["object_id"].iloc[i]
        if isinstance(oid, str):
            return f"object {oid!r}"
    return f"row {i}"


def _first(mask: np.ndarray) -> int:
    return int(np.flatnonzero(mask)[0])


def _check_column(df: pd.DataFrame, col: ColumnSpec, kind: str, path: PathArg | None) -> pd.Series:
    """Check one present column; return it converted to the spec dtype."""
    s = df[col.name]

    def fail(message: str) -> SchemaError:
        return SchemaError(message, path=path, field=col.name)

    if col.dtype == "float64":
        if pd.api.types.is_bool_dtype(s) or not pd.api.types.is_numeric_dtype(s):
            raise fail(f"expected float64 ({kind} spec), got {s.dtype}")
        values = s.to_numpy(dtype=np.float64, na_value=np.nan)
        nan = np.isnan(values)
        if nan.any() and not col.nullable:
            raise fail(f"{_row_label(df, _first(nan))}: missing value (NaN) in a required column")
        inf = np.isinf(values)
        if inf.any():
            raise fail(f"{_row_label(df, _first(inf))}: value is infinite")
        finite = ~nan
        if col.minimum is not None:
            bad = finite & (values < col.minimum)
            if bad.any():
                i = _first(bad)
                raise fail(
                    f"{_row_label(df, i)}: must be >= {col.minimum:g}, got {float(values[i])!r}"
                )
        if col.exclusive_minimum is not None:
            bad = finite & (values <= col.exclusive_minimum)
            if bad.any():
                i = _first(bad)
                low = col.exclusive_minimum
                raise fail(f"{_row_label(df, i)}: must be > {low:g}, got {float(values[i])!r}")
        if col.maximum is not None:
            bad = finite & (values > col.maximum)
            if bad.any():
                i = _first(bad)
                high = col.maximum
                raise fail(f"{_row_label(df, i)}: must be <= {high:g}, got {float(values[i])!r}")
        out = pd.Series(values, index=s.index, name=col.name)
    elif col.dtype == "int64":
        if pd.api.types.is_bool_dtype(s) or not pd.api.types.is_integer_dtype(s):
            raise fail(f"expected int64 ({kind} spec), got {s.dtype}")
        ints = s.to_numpy(dtype=np.int64)
        if col.minimum is not None and (ints < col.minimum).any():
            i = _first(ints < col.minimum)
            raise fail(f"{_row_label(df, i)}: must be >= {col.minimum:g}, got {ints[i]}")
        out = pd.Series(ints, index=s.index, name=col.name)
    elif col.dtype == "bool":
        native = pd.api.types.is_bool_dtype(s) and not s.isna().any()
        boxed = s.dtype == object and all(isinstance(v, bool | np.bool_) for v in s)
        if native or boxed:
            out = s.astype(bool)
        elif col.nullable and all(isinstance(v, bool | np.bool_) or pd.isna(v) for v in s):
            values = [None if pd.isna(v) else bool(v) for v in s]  # True, False, None
            out = pd.Series(values, index=s.index, name=col.name, dtype=object)
        else:
            raise fail(f"expected bool ({kind} spec), got {s.dtype}")
    else:  # string
        values_obj = s.to_numpy(dtype=object)
        missing = np.array(
            [v is None or (isinstance(v, float) and math.isnan(v)) for v in values_obj]
        )
        wrong = np.array(
            [not (m or isinstance(v, str)) for v, m in zip(values_obj, missing, strict=True)]
        )
        if wrong.any():
            i = _first(wrong)
            raise fail(f"expected string ({kind} spec), got {type(values_obj[i]).__name__}")
        if missing.any() and not col.nullable:
            raise fail(f"row {_first(missing)}: missing value in a required column")
        if col.required and not col.nullable:
            empty = np.array([isinstance(v, str) and v == "" for v in values_obj])
            if empty.any():
                raise fail(f"row {_first(empty)}: empty string in a required column")
        out = pd.Series(
            [None if m else v for v, m in zip(values_obj, missing, strict=True)],
            index=s.index,
            name=col.name,
            dtype=object,
        )
    if col.unique:
        dup = out.duplicated(keep="first") & out.notna()
        if dup.any():
            raise fail(f"duplicate value {out[dup].iloc[0]!r}")
    return out


def validate_frame(df: pd.DataFrame, kind: str, *, path: PathArg | None = None) -> pd.DataFrame:
    """Check ``df`` against the column spec of ``kind`` and return a normalised copy.

    Checks: every required column is present; each spec column has the spec's dtype
    (integers are accepted for float columns); no missing value in a non-nullable column;
    no infinite value; ``minimum`` / ``exclusive_minimum`` / ``maximum`` hold; ``unique``
    columns have no duplicate. Columns the spec does not list are kept unchanged, after the
    spec's columns.

    Args:
        df: the table, one row per record.
        kind: a table kind from :data:`TABLE_KINDS`.
        path: the file the table came from, for error messages.

    Returns:
        A new DataFrame with a fresh ``RangeIndex``, spec columns first (spec order) with dtypes
        float64 / int64 / bool / object(str), then the extra columns.

    Raises:
        SchemaError: naming the file and the offending field.
    """
    spec = load_table_spec(kind)
    names = [str(c) for c in df.columns]
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise SchemaError("column appears twice", path=path, field=dup)
    for name in spec.required:
        if name not in df.columns:
            raise SchemaError(f"required column missing ({kind} spec)", path=path, field=name)
    df = df.reset_index(drop=True)
    out: dict[str, pd.Series] = {}
    for col in spec.columns:
        if col.name in df.columns:
            out[col.name] = _check_column(df, col, kind, path)
    for name in df.columns:
        if name not in out:
            out[str(name)] = df[name]
    return pd.DataFrame(out, index=pd.RangeIndex(len(df)))
