"""Reading budgets and bounds (inspect /dev/zero, population -n).

A device is refused before any byte is read; a file or stdin larger than the reading budget is
refused naming the budget; a file within it reads as before. ``population -n`` above its bound
is a usage error naming the flag and the memory it would take, before anything is written.
"""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from deformctl.cli import app
from deformctl.population import MAX_POPULATION_SIZE

runner = CliRunner()


def _one_error(res: object, code: int) -> str:
    assert res.exit_code == code, res.stderr  # type: ignore[attr-defined]
    lines = res.stderr.splitlines()  # type: ignore[attr-defined]
    assert len(lines) == 1
    return str(lines[0])


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="no /dev/zero")
def test_a_device_is_refused_before_reading() -> None:
    started = time.perf_counter()
    line = _one_error(runner.invoke(app, ["inspect", "/dev/zero"]), 65)
    assert line == "error: /dev/zero: is a device, not a file: refused before reading"
    assert time.perf_counter() - started < 5.0


def test_a_file_over_the_budget_is_refused_and_one_within_it_is_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "objects.csv"
    path.write_text(
        "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu\nA,1,1,1,1,0.5\n",
        encoding="utf-8",
    )
    assert runner.invoke(app, ["inspect", str(path)]).exit_code == 0  # the default budget
    monkeypatch.setenv("DEFORMCTL_READ_BUDGET_GIB", str(10 / (1 << 30)))  # 10 bytes
    line = _one_error(runner.invoke(app, ["inspect", str(path)]), 65)
    assert line.startswith(f"error: {path}: is ")
    assert line.endswith(
        "more than the reading budget of 9.31e-09 GiB (DEFORMCTL_READ_BUDGET_GIB raises it)"
    )
    res = runner.invoke(app, ["inspect", "-"], input=path.read_bytes())
    assert _one_error(res, 65).startswith("error: <stdin>: more than the reading budget")


def test_population_n_is_bounded_naming_the_flag(tmp_path: Path) -> None:
    out = tmp_path / "pop.csv"
    line = _one_error(runner.invoke(app, ["population", "-n", "1000000000000", "-o", str(out)]), 2)
    assert line == (
        f"error: -n 1000000000000 is above the bound of {MAX_POPULATION_SIZE} objects (it would "
        "need about 6.52e+04 GiB of memory at 70 bytes per object)"
    )
    assert _one_error(runner.invoke(app, ["population", "-n", "0", "-o", str(out)]), 2) == (
        "error: -n must be an integer >= 1, got 0"
    )
    assert not out.exists()
    assert runner.invoke(app, ["population", "-n", "5", "-o", str(out)]).exit_code == 0


@pytest.mark.parametrize(
    ("args", "line"),
    [
        (["--weight-n", "0,10"], "error: --weight-n must be a number in [0.001, 5000] N, got 0"),
        (["--friction-mu", "0"], "error: --friction-mu must be a number in [0.01, 3], got 0"),
    ],
)
def test_population_range_errors_name_the_flag(tmp_path: Path, args: list[str], line: str) -> None:
    out = tmp_path / "pop.csv"
    assert _one_error(runner.invoke(app, ["population", *args, "-o", str(out)]), 2) == line
    assert not out.exists()
