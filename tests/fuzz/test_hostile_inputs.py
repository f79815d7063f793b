"""Silent acceptance closed. Duplicate catalog headers are refused; every log a
command reads must say (in its ``deformctl`` record) that it is the kind the command expects.
"""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from mcap.writer import Writer
from typer.testing import CliRunner

from deformctl.artifacts.schema import json_schema_bytes
from deformctl.cli import app

runner = CliRunner()
HEADER = "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu"
ROW = "A,10,10,10,1.0,0.5"
SIM = ",material_stiffness_n_per_cm,material_damping_ns_per_cm"


def _one_line(stderr: str) -> str:
    assert stderr.startswith("error: "), stderr
    assert stderr.count("\n") == 1, stderr
    return stderr


@pytest.mark.parametrize(
    ("extra_header", "extra_value", "twice"),
    [
        (",weight_n", ",5.0", "weight_n"),
        (",object_id", ",B", "object_id"),
        (", weight_n", ",5", "weight_n"),
    ],
)
@pytest.mark.parametrize("command", ["inspect", "measure", "lift"])
def test_a_column_named_twice_is_refused(
    extra_header: str, extra_value: str, twice: str, command: str, tmp_path: Path
) -> None:
    cat = tmp_path / "cat.csv"
    cat.write_text(f"{HEADER}{SIM}{extra_header}\n{ROW},10,1{extra_value}\n")
    out = tmp_path / ("x.mcap" if command == "measure" else "l.parquet")
    argv = (
        [command, str(cat)] if command == "inspect" else [command, "sim", str(cat), "-o", str(out)]
    )
    result = runner.invoke(app, argv)
    assert result.exit_code == 65, result.output
    line = _one_line(result.stderr)
    assert "cat.csv" in line
    assert f"'{twice}'" in line
    assert "twice" in line
    assert not out.exists()


def test_a_parquet_catalog_with_a_column_twice_is_refused(tmp_path: Path) -> None:
    names = [*HEADER.split(","), "weight_n"]
    values = ["A", 10.0, 10.0, 10.0, 1.0, 0.5, 5.0]
    table = pa.Table.from_arrays([pa.array([v]) for v in values], names=names)
    path = tmp_path / "cat.parquet"
    pq.write_table(table, path)
    result = runner.invoke(app, ["inspect", str(path)])
    assert result.exit_code == 65, result.output
    assert "'weight_n'" in _one_line(result.stderr)


GOOD = {"object_id": "A", "squeeze_index": 0, "time_s": 0.0, "force_n": 1.0, "compression_m": 0.0}


def _log(path: Path, record: dict[str, str] | None, *, crcs: bool = True) -> Path:
    with path.open("wb") as fh:
        w = Writer(fh, enable_data_crcs=crcs, enable_crcs=crcs)
        w.start()
        if record is not None:
            w.add_metadata("deformctl", record)
        sid = w.register_schema(
            "deformctl.SqueezeSample", "jsonschema", json_schema_bytes("squeeze_sample")
        )
        cid = w.register_channel("/squeeze", "json", sid)
        for i in range(20):
            w.add_message(cid, i, json.dumps({**GOOD, "time_s": i * 0.1}).encode(), i)
        w.finish()
    return path


KINDS = {
    "no record": (None, "no 'deformctl' metadata record"),
    "no kind": ({"format_version": "1"}, "not a deformctl log"),
    "bogus kind": ({"kind": "bogus", "format_version": "1"}, "is a bogus"),
    "lift log": ({"kind": "lift_log", "format_version": "1"}, "is a lift_log"),
}


@pytest.mark.parametrize("case", list(KINDS))
@pytest.mark.parametrize("command", ["inspect", "characterize"])
def test_a_log_must_say_its_kind(case: str, command: str, tmp_path: Path) -> None:
    record, needle = KINDS[case]
    log = _log(tmp_path / "s.mcap", record)
    out = tmp_path / "c.parquet"
    argv = [command, str(log)] + (["-o", str(out)] if command == "characterize" else [])
    result = runner.invoke(app, argv)
    if command == "inspect" and case in ("bogus kind", "lift log", "no kind"):
        # inspect describes any MCAP; it must not read the samples as a squeeze log
        assert "squeeze_log" not in result.stdout
        return
    assert result.exit_code == 65, result.output
    line = _one_line(result.stderr)
    assert "s.mcap" in line
    assert needle in line
    assert not out.exists()


@pytest.mark.parametrize("record", [None, {"kind": "squeeze_log", "format_version": "1"}])
def test_a_log_without_crcs_is_refused(record: dict[str, str] | None, tmp_path: Path) -> None:
    log = _log(tmp_path / "s.mcap", record, crcs=False)
    result = runner.invoke(app, ["characterize", str(log), "-o", str(tmp_path / "c.parquet")])
    assert result.exit_code == 65, result.output
    _one_line(result.stderr)
