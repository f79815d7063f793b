"""``deformctl inspect`` rows: the text table, --rows, --columns, --json, --csv, --attempts."""

from __future__ import annotations

import io
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_table
from deformctl.artifacts.dataset import read_dataset
from deformctl.cli import app
from deformctl.population import make_population

REPO = Path(__file__).resolve().parents[2]
DATA = REPO / "tests" / "data"
runner = CliRunner()


def _run(*args: object, columns: int | None = None) -> object:
    env = {"COLUMNS": str(columns)} if columns else {"COLUMNS": ""}
    return runner.invoke(app, ["inspect", *map(str, args)], env=env)


def _ok(result: object) -> str:
    assert result.exit_code == 0, result.stderr  # type: ignore[attr-defined]
    return result.stdout  # type: ignore[attr-defined,no-any-return]


def test_plain_inspect_of_a_table_shows_the_summary_then_rows_with_units() -> None:
    out = _ok(_run(DATA / "lift_results.parquet"))
    assert "kind: lift_results" in out
    table = out.split("rows (first ")[1].splitlines()
    header = table[1]
    assert header.split()[:3] == ["object_id", "weight_n", "[N]"]
    assert "lift_force_n [N]" in header
    expected = read_table(DATA / "lift_results.parquet", "lift_results")
    body = table[2 : 2 + len(expected)]
    assert [line.split()[0] for line in body] == list(expected["object_id"])
    assert f"{expected['lift_force_n'][0]:.6g}" in body[0]


def test_rows_alone_with_columns_and_count() -> None:
    out = _ok(_run(DATA / "catalog.parquet", "--rows", "1", "--columns", "weight_n,object_id"))
    lines = out.splitlines()
    assert lines[0].split() == ["weight_n", "[N]", "object_id"]
    assert len(lines) == 2  # the header and one row; no summary
    result = _run(DATA / "catalog.parquet", "--rows", "1")
    assert "rows shown" in result.stderr  # type: ignore[attr-defined]


def test_a_narrow_terminal_cuts_long_text_and_splits_the_columns() -> None:
    out = _ok(_run(DATA / "lift_results.parquet", "--rows", "all", columns=60))
    lines = out.splitlines()
    assert all(len(line) <= 60 for line in lines), max(lines, key=len)
    blocks = out.split("\n\n")
    assert len(blocks) > 1
    assert all(block.startswith("object_id") for block in blocks)
    wide = _ok(_run(DATA / "lift_results.parquet", "--rows", "all"))  # a pipe: one block
    assert "\n\n" not in wide.strip()


def test_long_text_is_cut_with_an_ellipsis(tmp_path: Path) -> None:
    catalog = make_population(2, seed=0)
    catalog["name"] = "a very long object name " * 10
    path = tmp_path / "cat.csv"
    catalog.to_csv(path, index=False)
    out = _ok(_run(path, "--columns", "object_id,name", columns=50))
    assert all(len(line) <= 50 for line in out.splitlines())
    assert "…" in out
    csv = _ok(_run(path, "--columns", "name", "--csv"))
    assert "a very long object name " * 9 in csv  # --csv keeps the whole text


def test_json_records_and_csv_keep_full_precision() -> None:
    expected = read_table(DATA / "lift_results.parquet", "lift_results")
    info = json.loads(_ok(_run(DATA / "lift_results.parquet", "--json", "--rows", "all")))
    assert info["records_total"] == len(expected)
    got = [r["lift_force_n"] for r in info["records"]]
    want = [None if math.isnan(v) else v for v in expected["lift_force_n"]]
    assert got == want  # NaN is null
    csv = _ok(_run(DATA / "lift_results.parquet", "--csv", "--rows", "all"))
    back = pd.read_csv(io.StringIO(csv))
    for column in ("lift_force_n", "f_w_n", "weight_n"):
        np.testing.assert_array_equal(back[column].to_numpy(), expected[column].to_numpy())
    assert list(back.columns) == list(expected.columns)


def test_attempts_of_a_lift_log() -> None:
    out = _ok(_run(DATA / "lift_2.mcap", "--attempts"))
    header = out.splitlines()[0]
    for column in ("grip_force_n [N]", "lifted", "outcome", "slip_m [m]", "lift_force_n [N]"):
        assert column in header
    assert "A: L_f = 0.84 N" in out
    csv = _ok(_run(DATA / "lift_2.mcap", "--attempts", "--csv"))
    assert csv.splitlines()[1].startswith("A,0,0.7,false,slipped,0.0125,0.84")


def test_a_dataset_directory_shows_its_rows(tmp_path: Path) -> None:
    catalog = tmp_path / "cat.csv"
    make_population(2, seed=1).to_csv(catalog, index=False)
    fast = ["--alpha-cm", "10", "--dt-s", "0.002", "--hold-s", "0.05", "--lift-height-m", "0.01"]
    args = ["lift", "sim", str(catalog), "--protocol", "paper", "--workers", "1", *fast]
    done = runner.invoke(app, [*args, "-o", f"{tmp_path / 'lift'}/"])
    assert done.exit_code == 0, done.stderr
    out = _ok(_run(tmp_path / "lift", "--columns", "object_id,lift_force_n"))
    rows = read_dataset(tmp_path / "lift")
    lines = out.splitlines()
    assert lines[0].split() == ["object_id", "lift_force_n", "[N]"]
    assert [line.split()[0] for line in lines[1:]] == list(rows["object_id"])


@pytest.mark.parametrize(
    ("args", "code", "text"),
    [
        (["catalog.parquet", "--rows", "-2"], 2, "--rows must be a whole number"),
        (["catalog.parquet", "--rows", "ten"], 2, "--rows must be a whole number"),
        (["catalog.parquet", "--columns", "object_id,weight"], 2, "its columns: object_id,"),
        (["catalog.parquet", "--json", "--csv"], 2, "not both"),
        (["squeeze_2x2.mcap", "--attempts"], 65, "not a lift log"),
        (["lift_results.parquet", "--attempts"], 65, "not a lift log"),
        (["squeeze_2x2.mcap", "--rows", "3"], 2, "has no rows"),
        (["lift_2.mcap", "--csv"], 2, "--attempts"),
    ],
)
def test_bad_input_is_one_line_and_prints_nothing(args: list[str], code: int, text: str) -> None:
    result = _run(DATA / args[0], *args[1:])
    assert result.exit_code == code, result.stderr  # type: ignore[attr-defined]
    err = result.stderr.strip()  # type: ignore[attr-defined]
    assert err.startswith("error: "), err
    assert "\n" not in err, err
    assert text in err
    assert result.stdout == ""  # type: ignore[attr-defined]
