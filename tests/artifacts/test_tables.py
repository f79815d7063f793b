"""Parquet tables and the catalog: round trips, validation errors, atomic writes."""

from __future__ import annotations

import io
import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from deformctl.artifacts import (
    TABLE_KINDS,
    load_table_spec,
    read_catalog,
    read_table,
    write_catalog,
    write_table,
)
from deformctl.errors import (
    EXIT_DATAERR,
    EXIT_FAILURE,
    EXIT_NOINPUT,
    InputDataError,
    MissingInputError,
    OutputExistsError,
    SchemaError,
)
from tests._helpers.builders import PAPER_OBJECTS, make_provenance, make_tables

CATALOG_HEADER = "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu\n"


def _files(directory: Path) -> list[str]:
    return sorted(p.name for p in directory.iterdir())


@pytest.mark.parametrize("kind", TABLE_KINDS)
def test_round_trip_every_table_kind(tmp_path: Path, kind: str) -> None:
    df = make_tables()[kind]
    prov = make_provenance()
    out = tmp_path / f"{kind}.parquet"
    written = write_table(df, out, kind, provenance=prov)
    back = read_table(out, kind)
    pd.testing.assert_frame_equal(back, written)
    assert back.attrs["provenance"] == prov
    assert back.attrs["kind"] == kind
    spec = load_table_spec(kind)
    for col in spec.columns:
        if col.name in back.columns:
            assert back.attrs["units"][col.name] == col.unit
    # Values survive exactly, checked against the input frame column by column.
    for name in df.columns:
        if pd.api.types.is_float_dtype(df[name]):
            np.testing.assert_array_equal(back[name].to_numpy(), df[name].to_numpy())
        else:  # missing strings come back as None
            assert list(back[name]) == [None if pd.isna(v) else v for v in df[name]]
    # Units are in the file itself, independently of our reader.
    schema = pq.read_schema(out)
    for col in spec.columns:
        if col.name in schema.names:
            assert schema.field(col.name).metadata[b"unit"].decode() == (col.unit or "")
    meta = json.loads(schema.metadata[b"deformctl"])
    assert meta["kind"] == kind
    assert meta["schema_version"] == spec.version
    assert meta["provenance"]["seed"] == 7
    # kind=None reads the kind from the file.
    assert read_table(out).attrs["kind"] == kind


def test_catalog_csv_and_parquet_round_trip(tmp_path: Path) -> None:
    cat = read_catalog(PAPER_OBJECTS)
    assert list(cat["object_id"]) == ["A", "B", "C", "D"]
    assert cat["weight_n"].tolist() == [0.7, 1.4, 2.9, 4.9]
    write_catalog(cat, tmp_path / "c.csv")
    write_catalog(cat, tmp_path / "c.parquet", provenance=make_provenance())
    pd.testing.assert_frame_equal(read_catalog(tmp_path / "c.csv"), cat)
    back = read_catalog(tmp_path / "c.parquet")
    pd.testing.assert_frame_equal(back, cat)
    assert back.attrs["provenance"] == make_provenance()


def test_stdout_and_stdin(tmp_path: Path, capsysbinary: pytest.CaptureFixture[bytes]) -> None:
    df = make_tables()["coefficients"]
    write_table(df, "-", "coefficients", provenance=make_provenance())
    data = capsysbinary.readouterr().out
    assert data[:4] == b"PAR1"
    assert data[-4:] == b"PAR1"
    assert _files(tmp_path) == []
    old = sys.stdin
    sys.stdin = io.TextIOWrapper(io.BytesIO(data))
    try:
        back = read_table("-", "coefficients")
    finally:
        sys.stdin = old
    assert back["deformability_n_per_cm"].tolist() == [49.18, 13.03]


def _raw_parquet(path: Path, columns: dict[str, list[object]]) -> None:
    """A Parquet file written by plain pyarrow (no deformctl metadata), like a foreign tool."""
    pq.write_table(pa.table(columns), path)


def test_missing_required_column(tmp_path: Path) -> None:
    bad = tmp_path / "coef.parquet"
    _raw_parquet(bad, {"object_id": ["A"], "deformability_n_per_cm": [1.0]})
    with pytest.raises(SchemaError) as info:
        read_table(bad, "coefficients")
    assert info.value.exit_code == EXIT_DATAERR
    assert str(info.value) == (
        f"{bad}: field 'damping_ns_per_cm': required column missing (coefficients spec)"
    )


def test_wrong_dtype(tmp_path: Path) -> None:
    bad = tmp_path / "coef.parquet"
    _raw_parquet(
        bad,
        {"object_id": ["A"], "deformability_n_per_cm": ["49.18"], "damping_ns_per_cm": [1.0]},
    )
    with pytest.raises(SchemaError, match="field 'deformability_n_per_cm': expected float64"):
        read_table(bad, "coefficients")


def test_foreign_table_with_matching_columns_is_accepted(tmp_path: Path) -> None:
    ok = tmp_path / "coef.parquet"
    _raw_parquet(
        ok, {"object_id": ["A"], "deformability_n_per_cm": [3], "damping_ns_per_cm": [1.5]}
    )
    df = read_table(ok, "coefficients")
    assert df["deformability_n_per_cm"].dtype == np.float64
    assert df.attrs["provenance"] is None


def test_kind_mismatch(tmp_path: Path) -> None:
    out = tmp_path / "coef.parquet"
    write_table(make_tables()["coefficients"], out, "coefficients", provenance=None)
    with pytest.raises(SchemaError, match="is a coefficients table, expected lift_results"):
        read_table(out, "lift_results")


def test_edited_metadata_is_detected(tmp_path: Path) -> None:
    out = tmp_path / "coef.parquet"
    write_table(make_tables()["coefficients"], out, "coefficients", provenance=make_provenance())
    table = pq.read_table(out)
    meta = json.loads(table.schema.metadata[b"deformctl"])
    meta["provenance"]["seed"] = 8
    pq.write_table(table.replace_schema_metadata({b"deformctl": json.dumps(meta).encode()}), out)
    with pytest.raises(SchemaError, match="content checksum mismatch"):
        read_table(out)


@pytest.mark.parametrize(
    ("row", "message"),
    [
        ("A,1,1,1,,0.5", "field 'weight_n': object 'A': missing value (NaN) in a required column"),
        ("A,1,1,1,-0.7,0.5", "field 'weight_n': object 'A': must be >= 0.001, got -0.7"),
        ("A,1,1,1,0.7,-0.5", "field 'friction_mu': object 'A': must be >= 0.01, got -0.5"),
        ("A,1,1,1,heavy,0.5", "field 'weight_n': expected float64"),
        ("A,1,1,1,0.7,0.5\nA,2,2,2,1.0,0.5", "field 'object_id': duplicate value 'A'"),
    ],
)
def test_bad_catalog(tmp_path: Path, row: str, message: str) -> None:
    bad = tmp_path / "objects.csv"
    bad.write_text(CATALOG_HEADER + row + "\n")
    with pytest.raises(SchemaError) as info:
        read_catalog(bad)
    assert info.value.exit_code == EXIT_DATAERR
    assert str(info.value).startswith(f"{bad}: {message}")
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("content", ["", CATALOG_HEADER])
def test_empty_catalog(tmp_path: Path, content: str) -> None:
    bad = tmp_path / "objects.csv"
    bad.write_text(content)
    with pytest.raises(InputDataError, match="empty catalog") as info:
        read_catalog(bad)
    assert info.value.exit_code == EXIT_DATAERR


def test_missing_input(tmp_path: Path) -> None:
    with pytest.raises(MissingInputError) as info:
        read_catalog(tmp_path / "nope.csv")
    assert info.value.exit_code == EXIT_NOINPUT
    assert str(info.value) == f"{tmp_path / 'nope.csv'}: no such file"
    with pytest.raises(MissingInputError):
        read_table(tmp_path / "nope.parquet", "coefficients")


def test_existing_output_without_force(tmp_path: Path) -> None:
    out = tmp_path / "coef.parquet"
    out.write_bytes(b"precious")
    df = make_tables()["coefficients"]
    with pytest.raises(OutputExistsError) as info:
        write_table(df, out, "coefficients", provenance=None)
    assert info.value.exit_code == EXIT_FAILURE
    assert str(info.value) == f"{out}: exists already, not overwriting (use --force)"
    assert out.read_bytes() == b"precious"
    assert _files(tmp_path) == ["coef.parquet"]
    write_table(df, out, "coefficients", provenance=None, force=True)
    assert read_table(out, "coefficients")["object_id"].tolist() == ["A", "B"]
    assert _files(tmp_path) == ["coef.parquet"]


def test_invalid_frame_writes_nothing(tmp_path: Path) -> None:
    df = make_tables()["index_table"].drop(columns=["lift_force_n"])
    with pytest.raises(SchemaError, match="'lift_force_n': required column missing"):
        write_table(df, tmp_path / "index.parquet", "index_table", provenance=None)
    assert _files(tmp_path) == []
