"""deformctl.artifacts.rows: the rows of every table and of a lift log's attempts."""

from __future__ import annotations

import io
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from deformctl.artifacts import read_catalog, read_table, write_lift_log
from deformctl.artifacts.row_options import DEFAULT_ROWS, parse_column_list, parse_row_count
from deformctl.artifacts.rows import artifact_rows, rows_csv, rows_records, select_rows
from deformctl.artifacts.schema import load_table_spec
from deformctl.errors import SchemaError, UsageError
from deformctl.series import LiftAttempt, TrialOutcome

REPO = Path(__file__).resolve().parents[2]
DATA = REPO / "tests" / "data"
TABLES = ["catalog", "coefficients", "lift_results", "index_table", "predictions"]


@pytest.mark.parametrize("kind", TABLES)
def test_every_golden_table_gives_its_rows_with_the_spec_units(kind: str) -> None:
    path = DATA / f"{kind}.parquet"
    rows = artifact_rows(path, None)
    assert rows is not None
    expected = read_catalog(path) if kind == "catalog" else read_table(path, kind)
    assert rows.kind == kind
    assert rows.total == len(expected)
    pd.testing.assert_frame_equal(rows.frame, expected)
    spec = load_table_spec(kind)
    for column in rows.frame.columns:
        col = spec.column(str(column))
        if col is not None:
            assert rows.units[str(column)] == col.unit


def _attempt(oid: str, i: int, force: float, lifted: bool, **details: object) -> LiftAttempt:
    return LiftAttempt(oid, i, TrialOutcome(force, lifted, 1e-4 * (not lifted), None, details))


def test_lift_log_attempts_give_every_attempt_and_the_smallest_lifting_force(
    tmp_path: Path,
) -> None:
    attempts = [
        _attempt("A", 0, 1.0, False, off_table=False),
        _attempt("A", 1, 1.2, True),
        _attempt("A", 2, 1.1, True),  # the bisection's lower force lifted: L_f = 1.1
        _attempt("A", 3, 1.05, False, off_table=True),
        _attempt("B", 0, 2.0, False),  # nothing lifted: no L_f
    ]
    log = tmp_path / "lift.mcap"
    write_lift_log(log, [{"object_id": "A"}, {"object_id": "B"}], attempts, provenance=None)
    rows = artifact_rows(log, None, attempts=True)
    assert rows is not None
    assert rows.kind == "lift_attempts"
    frame = rows.frame
    assert list(frame["object_id"]) == ["A", "A", "A", "A", "B"]
    assert list(frame["attempt_index"]) == [0, 1, 2, 3, 0]
    assert list(frame["grip_force_n"]) == [1.0, 1.2, 1.1, 1.05, 2.0]
    assert list(frame["outcome"]) == ["on table", "lifted", "lifted", "slipped", "slipped"]
    assert list(frame["slip_m"]) == [1e-4, 0.0, 0.0, 1e-4, 1e-4]
    assert list(frame["lift_force_n"][:4]) == [1.1] * 4
    assert math.isnan(frame["lift_force_n"][4])
    assert rows.units["grip_force_n"] == "N"
    assert rows.units["slip_m"] == "m"


def test_attempts_of_a_real_lift_log_match_its_expected_json() -> None:
    rows = artifact_rows(DATA / "lift_2.mcap", None, attempts=True)
    expected = json.loads((DATA / "lift_2.expected.json").read_text())["attempts"]
    assert rows is not None
    assert list(rows.frame["grip_force_n"]) == [a["grip_force_n"] for a in expected]
    assert list(rows.frame["lifted"]) == [a["lifted"] for a in expected]


@pytest.mark.parametrize("name", ["squeeze_2x2.mcap", "lift_results.parquet", "catalog.parquet"])
def test_attempts_of_anything_but_a_lift_log_is_refused(name: str) -> None:
    with pytest.raises(SchemaError, match="not a lift log"):
        artifact_rows(DATA / name, None, attempts=True)


def test_a_log_without_attempts_and_a_squeeze_log_have_no_rows() -> None:
    assert artifact_rows(DATA / "lift_2.mcap", None) is None
    assert artifact_rows(DATA / "squeeze_2x2.mcap", None) is None


def test_csv_and_records_keep_every_digit() -> None:
    rows = artifact_rows(DATA / "lift_results.parquet", None)
    assert rows is not None
    frame = pd.DataFrame(
        {"object_id": ["A", "B"], "x_n": [0.1 + 0.2, math.nan], "ok": [True, False]}
    )
    custom = type(rows)("t", frame, {"object_id": None, "x_n": "N", "ok": None}, 2)
    text = rows_csv(custom)
    assert text.splitlines() == ["object_id,x_n,ok", "A,0.30000000000000004,true", "B,,false"]
    back = pd.read_csv(io.StringIO(rows_csv(rows)))
    for column in rows.frame.columns:
        if pd.api.types.is_float_dtype(rows.frame[column]):
            np.testing.assert_array_equal(back[column].to_numpy(), rows.frame[column].to_numpy())
    records = rows_records(custom)
    assert records == [
        {"object_id": "A", "x_n": 0.30000000000000004, "ok": True},
        {"object_id": "B", "x_n": None, "ok": False},
    ]
    json.dumps(rows_records(rows), allow_nan=False)  # no NaN reaches JSON


def test_select_rows_columns_and_count() -> None:
    rows = artifact_rows(DATA / "lift_results.parquet", None)
    assert rows is not None
    picked = select_rows(rows, ["lift_force_n", "object_id"], 1, "lift.parquet")
    assert list(picked.frame.columns) == ["lift_force_n", "object_id"]
    assert len(picked.frame) == 1
    assert picked.total == rows.total
    assert picked.units == {"lift_force_n": "N", "object_id": None}
    with pytest.raises(UsageError) as err:
        select_rows(rows, ["object_id", "lift_force"], None, "lift.parquet")
    assert "'lift_force'" in str(err.value)
    assert "its columns: object_id, weight_n," in str(err.value)


@pytest.mark.parametrize(
    ("text", "count"), [(None, DEFAULT_ROWS), ("all", None), ("ALL", None), ("1", 1), (" 7 ", 7)]
)
def test_row_counts(text: str | None, count: int | None) -> None:
    assert parse_row_count(text) == count


def test_no_row_count_is_the_default_given() -> None:
    assert parse_row_count(None, default=None) is None  # --json and --csv: every row
    assert parse_row_count("3", default=None) == 3


@pytest.mark.parametrize("text", ["0", "00", "-1", "x", "1.5", "", "1e3"])
def test_bad_row_counts_are_usage_errors(text: str) -> None:
    with pytest.raises(UsageError, match="--rows"):
        parse_row_count(text)


def test_column_lists() -> None:
    assert parse_column_list(None) is None
    assert parse_column_list("a, b,c") == ["a", "b", "c"]
    for bad in ("a,,b", "a,a", ""):
        with pytest.raises(UsageError, match="--columns"):
            parse_column_list(bad)
