"""Usage errors in the one-line form, warnings folded, clean exits."""

from __future__ import annotations

import os
import subprocess
import sys
import warnings
from pathlib import Path

import pyarrow as pa
import pytest
import typer
from typer.testing import CliRunner

from deformctl.artifacts import tables
from deformctl.cli import app
from deformctl.cli._common import translate_errors
from deformctl.errors import InputDataError

runner = CliRunner()
DATA = Path(__file__).parents[1] / "data"


def _one_error_line(stderr: str) -> str:
    assert stderr.startswith("error: "), stderr
    assert stderr.count("\n") == 1, stderr
    assert "Traceback" not in stderr
    return stderr


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["no-such-command"], "no such command 'no-such-command'"),
        (["lift", "--bogus"], "no such option: --bogus"),
        (["population", "--seed", "abc", "-o", "p.csv"], "--seed"),
        (["lift", "sim"], "missing argument"),
        (["inspect"], "missing argument"),
        (["table", "a", "--interpolate", "x"], "--interpolate"),
        (["measure", "sim", "x", "--squeezes", "many", "-o", "y"], "--squeezes"),
    ],
)
def test_usage_errors_are_one_line_exit_2(argv: list[str], needle: str) -> None:
    result = runner.invoke(app, argv)
    assert result.exit_code == 2
    line = _one_error_line(result.stderr)
    assert needle in line
    assert "--help" in line


def test_bare_command_still_prints_help() -> None:
    result = runner.invoke(app, [])
    assert result.exit_code == 2
    assert "Usage: deformctl" in result.stdout


def test_usage_error_in_a_real_process_is_one_line() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "deformctl", "lift", "--seed", "abc"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 2
    _one_error_line(proc.stderr)


def test_numeric_warnings_are_folded_into_the_error_line(
    capsys: pytest.CaptureFixture[str],
) -> None:
    @translate_errors
    def command() -> None:
        warnings.warn("overflow encountered in multiply", RuntimeWarning, stacklevel=1)
        raise InputDataError("samples are not finite", path="x.mcap")

    with pytest.raises(typer.Exit) as exit_info:
        command()
    assert exit_info.value.exit_code == 65
    err = capsys.readouterr().err
    _one_error_line(err)
    assert "x.mcap: samples are not finite (while: RuntimeWarning: overflow" in err


def test_warnings_after_success_are_one_line_each(capsys: pytest.CaptureFixture[str]) -> None:
    @translate_errors
    def command() -> int:
        for _ in range(3):
            warnings.warn("divide by zero\nencountered", RuntimeWarning, stacklevel=1)
        return 1

    assert command() == 1
    assert capsys.readouterr().err == "warning: divide by zero encountered\n"


def test_parquet_is_decoded_from_an_arrow_buffer(monkeypatch: pytest.MonkeyPatch) -> None:
    # The cause of the exit -6 after an error: Arrow's I/O threads reading a Python file object
    # through the GIL while the interpreter finalizes. Parquet must be read from an Arrow buffer.
    seen: list[object] = []
    real = tables.pq.ParquetFile

    def spy(source: object, *args: object, **kwargs: object) -> object:
        seen.append(source)
        return real(source, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(tables.pq, "ParquetFile", spy)
    tables.read_parquet_bytes((DATA / "index_table.parquet").read_bytes(), "index.parquet")
    assert seen
    assert all(isinstance(s, pa.BufferReader) for s in seen)


def test_parquet_is_decoded_on_the_calling_thread(monkeypatch: pytest.MonkeyPatch) -> None:
    # The buffer wraps the Python bytes; an Arrow pool worker dropping it after the read takes
    # the GIL in ~PyBuffer, which aborts the process when that happens during finalization.
    calls: list[dict[str, object]] = []
    real = tables.pq.ParquetFile.read

    def spy(self: object, *args: object, **kwargs: object) -> object:
        calls.append(kwargs)
        return real(self, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(tables.pq.ParquetFile, "read", spy)
    tables.read_parquet_bytes((DATA / "index_table.parquet").read_bytes(), "index.parquet")
    assert calls == [{"use_threads": False}]


def _bad_inputs(tmp: Path, command: str) -> list[str]:
    """The stress cases: table and predict on inputs that are refused (exit 65)."""
    import pyarrow.parquet as pq

    if command == "table":
        lift = str(DATA / "lift_results.parquet")
        return ["table", str(DATA / "predictions.parquet"), lift, "-o", str(tmp / "t.parquet")]
    demo = tmp / "demo"
    example = Path(__file__).parents[2] / "examples" / "synthetic_index.py"
    subprocess.run([sys.executable, str(example), str(demo)], check=True, capture_output=True)
    index, model = str(demo / "index.parquet"), str(demo / "model.skops")
    runner.invoke(
        app,
        ["table", str(demo / "coefficients.parquet"), str(demo / "lift.parquet"), "-o", index],
    )
    assert runner.invoke(app, ["train", index, "-o", model]).exit_code == 0
    bad = tmp / "bad_meta.parquet"
    t = pq.read_table(demo / "coefficients.parquet")
    pq.write_table(t.replace_schema_metadata({b"deformctl": b"{garbage"}), bad)
    return ["predict", model, str(bad), "--catalog", str(demo / "objects.csv")]


@pytest.mark.skipif(
    os.environ.get("DEFORMCTL_STRESS") is None,
    reason="80 interpreter start-ups (about 3 minutes); DEFORMCTL_STRESS=40 runs it",
)
@pytest.mark.parametrize("command", ["table", "predict"])
def test_stress_bad_inputs_exit_with_the_documented_code(command: str, tmp_path: Path) -> None:
    argv = _bad_inputs(tmp_path, command)
    codes = []
    for _ in range(int(os.environ.get("DEFORMCTL_STRESS", "40"))):
        proc = subprocess.run(
            [sys.executable, "-m", "deformctl", *argv], capture_output=True, text=True, check=False
        )
        _one_error_line(proc.stderr)
        codes.append(proc.returncode)
    assert set(codes) == {65}
