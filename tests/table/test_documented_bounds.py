"""The documented bounds at every stage that reads coefficients or catalogs.

D = 1e308, W = 1e308 and μ = 50 passed ``table``, ``train`` and ``table --lookup`` (``train``
wrote a model from them; ``--lookup`` switched to raw units, the spread of D overflowing). Each
stage now refuses them with one line naming the column, the bounds and the object (exit 65), the
bounds being the catalog's (:mod:`deformctl.quantities`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import write_table
from deformctl.cli import app
from deformctl.grip.fast import Predictor

cli = CliRunner()
BAD = [("deformability_n_per_cm", 1e308), ("weight_n", 1e308), ("friction_mu", 50.0)]
QUERY = "weight_n=3,deformability_n_per_cm=30,damping_ns_per_cm=1"


def _index(n: int = 48, source: str = "sim") -> pd.DataFrame:
    rng = np.random.default_rng(0)
    W, D = rng.uniform(1, 20, n), rng.uniform(10, 40, n)
    lam, mu = rng.uniform(0.5, 5, n), rng.uniform(0.3, 0.8, n)
    lift = 1.05 * Predictor.load("grip").predict_many(W, D, lam, mu).lift_force_n
    return pd.DataFrame({
        "object_id": [f"O{i}" for i in range(n)], "weight_n": W, "deformability_n_per_cm": D,
        "damping_ns_per_cm": lam, "friction_mu": mu, "f_w_n": W / (2 * mu),
        "lift_force_n": lift, "converged": True, "source": source})  # fmt: skip


def _one_line_65(args: list[str], column: str) -> None:
    res = cli.invoke(app, args)
    assert res.exit_code == 65, (args, res.stdout, res.stderr)
    assert res.stderr.count("\n") == 1, res.stderr
    assert "Traceback" not in res.stderr
    assert column in res.stderr
    assert "bounds" in res.stderr or "must be a number in" in res.stderr


@pytest.mark.parametrize(("column", "value"), BAD)
def test_table_train_lookup_adapt_predict_refuse_it(
    column: str, value: float, tmp_path: Path
) -> None:
    frame = _index()
    frame.loc[0, column] = value
    index = tmp_path / "index.parquet"
    write_table(frame, index, "index_table", provenance=None)
    _one_line_65(["train", str(index), "-o", str(tmp_path / "m.skops")], column)
    assert not (tmp_path / "m.skops").exists()
    _one_line_65(["table", str(index), "--lookup", QUERY], column)
    _one_line_65(["table", str(index), "--lookup", QUERY, "--interpolate", "3"], column)
    _one_line_65(["predict", "grip", str(index)], column)
    rig = _index(12, "rig")
    rig.loc[0, column] = value
    rig_path = tmp_path / "rig.parquet"
    rig.to_parquet(rig_path)
    _one_line_65(["adapt", "grip", str(rig_path), "-o", str(tmp_path / "a.skops")], column)
    # table: the coefficients and the lift results it joins
    coef = frame[["object_id", "deformability_n_per_cm", "damping_ns_per_cm"]].assign(quality="ok")
    lift = frame[["object_id", "weight_n", "friction_mu", "f_w_n", "lift_force_n"]].assign(
        converged=True, attempts=6, protocol="refine", f_d_n=0.05 * frame["f_w_n"]
    )
    coef.to_parquet(tmp_path / "c.parquet")
    lift.to_parquet(tmp_path / "l.parquet")
    out = tmp_path / "t.parquet"
    _one_line_65(["table", str(tmp_path / "c.parquet"), str(tmp_path / "l.parquet"),
                  "-o", str(out)], column)  # fmt: skip
    assert not out.exists()


def test_rows_inside_the_bounds_still_pass(tmp_path: Path) -> None:
    index = tmp_path / "index.parquet"
    write_table(_index(), index, "index_table", provenance=None)
    res = cli.invoke(app, ["table", str(index), "--lookup", QUERY, "--interpolate", "3"])
    assert res.exit_code == 0, res.stderr
    assert "raw units" not in res.stderr
