"""Edge-case user inputs found by review: each is a one-line error, never a traceback."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from deformctl.cli import app

runner = CliRunner()
CATALOG = (
    "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu,"
    "material_stiffness_n_per_cm,material_damping_ns_per_cm\nA,10,10,10,1,0.5,10,1\n"
)


@pytest.fixture
def catalog(tmp_path: Path) -> Path:
    path = tmp_path / "cat.csv"
    path.write_text(CATALOG)
    return path


def _one_line_error(stderr: str) -> None:
    assert stderr.startswith("error: ")
    assert stderr.count("\n") == 1


@pytest.mark.parametrize("command", ["measure", "lift"])
def test_tiny_alpha_is_refused_before_building_the_lattice(
    command: str, catalog: Path, tmp_path: Path
) -> None:
    out = tmp_path / ("x.mcap" if command == "measure" else "x.parquet")
    result = runner.invoke(
        app, [command, "sim", str(catalog), "--alpha-cm", "1e-3", "-o", str(out)]
    )
    assert result.exit_code == 2
    _one_line_error(result.stderr)
    assert "particles" in result.stderr
    assert "use a larger alpha_cm" in result.stderr
    assert not out.exists()


@pytest.mark.parametrize(
    "args",
    [
        ["population", "--seed", "-1", "-o", "{tmp}/p.csv"],
        ["measure", "sim", "{catalog}", "--seed", "-1", "-o", "{tmp}/x.mcap"],
        ["train", "{tmp}/index.parquet", "--seed", "-1", "-o", "{tmp}/m.skops"],
    ],
)
def test_negative_seed_is_a_usage_error(args: list[str], catalog: Path, tmp_path: Path) -> None:
    argv = [a.format(tmp=tmp_path, catalog=catalog) for a in args]
    result = runner.invoke(app, argv)
    assert result.exit_code == 2
    assert "--seed" in result.stderr
    assert "Traceback" not in result.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cat.csv"]


def test_csv_that_is_not_utf8_is_bad_input(tmp_path: Path) -> None:
    src = tmp_path / "latin1.csv"
    src.write_bytes("time,force,pos\n0,1,caf\xe9\n".encode("latin-1"))
    out = tmp_path / "x.mcap"
    argv = ["measure", "csv", str(src), "--columns", "time=time,force=force,position=pos"]
    result = runner.invoke(app, [*argv, "--object-id", "A", "--weight-n", "1", "-o", str(out)])
    assert result.exit_code == 65
    _one_line_error(result.stderr)
    assert "not UTF-8 text: byte 0xe9 on line 2 does not decode; pass --encoding cp1252" in (
        result.stderr
    )
    assert not out.exists()
