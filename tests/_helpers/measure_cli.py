"""Helpers of the ``measure`` command tests: the bag and CSV command lines and a refusal check.

The bag of :func:`bag_args` is one written by :func:`tests._helpers.ros2_bags.write_bag` with
:data:`D_TRUE` and :data:`LAM_TRUE`; :func:`_kv_csv_rows` is one squeeze of a Kelvin–Voigt
object with :data:`D_CSV` and :data:`LAM_CSV`; :func:`_fails` runs a command line that must be
refused and checks that nothing was written.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from deformctl.characterize import kelvin_voigt_piecewise_linear
from deformctl.cli import app
from tests._helpers.ros2_bags import LEFT, POSE, RIGHT

runner = CliRunner()
D_TRUE, LAM_TRUE = 30.02, 6.47  # N/cm, N·s/cm


D_CSV, LAM_CSV = 20.0, 3.0  # N/cm, N·s/cm


def bag_args(bag: Path, out: Path, *extra: str) -> list[str]:
    return [
        "measure",
        "bag",
        str(bag),
        "--wrench-topic",
        LEFT,
        "--wrench-topic",
        RIGHT,
        "--position-topic",
        POSE,
        "--object-id",
        "sand",
        "--weight-n",
        "2.9",
        "-o",
        str(out),
        *extra,
    ]


def _kv_csv_rows(noise: bool, rate_hz: float = 1000.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Time (s), force (N) and gap (m) of one ramp-hold-release squeeze, D_CSV and LAM_CSV."""
    t = np.arange(0.0, 5.0, 1.0 / rate_hz)
    knots_t = np.array([0.0, 0.5, 1.5, 3.1, 4.1, 5.0])
    knots_f = np.array([0.0, 0.0, 10.0, 10.0, 0.0, 0.0])
    f = np.interp(t, knots_t, knots_f)
    gap = 0.1 - kelvin_voigt_piecewise_linear(t, knots_t, knots_f, D_CSV * 100, LAM_CSV * 100)
    if noise:
        rng = np.random.default_rng(7)
        f = f + rng.normal(0.0, 0.1, t.size)  # 1 % of the 10 N peak
        gap = gap + rng.normal(0.0, 1e-5, t.size)  # 0.01 mm, a testing machine's crosshead
    return t, f, gap


def csv_args(path: Path, out: Path, columns: str, *extra: str) -> list[str]:
    return [
        "measure",
        "csv",
        str(path),
        "--columns",
        columns,
        "--position-is",
        "gap",
        "--object-id",
        "foam",
        "--weight-n",
        "0.7",
        "-o",
        str(out),
        *extra,
    ]


def _fails(args: list[str], code: int, match: str, out: Path) -> str:
    """Run, check the exit code, the one-line message and that nothing was written."""
    before = sorted(out.parent.iterdir())
    res = runner.invoke(app, args)
    assert res.exit_code == code, (res.exit_code, res.stderr)
    assert res.stdout == ""
    lines = res.stderr.splitlines()
    assert len(lines) == 1, res.stderr
    assert lines[0].startswith("error: ")
    assert match in lines[0], lines[0]
    assert sorted(out.parent.iterdir()) == before  # no output, no temporary file
    return lines[0]
