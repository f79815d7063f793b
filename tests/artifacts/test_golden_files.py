"""Golden files: every reader returns, for each tiny artifact in tests/data/, what its
``.expected.json`` says (the habit of mcap's conformance data). ``tests/data/make_golden_files.py``
wrote both; a reader that changes what it returns fails here, naming the file."""

from __future__ import annotations

import importlib.util
import io
import json
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow.parquet as pq
import pytest
from mcap.reader import make_reader
from typer.testing import CliRunner

from deformctl.artifacts import describe, read_catalog, read_table
from deformctl.artifacts.dataset import read_table_any
from deformctl.artifacts.mcap import (
    decode_objects,
    decode_provenance,
    lift_attempts_from_contents,
    load_mcap,
    squeezes_from_contents,
)
from deformctl.artifacts.provenance import Provenance
from deformctl.cli import app

DATA = Path(__file__).resolve().parents[1] / "data"
TABLE_KINDS = ("catalog", "coefficients", "lift_results", "index_table", "predictions")
_spec = importlib.util.spec_from_file_location("make_golden_files", DATA / "make_golden_files.py")
assert _spec is not None
assert _spec.loader is not None
golden = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(golden)


def expected(path: Path) -> dict[str, Any]:
    return json.loads(path.with_name(path.stem + ".expected.json").read_text(encoding="utf-8"))


@pytest.mark.parametrize(("name", "kind"), [("squeeze_2x2", "squeeze_log"), ("lift_2", "lift_log")])
def test_logs_read_the_same_through_every_reader(name: str, kind: str, tmp_path: Path) -> None:
    path = DATA / f"{name}.mcap"
    want = expected(path)
    read = golden.squeeze_expectation if kind == "squeeze_log" else golden.lift_expectation
    assert {**read(path), "provenance": want["provenance"]} == want  # the file reader
    contents = load_mcap(path.read_bytes(), "-")  # the bytes reader (stdin)
    assert decode_objects(contents) == want["objects"]
    assert decode_provenance(contents) == Provenance.from_dict(want["provenance"])
    items = (squeezes_from_contents if kind == "squeeze_log" else lift_attempts_from_contents)(
        contents
    )
    n_items = len(want["squeezes" if kind == "squeeze_log" else "attempts"])
    assert len(items) == n_items
    info = describe(path)  # inspect's reader
    assert (info["kind"], info["objects"]) == (kind, want["objects"])
    with path.open("rb") as fh:  # the mcap library's own reader, as Foxglove reads the file
        messages = list(make_reader(fh).iter_messages())
    assert len(messages) == info["messages"]
    result = CliRunner().invoke(app, ["inspect", str(path), "--json"])
    assert result.exit_code == 0, result.stderr
    assert json.loads(result.stdout)["provenance"] == want["provenance"]


@pytest.mark.parametrize("kind", TABLE_KINDS)
def test_tables_read_the_same_through_every_reader(kind: str) -> None:
    path = DATA / f"{kind}.parquet"
    want = expected(path)
    assert golden.table_expectation(path, kind) == want  # read_table with its kind
    auto = read_table(path)  # the kind from the file
    assert auto.attrs["kind"] == kind
    assert golden.plain(auto.to_dict("records")) == want["rows"]
    if kind != "catalog":
        any_ = read_table_any(str(path), kind)  # the file-or-dataset reader
        assert golden.plain(any_.to_dict("records")) == want["rows"]
    else:
        cat = read_catalog(path)
        assert golden.plain(cat.to_dict("records")) == want["rows"]
    plain = pq.read_table(path)  # a plain Parquet reader sees the same columns and units
    assert plain.column_names == want["columns"]
    units = {f.name: (f.metadata or {}).get(b"unit", b"").decode() for f in plain.schema}
    assert {k: v or "" for k, v in want["units"].items()} == units
    assert len(pd.read_parquet(io.BytesIO(path.read_bytes()))) == len(want["rows"])
    info = describe(path)
    assert (info["kind"], info["rows"]) == (kind, len(want["rows"]))
    assert info["provenance"] == want["provenance"]
