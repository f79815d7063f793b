"""Machine-readable outputs: ``inspect --json``/``--csv`` print every row unless ``--rows N``;
``predict --json`` has the same columns in every mode; both documents follow their JSON Schemas
in ``schemas/`` (read from this checkout by path)."""

from __future__ import annotations

import io
import json
from pathlib import Path

import jsonschema
import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.artifacts.row_options import DEFAULT_ROWS
from deformctl.cli import app
from deformctl.population import make_population
from deformctl.predict import load_predictor, predict_objects

REPO = Path(__file__).resolve().parents[2]
DATA = REPO / "tests" / "data"
SCHEMAS = REPO / "schemas"
runner = CliRunner()
ONE = ["--weight-n", "2.9", "--deformability-n-per-cm", "30", "--damping-ns-per-cm", "0.47",
       "--friction-mu", "0.5"]  # fmt: skip


def _validator(name: str) -> jsonschema.Draft202012Validator:
    schema = json.loads((SCHEMAS / f"{name}.schema.json").read_text(encoding="utf-8"))
    jsonschema.Draft202012Validator.check_schema(schema)
    assert schema["x-deformctl"]["name"] == name
    return jsonschema.Draft202012Validator(schema)


def _ok(*args: object) -> str:
    result = runner.invoke(app, [str(a) for a in args], env={"COLUMNS": ""})
    assert result.exit_code == 0, result.stderr
    return result.stdout


@pytest.fixture(scope="module")
def big_catalog(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A catalog with more rows than the text table shows."""
    path = tmp_path_factory.mktemp("big") / "objects.csv"
    make_population(DEFAULT_ROWS + 7, seed=3).to_csv(path, index=False)
    return path


def test_csv_and_json_print_every_row_unless_rows_is_given(big_catalog: Path) -> None:
    n = DEFAULT_ROWS + 7
    table = pd.read_csv(big_catalog)
    csv = pd.read_csv(io.StringIO(_ok("inspect", big_catalog, "--csv")))
    assert list(csv["object_id"]) == list(table["object_id"])  # all 27, in file order
    info = json.loads(_ok("inspect", big_catalog, "--json"))
    assert [r["object_id"] for r in info["records"]] == list(table["object_id"])
    assert info["records_total"] == n
    _validator("inspect").validate(info)
    three = json.loads(_ok("inspect", big_catalog, "--json", "--rows", "3"))
    assert [r["object_id"] for r in three["records"]] == list(table["object_id"][:3])
    assert three["records_total"] == n
    assert len(pd.read_csv(io.StringIO(_ok("inspect", big_catalog, "--csv", "--rows", "3")))) == 3
    text = _ok("inspect", big_catalog)  # the text table still stops at DEFAULT_ROWS
    assert f"rows (first {DEFAULT_ROWS} of {n}):" in text


def test_csv_and_json_of_every_artifact_kind_follow_the_schema() -> None:
    validator = _validator("inspect")
    tables = ("catalog", "coefficients", "lift_results", "index_table", "predictions")
    logs = ("squeeze_2x2.mcap", "lift_2.mcap")
    for name in [f"{t}.parquet" for t in tables] + list(logs):
        info = json.loads(_ok("inspect", DATA / name, "--json"))
        validator.validate(info)
        if name.endswith(".parquet"):
            assert info["records_total"] == len(info["records"]) == info["rows"], name


@pytest.mark.parametrize("rows", ["0", "-1", "-20", "2.5", "some"])
@pytest.mark.parametrize("mode", [[], ["--json"], ["--csv"]])
def test_a_row_count_below_one_is_one_usage_line(rows: str, mode: list[str]) -> None:
    result = runner.invoke(app, ["inspect", str(DATA / "catalog.parquet"), *mode, "--rows", rows])
    assert result.exit_code == 2, result.stderr
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, lines
    assert lines[0].startswith("error:")
    assert "--rows must be a whole number >= 1" in lines[0]


def _predict_json(*args: object) -> dict:  # type: ignore[type-arg]
    doc = json.loads(_ok("predict", "grip", *args, "--json"))
    _validator("predict").validate(doc)
    return doc  # type: ignore[no-any-return]


def test_predict_json_has_the_same_columns_in_every_mode(tmp_path: Path) -> None:
    one = _predict_json(*ONE)
    pd.DataFrame(
        {
            "object_id": ["a", "b"],
            "weight_n": [2.9, 6.0],
            "deformability_n_per_cm": [30.0, 12.0],
            "damping_ns_per_cm": [0.47, 2.0],
            "friction_mu": [0.5, 0.7],
        }
    ).to_parquet(tmp_path / "in.parquet")
    many = _predict_json(tmp_path / "in.parquet", "--coverage", "0.9")
    contract = json.loads((SCHEMAS / "predictions.columns.json").read_text(encoding="utf-8"))
    names = [c["name"] for c in contract["columns"]]
    assert list(one["records"][0]) == list(many["records"][0]) == names
    assert list(one["units"]) == names
    assert one["units"]["predicted_lift_force_n"] == "N"
    # what one mode lacks is null, not left out; the flags no row raised are false
    assert one["records"][0]["object_id"] is None
    assert one["records"][0]["lift_force_upper_n"] is None
    assert one["records"][0]["damping_assumed"] is False
    assert [r["object_id"] for r in many["records"]] == ["a", "b"]
    assert all(r["bound_guaranteed"] is not None for r in many["records"])


def test_predict_json_numbers_are_the_library_s_at_full_precision() -> None:
    doc = _predict_json(*ONE, "--coverage", "0.9")
    est = predict_objects(
        load_predictor("grip"),
        {
            "weight_n": [2.9],
            "deformability_n_per_cm": [30.0],
            "damping_ns_per_cm": [0.47],
            "friction_mu": [0.5],
        },
        coverage=0.9,
    )
    rec = doc["records"][0]
    assert rec["predicted_lift_force_n"] == float(est.lift_force_n[0])
    assert rec["lift_force_upper_n"] == float(est.lift_force_upper_n[0])
    assert rec["f_w_n"] == pytest.approx(2.9 / (2 * 0.5), rel=1e-12)  # F_w = W / (2 μ)
    assert rec["coverage"] == 0.9


def test_predict_json_with_an_output_file_is_one_usage_line(tmp_path: Path) -> None:
    out = tmp_path / "p.parquet"
    result = runner.invoke(app, ["predict", "grip", *ONE, "--json", "-o", str(out)])
    assert result.exit_code == 2
    assert result.stderr.strip().count("\n") == 0
    assert result.stderr.startswith("error:")
    assert not out.exists()


def test_inspect_grip_describes_the_bundled_model(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)  # no file named grip here: the name is the bundled model
    info = json.loads(_ok("inspect", "grip", "--json"))
    assert info["kind"] == "model"
    assert Path(info["path"]).name == "grip.skops"
    lo, hi = info["training_range"]["weight_n"]
    assert 0 < lo < hi
    text = _ok("inspect", "grip")
    assert "kind: model" in text
    assert "training range:" in text
    bad = runner.invoke(app, ["inspect", "./grip"])  # a path is a path
    assert bad.exit_code == 66
    assert bad.stderr.startswith("error:")
