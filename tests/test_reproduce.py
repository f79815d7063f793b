"""The ``make reproduce`` path end to end: CLI commands into a run directory, then the report."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.cli import app
from deformctl.errors import MissingInputError
from deformctl.repro.golden import EXPECTED_PATH
from deformctl.repro.report import RUN_FILES, main, write_report

PAPER = Path(__file__).resolve().parent.parent / "datasets" / "paper"
runner = CliRunner()


def _run(*args: str) -> None:
    result = runner.invoke(app, list(args))
    assert result.exit_code == 0, f"{args}: {result.stderr}"


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    run = tmp_path_factory.mktemp("reproduce")
    catalog = str(EXPECTED_PATH.parent / "catalog.csv")
    r = str(run)
    _run("measure", catalog, "--sim", "-o", f"{r}/squeeze.mcap")
    _run("characterize", f"{r}/squeeze.mcap", "-o", f"{r}/coefficients.parquet")
    _run("lift", catalog, "--sim", "-o", f"{r}/lift.parquet")
    _run("table", f"{r}/coefficients.parquet", f"{r}/lift.parquet", "-o", f"{r}/index.parquet")
    _run(
        "train", f"{r}/index.parquet", "-o", f"{r}/model.skops", "--train-size", "6",
        "--metrics", f"{r}/metrics.json",
    )  # fmt: skip
    _run("predict", f"{r}/model.skops", f"{r}/index.parquet", "-o", f"{r}/predictions.parquet")
    paper = str(PAPER / "objects.csv")
    _run("measure", paper, "--sim", "-o", f"{r}/paper_squeeze.mcap")
    _run("characterize", f"{r}/paper_squeeze.mcap", "-o", f"{r}/paper_coefficients.parquet")
    _run("lift", paper, "--sim", "-o", f"{r}/paper_lift.parquet")
    return run


def test_report_has_tables_and_plots(run_dir: Path) -> None:
    summary = write_report(run_dir)
    text = summary.report_path.read_text()
    for heading in ("## Table II", "## Table III", "## Model metrics", "## Plots"):
        assert heading in text
    for oid, name in (("A", "sponge"), ("B", "cotton"), ("C", "sand"), ("D", "water")):
        assert f"| {oid} {name} |" in text
    assert len(summary.plots) == 3
    for png in summary.plots:
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # Our D for the Table I objects is the paper's within 5 % (the catalog carries Table II).
    assert (summary.table2["d_rel_diff"].abs() < 0.05).all()
    # The printed headline equals the test rows of the predictions.
    pred = pd.read_parquet(run_dir / "predictions.parquet")
    assert len(pred) == 8
    match = re.search(r"max relative error ([\d.]+) %", summary.text)
    assert match is not None
    assert float(match.group(1)) == pytest.approx(100 * summary.model_test_max_rel_error, abs=0.01)


def test_missing_run_file_is_one_line_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(MissingInputError, match=RUN_FILES["paper_squeeze"]):
        write_report(tmp_path)
    assert main([str(tmp_path)]) == 66
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert err.startswith("error: ")


def test_required_max_test_error_gates_the_run(
    run_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    error = write_report(run_dir).model_test_max_rel_error
    assert (
        main([str(run_dir), "--require-max-test-error", f"{min(0.99, error * 1.01 + 1e-9)}"]) == 0
    )
    capsys.readouterr()
    assert main([str(run_dir), "--require-max-test-error", f"{error * 0.99}"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("error: the network's max relative test error")
    assert err.count("\n") == 1
    assert main([str(run_dir), "--require-max-test-error", "abc"]) == 2
