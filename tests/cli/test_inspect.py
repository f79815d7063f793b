"""``deformctl inspect``: every artifact kind, text and JSON, and its error lines."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import Provenance, write_squeeze_log, write_table
from deformctl.cli import app
from deformctl.series import SqueezeSeries

runner = CliRunner()
REPO = Path(__file__).resolve().parents[2]
PAPER = REPO / "datasets" / "paper"
HEADER = "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu\n"


def _prov() -> Provenance:
    return Provenance.from_invocation(
        [PAPER / "objects.csv"], seed=11, settings={"dt_s": 0.001}, argv=["deformctl", "measure"]
    )


def test_paper_catalog_json_describes_the_four_objects() -> None:
    result = runner.invoke(app, ["inspect", str(PAPER / "objects.csv"), "--json"])
    assert result.exit_code == 0, result.stderr
    info = json.loads(result.stdout)
    assert info["kind"] == "catalog"
    assert info["format"] == "csv"
    assert info["schema"] == {"name": "catalog", "version": 1}
    assert info["rows"] == 4
    objects = {o["object_id"]: o for o in info["objects"]}
    assert sorted(objects) == ["A", "B", "C", "D"]
    # Table I weights and sizes, Table II D and λ (paper units).
    assert [objects[k]["weight_n"] for k in "ABCD"] == [0.7, 1.4, 2.9, 4.9]
    assert [objects[k]["interior"] for k in "ABCD"] == ["sponge", "cotton", "sand", "water"]
    assert objects["A"]["size_x_cm"] == 17.8
    assert objects["C"]["material_stiffness_n_per_cm"] == 30.02
    assert objects["D"]["material_damping_ns_per_cm"] == 0.0
    units = {c["name"]: c["unit"] for c in info["columns"]}
    assert units["weight_n"] == "N"
    assert units["material_damping_ns_per_cm"] == "N·s/cm"
    assert info["provenance"] is None


def test_paper_catalog_text() -> None:
    result = runner.invoke(app, ["inspect", str(PAPER / "objects.csv")])
    assert result.exit_code == 0
    assert "kind: catalog" in result.stdout
    assert "objects (4): A, B, C, D" in result.stdout


def test_squeeze_log(tmp_path: Path) -> None:
    path = tmp_path / "squeeze.mcap"
    t = np.array([0.0, 0.5, 1.0])
    squeezes = [SqueezeSeries("A", i, t, 2 * t, 0.01 * t) for i in range(3)]
    write_squeeze_log(path, [{"object_id": "A", "weight_n": 0.7}], squeezes, provenance=_prov())
    result = runner.invoke(app, ["inspect", str(path), "--json"])
    assert result.exit_code == 0, result.stderr
    info = json.loads(result.stdout)
    assert info["kind"] == "squeeze_log"
    assert info["messages"] == 9
    assert info["squeezes"] == 3
    (channel,) = info["channels"]
    assert channel["topic"] == "/squeeze/A"
    assert channel["messages"] == 9
    assert channel["schema"] == "deformctl.SqueezeSample"
    fields = {f["name"]: f["unit"] for f in channel["fields"]}
    assert fields["force_n"] == "N"
    assert fields["compression_m"] == "m"
    # Three 1 s squeezes with 1 s gaps, from 2000-01-01: 0 .. 5 s.
    epoch = 946_684_800_000_000_000
    assert info["time_range"] == {
        "start_ns": epoch,
        "end_ns": epoch + 5_000_000_000,
        "duration_s": 5.0,
    }
    assert info["provenance"]["seed"] == 11
    text = runner.invoke(app, ["inspect", str(path)]).stdout
    assert "/squeeze/A: 9 messages" in text
    assert "time range: 2000-01-01T00:00:00.000000000Z .. 2000-01-01T00:00:05.000000000Z" in text


def test_parquet_table_and_stdin(tmp_path: Path) -> None:
    path = tmp_path / "coef.parquet"
    df = pd.DataFrame(
        {"object_id": ["A"], "deformability_n_per_cm": [49.18], "damping_ns_per_cm": [6.47]}
    )
    write_table(df, path, "coefficients", provenance=_prov())
    result = runner.invoke(app, ["inspect", "-", "--json"], input=path.read_bytes())
    assert result.exit_code == 0, result.stderr
    info = json.loads(result.stdout)
    assert info["path"] == "<stdin>"
    assert info["kind"] == "coefficients"
    assert info["rows"] == 1
    units = {c["name"]: c["unit"] for c in info["columns"]}
    assert units == {
        "object_id": None,
        "deformability_n_per_cm": "N/cm",
        "damping_ns_per_cm": "N·s/cm",
    }
    assert info["provenance"]["command_line"] == ["deformctl", "measure"]


def _assert_error(args: list[str], code: int, message: str) -> None:
    result = runner.invoke(app, ["inspect", *args])
    assert result.exit_code == code
    assert result.stdout == ""
    assert result.stderr.count("\n") == 1
    assert result.stderr.startswith(f"error: {message}"), result.stderr


def test_missing_input_is_66(tmp_path: Path) -> None:
    missing = tmp_path / "nope.mcap"
    _assert_error([str(missing)], 66, f"{missing}: no such file")


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        ("objects.csv", HEADER + "A,1,1,1,nan,0.5\n", "field 'weight_n': object 'A': missing"),
        (
            "objects.csv",
            HEADER + "A,1,1,1,-1,0.5\n",
            "field 'weight_n': object 'A': must be >= 0.001",
        ),
        ("objects.csv", HEADER, "empty catalog"),
        ("objects.csv", HEADER + "A,1,1,1,1,0.5\nA,1,1,1,1,0.5\n", "field 'object_id': duplicate"),
        ("x.mcap", "hello", "not a deformctl artifact"),
        ("x.mcap", "\x89MCAP0\r\n" + "x" * 40, "truncated or damaged MCAP"),
    ],
)
def test_bad_inputs_are_65(tmp_path: Path, name: str, content: str, message: str) -> None:
    path = tmp_path / name
    path.write_bytes(content.encode("latin-1"))
    _assert_error([str(path)], 65, f"{path}: {message}")


def test_mcap_truncated_or_flipped_is_65(tmp_path: Path) -> None:
    path = tmp_path / "squeeze.mcap"
    t = np.array([0.0, 0.5])
    write_squeeze_log(path, [], [SqueezeSeries("A", 0, t, t, t)], provenance=None)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    _assert_error([str(path)], 65, f"{path}: truncated or damaged MCAP file")
    flipped = bytearray(data)
    flipped[len(data) // 3] ^= 0x01
    path.write_bytes(bytes(flipped))
    _assert_error([str(path)], 65, f"{path}: damaged MCAP file")


def test_parquet_missing_column_and_wrong_dtype_are_65(tmp_path: Path) -> None:
    path = tmp_path / "t.parquet"
    pq.write_table(pa.table({"object_id": ["A"], "deformability_n_per_cm": [1.0]}), path)
    _assert_error([str(path)], 65, f"{path}: columns match no deformctl table spec")
    pq.write_table(
        pa.table({"object_id": ["A"], "deformability_n_per_cm": [1], "damping_ns_per_cm": ["x"]}),
        path,
    )
    _assert_error([str(path)], 65, f"{path}: field 'damping_ns_per_cm': expected float64")


def test_other_paper_tables_are_not_artifacts() -> None:
    path = PAPER / "table2.csv"
    _assert_error([str(path)], 65, f"{path}: not a deformctl artifact")
