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


def test_cli_start_up_imports_no_heavy_library() -> None:
    # `deformctl --help` and the light commands must start fast in shell pipelines: OpenCV,
    # scikit-learn, skops, scipy.signal and numba are imported only by the commands that use them.
    code = (
        "import sys, deformctl.cli; "
        "print(','.join(m for m in ('cv2', 'sklearn', 'skops', 'scipy.signal', 'numba', "
        "'distributed', 'matplotlib') if m in sys.modules))"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == ""
