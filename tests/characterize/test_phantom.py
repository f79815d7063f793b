"""Real silicone-phantom recordings (``tests/data/phantom/``, CC BY 4.0, credit in its README):
the small-strain slope and the stiffening ratio ``characterize`` reports agree within 5 % with a
straight-line fit made here on the file's own rows.

The recordings are single-speed loadings of a strongly stiffening material, so the row must also
say so: ``damping_unidentifiable`` (one speed cannot tell damping from a preload) and
``nonlinear_stiffness``, and never ``ok``. Measured: small-strain slope within 0.1 %, stiffening
ratio within 1.5 % of the direct fits (the loading ends 1 % below the peak force).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_table
from deformctl.cli import app

DATA = Path(__file__).resolve().parents[1] / "data" / "phantom"
FILES = ("EF10_100T_A1", "EF30_12_5T_A1", "EF50_0T_A1")
PREAMBLE_ROWS = 7
REL_TOL = 0.05
runner = CliRunner()


def _direct(rows: pd.DataFrame) -> tuple[float, float]:
    """Straight-line slopes (N/cm) over the first and last 10 % of the compression."""
    d = rows["Compression (mm)"].to_numpy() / 10.0  # cm
    f = rows["Load (N)"].to_numpy()
    top = float(d.max())
    small = d <= 0.1 * top
    large = d >= 0.9 * top
    return float(np.polyfit(d[small], f[small], 1)[0]), float(np.polyfit(d[large], f[large], 1)[0])


@pytest.mark.parametrize("name", FILES)
def test_small_strain_slope_and_stiffening_ratio(tmp_path: Path, name: str) -> None:
    text = (DATA / f"{name}.csv").read_text(encoding="utf-8").splitlines()
    export = tmp_path / "export.csv"  # the reader of this branch needs the header first
    export.write_text("\n".join(text[PREAMBLE_ROWS:]) + "\n", encoding="utf-8")
    rows = pd.read_csv(export)
    log, out = tmp_path / "log.mcap", tmp_path / "c.parquet"
    res = runner.invoke(
        app,
        [
            "measure", "--csv", str(export),
            "--columns", "time=Time (s),force=Load (N),compression=Compression (mm)",
            "--units", "time=s,force=N,compression=mm",
            "--object-id", name, "--weight-n", "1", "-o", str(log),
        ],
    )  # fmt: skip
    assert res.exit_code == 0, res.stderr
    res = runner.invoke(app, ["characterize", str(log), "-o", str(out)])
    assert res.exit_code == 0, res.stderr
    (row,) = read_table(out, "coefficients").to_dict("records")
    small, large = _direct(rows)
    print(
        f"\n{name}: small-strain {row['deformability_small_strain_n_per_cm']:.4g} vs "
        f"{small:.4g} N/cm, stiffening {row['stiffening_ratio']:.4g} vs {large / small:.4g}, "
        f"model {row['model']}, {row['quality']}"
    )
    assert row["deformability_small_strain_n_per_cm"] == pytest.approx(small, rel=REL_TOL)
    assert row["stiffening_ratio"] == pytest.approx(large / small, rel=REL_TOL)
    flags = row["quality"].split(",")
    assert "damping_unidentifiable" in flags
    assert "nonlinear_stiffness" in flags
    assert np.isnan(row["damping_ns_per_cm"])
    assert row["operating_force_source"] == "median_loading"  # no friction in the log
    assert row["operating_force_n"] == pytest.approx(float(np.median(rows["Load (N)"])), rel=0.02)
