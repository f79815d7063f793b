"""The root command: version, help, exit codes."""

from __future__ import annotations

import subprocess
import sys

from typer.testing import CliRunner

from deformctl import __version__
from deformctl.cli import app

runner = CliRunner()


def test_version() -> None:
    result = runner.invoke(app, ["--version"])
    assert result.exit_code == 0
    assert result.stdout.strip() == f"deformctl {__version__}"


def test_help_lists_exit_codes() -> None:
    result = runner.invoke(app, ["--help"])
    assert result.exit_code == 0
    assert "65 bad input data" in result.stdout


def test_unknown_subcommand_is_usage_error() -> None:
    result = runner.invoke(app, ["no-such-command"])
    assert result.exit_code == 2


def test_python_dash_m_entry_point() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "deformctl", "--version"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 0
    assert proc.stdout.startswith("deformctl ")


def test_help_lists_subcommands_in_pipeline_order() -> None:
    result = runner.invoke(app, ["--help"])
    order = ["population", "measure", "characterize", "lift", "table", "train", "predict"]
    positions = [result.stdout.index(f"  {name} ") for name in [*order, "inspect"]]
    assert positions == sorted(positions)
