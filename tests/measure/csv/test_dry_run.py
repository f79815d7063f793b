"""``measure csv --dry-run``: what would be detected in each export, and nothing written.

The exports are written by tests/measure/_exports.py in known dialects (a preamble, ``;`` with a
decimal comma, a units row, a negative force), so every detected item has a known answer. A bad
file gets the same one ``error:`` line and exit code as a real run.
"""

from __future__ import annotations

from pathlib import Path

from typer.testing import CliRunner

from deformctl.cli import app
from deformctl.errors import EXIT_DATAERR, EXIT_FAILURE, EXIT_NOINPUT, EXIT_USAGE

from .._exports import kv_squeeze, write_export

runner = CliRunner()


def _dry(*args: str) -> tuple[int, str, str]:
    res = runner.invoke(app, ["measure", "csv", "--dry-run", *args])
    return res.exit_code, res.stdout, res.stderr


def test_a_european_export_is_described_and_nothing_is_written(tmp_path: Path) -> None:
    path = write_export(
        tmp_path / "foam.csv",
        kv_squeeze(),
        preamble=("Machine: UTM 5900", "Operator: A", "free text"),
        delimiter=";",
        decimal=",",
        force_sign=-1.0,
    )
    out = tmp_path / "squeeze.mcap"
    code, stdout, stderr = _dry(str(path), "--weight-n", "1", "-o", str(out))
    assert code == 0, stderr
    assert stderr == ""
    lines = stdout.splitlines()
    assert lines[0] == f"{path}: object 'foam'"
    assert (
        "  preamble: 3 line(s) before the header skipped (lines 1-3, 2 of them 'key: value' lines)"
        in lines
    )
    assert "  header row: line 4 (found); units row: none; data from line 5" in lines
    assert lines[3].startswith("  delimiter: ';' (found); decimal mark: ',' (found);")
    assert "  time: column 'Time (s)' in s (column by name, unit from header)" in lines
    assert "  force: column 'Load (N)' in N (column by name, unit from header)" in lines
    assert (
        "  compression: column 'Compression (mm)' in mm (column by name, unit from header)" in lines
    )
    sign = [line for line in lines if "force sign" in line]
    assert sign == [
        "  force sign: compressive force is negative in column 'Load (N)' (nearly all of the "
        "force has that sign): flipped to positive"
    ]
    assert lines[-1] == "dry run: 1 of 1 file(s) read; nothing written"
    assert list(tmp_path.iterdir()) == [path]  # no log, not even with -o


def test_a_units_row_a_named_column_and_a_dataset_output(tmp_path: Path) -> None:
    s = kv_squeeze()
    path = write_export(
        tmp_path / "grip.csv",
        s,
        names=("Time", "F", "Compression"),
        units=("ms", "kN", "mm"),
        units_row=("ms", "kN", "mm"),
    )
    out = tmp_path / "ds"
    code, stdout, stderr = _dry(
        str(path), "--weight-n", "1", "--columns", "force=F", "-o", f"{out}/"
    )
    assert code == 0, stderr
    assert "units row: line 2" in stdout
    assert "  force: column 'F' in kN (column by --columns, unit from units row)" in stdout
    assert "  time: column 'Time' in ms (column by name, unit from units row)" in stdout
    assert "compressive force is positive" in stdout
    assert "kept as it is" in stdout
    assert not out.exists()


def test_the_position_reading_follows_position_is(tmp_path: Path) -> None:
    s = kv_squeeze()
    path = write_export(tmp_path / "jaw.csv", s, names=("Time (s)", "Force (N)", "Position (mm)"))
    for kind, rule in (("travel", "d = |p - p(first row)|"), ("palm", "d = 2 x |p - p(first")):
        code, stdout, stderr = _dry(str(path), "--weight-n", "1", "--position-is", kind)
        assert code == 0, stderr
        assert f"  position: column 'Position (mm)' (position) read as {kind}: {rule}" in stdout


def test_a_bad_file_gets_the_real_runs_line_and_exit_code(tmp_path: Path) -> None:
    bad = tmp_path / "bad.csv"
    bad.write_text("Time (s),Load (furlong),Compression (mm)\n" + "0,1,2\n" * 40)
    out = tmp_path / "o.mcap"
    real = runner.invoke(app, ["measure", "csv", str(bad), "--weight-n", "1", "-o", str(out)])
    code, stdout, stderr = _dry(str(bad), "--weight-n", "1", "-o", str(out))
    assert (code, real.exit_code) == (EXIT_DATAERR, EXIT_DATAERR)
    assert stderr == real.stderr
    assert stderr.startswith("error: ")
    assert stderr.count("\n") == 1
    assert "furlong" in stderr
    assert stdout == "dry run: 0 of 1 file(s) read; nothing written\n"
    assert not out.exists()


def test_many_files_one_bad_exits_1_as_a_real_run(tmp_path: Path) -> None:
    good = write_export(tmp_path / "good.csv", kv_squeeze())
    bad = tmp_path / "bad.csv"
    bad.write_text("Time (s),Load (furlong),Compression (mm)\n" + "0,1,2\n" * 40)
    code, stdout, stderr = _dry(str(good), str(bad), "--weight-n", "1")
    assert code == EXIT_FAILURE
    assert f"{good}: object 'good'" in stdout
    assert [line for line in stderr.splitlines() if line.startswith("error:")] == [stderr.strip()]
    assert "dry run: 1 of 2 file(s) read; nothing written" in stdout


def test_a_missing_file_exits_66_and_no_output_without_dry_run_exits_2(tmp_path: Path) -> None:
    code, _, stderr = _dry(str(tmp_path / "none.csv"), "--weight-n", "1")
    assert code == EXIT_NOINPUT
    assert stderr.startswith("error: ")
    assert stderr.count("\n") == 1
    good = write_export(tmp_path / "good.csv", kv_squeeze())
    res = runner.invoke(app, ["measure", "csv", str(good), "--weight-n", "1"])
    assert res.exit_code == EXIT_USAGE
    assert res.stderr == "error: measure csv needs -o/--output (or --dry-run)\n"
