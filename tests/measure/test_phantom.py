"""Real testing-machine exports: read with no option, D checked against a line fit of the raw file.

The silicone phantom recordings (a 7-line preamble, units in the header names, CC BY 4.0: the
three shipped in ``datasets/examples/phantom/`` and, when the shared folder is there, all of
``/work/shared/data/phantom/``) go through ``measure --csv <every file> -o DIR/`` and
``characterize DIR/ --model kv`` with no ``--columns``, ``--units`` or ``--skip-rows``. Each
Kelvin–Voigt stiffness must agree within 2 % with a straight line fitted here to the raw file over
the same loading window
(the compression range the fit reports): the file is read with numpy knowing its layout (8 lines
before the data; time s, compression mm, load N), each sample weighted by its time interval, as
the fit's uniform time grid weights it (one file has rows at irregular intervals); each D, the
recording's own secant at the force it is stated at, within 1 % of that secant taken here from the
file's rows.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.cli import app

runner = CliRunner()
SHIPPED = Path(__file__).resolve().parents[2] / "datasets" / "examples" / "phantom"
SHARED = Path("/work/shared/data/phantom")


def _line_slope_n_per_cm(csv: Path, d_min_cm: float, d_max_cm: float) -> float:
    raw = np.genfromtxt(csv, delimiter=",", skip_header=8)
    t, d_cm, f = raw[:, 0], raw[:, 1] / 10.0, raw[:, 2]
    window = (d_cm >= d_min_cm) & (d_cm <= d_max_cm)
    weight = np.gradient(t)[window]
    slope, _ = np.polyfit(d_cm[window], f[window], 1, w=np.sqrt(weight))
    return float(slope)


def _file_secant_n_per_cm(csv: Path, force_n: float) -> float:
    raw = np.genfromtxt(csv, delimiter=",", skip_header=8)
    d_cm, f = raw[:, 1] / 10.0, raw[:, 2]
    j = int(np.argmax(f >= force_n))
    return force_n / float(np.interp(force_n, f[j - 1 : j + 1], d_cm[j - 1 : j + 1] - d_cm[0]))


def _check_folder(files: list[Path], tmp_path: Path) -> pd.DataFrame:
    out = tmp_path / "squeeze"
    args = ["measure", "csv", *map(str, files), "--weight-n", "1", "--workers", "1"]
    res = runner.invoke(app, [*args, "-o", f"{out}/"])
    assert res.exit_code == 0, res.stderr
    assert res.stderr.splitlines()[0] == (
        f"{out}: columns: time='Time (s)' [s], force='Load (N)' [N], compression='Compression "
        f"(mm)' [mm] (all {len(files)} files)"
    )
    table = tmp_path / "coefficients.parquet"
    res = runner.invoke(app, ["characterize", f"{out}/", "-o", str(table), "--model", "kv"])
    assert res.exit_code == 0, res.stderr
    coef = pd.read_parquet(table).set_index("object_id")
    assert list(coef.index) == [f.stem for f in files]
    for f in files:
        row = coef.loc[f.stem]
        slope = _line_slope_n_per_cm(f, row["compression_min_cm"], row["compression_max_cm"])
        assert row["kv_deformability_n_per_cm"] == pytest.approx(slope, rel=0.02), f.name
        secant = _file_secant_n_per_cm(f, row["deformability_at_force_n"])
        assert row["deformability_n_per_cm"] == pytest.approx(secant, rel=0.01), f.name
        assert row["compression_max_cm"] == pytest.approx(2.0, abs=0.01), f.name  # 20 mm
        # a straight line is a poor fit of a material that stiffens 20-50x: said
        # and where D is stated the straight line misses the recording (secant_misfit) on most
        flags = {"damping_unidentifiable", "low_r2", "nonlinear_stiffness"}
        assert flags <= set(row["quality"].split(",")) <= {*flags, "secant_misfit"}, f.name
    return coef


def test_shipped_phantom_examples(tmp_path: Path) -> None:
    files = sorted(SHIPPED.glob("*.csv"))
    assert [f.stem for f in files] == ["EF10_0T_A1", "EF30_0T_A1", "EF50_12_5T_A2"]
    coef = _check_folder(files, tmp_path)
    assert coef.loc["EF10_0T_A1", "kv_deformability_n_per_cm"] == pytest.approx(157.7, rel=0.01)


@pytest.mark.skipif(not SHARED.is_dir(), reason="the shared phantom folder is not on this machine")
def test_every_shared_phantom_file(tmp_path: Path) -> None:
    files = sorted(SHARED.glob("*.csv"))
    assert len(files) == 38
    coef = _check_folder(files, tmp_path)
    kv = coef["kv_deformability_n_per_cm"]
    assert 20.0 < kv.min() < kv.max() < 400
