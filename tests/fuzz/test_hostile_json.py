"""Untrusted JSON (MCAP samples and metadata, table and model metadata, rig
answers) parsed with depth, size and finite-number limits; beyond them exit 65, naming the file.
"""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from mcap.writer import Writer
from typer.testing import CliRunner

from deformctl import jsonsafe
from deformctl.artifacts.schema import json_schema_bytes
from deformctl.cli import app
from deformctl.lift.runners.rig import parse_rig_response
from tests._helpers.models import _model

runner = CliRunner()
DATA = Path(__file__).parents[1] / "data"
DEEP = "[" * 100_000 + "]" * 100_000
GOOD = {"object_id": "A", "squeeze_index": 0, "time_s": 0.0, "force_n": 1.0, "compression_m": 0.0}
HOSTILE = {
    "deep": DEEP,
    "deep object": '{"a":' * 5_000 + "1" + "}" * 5_000,
    "NaN": "NaN",
    "Infinity": "-Infinity",
    "overflowing float": "1e999",
    "overflowing int": "1" + "0" * 400,
    "huge int": "9" * 5_000,
}


def _one_line(stderr: str) -> str:
    assert stderr.startswith("error: "), stderr
    assert stderr.count("\n") == 1, stderr
    return stderr


@pytest.mark.parametrize("text", list(HOSTILE.values()), ids=list(HOSTILE))
def test_hostile_json_is_a_value_error(text: str) -> None:
    with pytest.raises(ValueError, match=r"nested|constant|float range|digits|Exceeds"):
        jsonsafe.loads(text)


def test_limits_and_the_fast_path() -> None:
    with pytest.raises(ValueError, match="above the limit of 10"):
        jsonsafe.loads(b"[1, 2, 3, 4, 5]", max_bytes=10)
    text = json.dumps({"a": "[" * 100})
    assert jsonsafe.loads(text) == {"a": "[" * 100}  # brackets inside strings do not count
    nested = "[" * 64 + "]" * 64
    assert jsonsafe.loads(nested) is not None
    with pytest.raises(ValueError, match="65 levels"):
        jsonsafe.loads("[" + nested + "]")
    assert jsonsafe.loads("[1e-300, 1e300, 12345678901234567890]") == [
        1e-300,
        1e300,
        12345678901234567890,
    ]


def _raw_log(path: Path, sample: bytes | None = None, object_meta: str | None = None) -> Path:
    """A well-formed squeeze log (CRCs) with one sample message and object record we choose."""
    with path.open("wb") as fh:
        w = Writer(fh, enable_data_crcs=True)
        w.start()
        w.add_metadata("deformctl", {"kind": "squeeze_log", "format_version": "1"})
        if object_meta is not None:
            w.add_metadata("object", {"object_id": '"A"', "weight_n": object_meta})
        sid = w.register_schema(
            "deformctl.SqueezeSample", "jsonschema", json_schema_bytes("squeeze_sample")
        )
        cid = w.register_channel("/squeeze", "json", sid)
        w.add_message(cid, 0, sample if sample is not None else json.dumps(GOOD).encode(), 0)
        w.finish()
    return path


@pytest.mark.parametrize("text", list(HOSTILE.values()), ids=list(HOSTILE))
@pytest.mark.parametrize("where", ["sample", "object"])
@pytest.mark.parametrize("command", ["inspect", "characterize"])
def test_hostile_json_in_a_squeeze_log(text: str, where: str, command: str, tmp_path: Path) -> None:
    if where == "object" and text in ("NaN", "-Infinity"):
        pytest.skip("metadata may hold the NaN / Infinity deformctl's writers put there")
    if where == "sample":
        sample = json.dumps(GOOD).replace('"force_n": 1.0', f'"force_n": {text}').encode()
        log = _raw_log(tmp_path / "s.mcap", sample=sample)
    else:
        log = _raw_log(tmp_path / "s.mcap", object_meta=text)
    out = tmp_path / "c.parquet"
    argv = [command, str(log)] + (["-o", str(out)] if command == "characterize" else [])
    result = runner.invoke(app, argv)
    assert result.exit_code == 65, result.output
    line = _one_line(result.stderr)
    assert "s.mcap" in line
    assert ("/squeeze" if where == "sample" else "object") in line
    assert not out.exists()


@pytest.mark.parametrize("text", [DEEP, '{"kind": "coefficients", "x": 1e999}'])
@pytest.mark.parametrize("command", ["inspect", "table", "predict"])
def test_hostile_json_in_table_metadata(text: str, command: str, tmp_path: Path) -> None:
    table = pq.read_table(DATA / "coefficients.parquet")
    bad = tmp_path / "bad.parquet"
    pq.write_table(table.replace_schema_metadata({"deformctl": text.encode()}), bad)
    argv = {
        "inspect": ["inspect", str(bad)],
        "table": ["table", str(bad), str(DATA / "lift_results.parquet"), "-o", "t.parquet"],
        "predict": ["predict", "m.skops", str(bad)],
    }[command]
    if command == "predict":
        argv[1] = str(_model(tmp_path / "m.skops"))
    result = runner.invoke(app, argv)
    assert result.exit_code == 65, result.output
    line = _one_line(result.stderr)
    assert "bad.parquet" in line
    assert "deformctl" in line


@pytest.mark.parametrize("text", [DEEP, '{"format": "deformctl-lift-force-model/1", "x": 1e999}'])
@pytest.mark.parametrize("command", ["inspect", "predict"])
def test_hostile_json_in_model_metadata(text: str, command: str, tmp_path: Path) -> None:
    model = _model(tmp_path / "m.skops", metadata_json=text)
    argv = [command, str(model)] + (
        [str(DATA / "index_table.parquet")] if command == "predict" else []
    )
    result = runner.invoke(app, argv)
    assert result.exit_code == 65, result.output
    line = _one_line(result.stderr)
    assert "m.skops" in line
    assert "metadata" in line


@pytest.mark.parametrize("text", list(HOSTILE.values()), ids=list(HOSTILE))
def test_hostile_json_in_a_rig_answer(text: str) -> None:
    with pytest.raises(ValueError, match="not valid JSON"):
        parse_rig_response('{"lifted": true, "slip_m": ' + text + "}")


def test_a_deep_pa_table_metadata_is_not_a_recursion(tmp_path: Path) -> None:
    bad = tmp_path / "bad.parquet"
    pq.write_table(pa.table({"x": [1.0]}).replace_schema_metadata({"deformctl": DEEP}), bad)
    result = runner.invoke(app, ["inspect", str(bad)])
    assert result.exit_code == 65
    assert "nested" in _one_line(result.stderr)
