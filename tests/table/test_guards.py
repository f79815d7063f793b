"""Quality travels with the numbers; impossible rows are refused, named.

``table`` refuses (65) coefficients that are physically impossible (D <= 0, λ < 0) unless
``--allow-flagged``, which keeps them with their flags in the index table's ``quality``;
``table``, ``table --lookup``, ``train`` and a ``lift --start-table`` refuse lifting forces that
cannot be (L_f below F_w, above 10 x F_w, not finite) with one line naming the rows, before
anything is written or any attempt is made. Good tables pass without a word.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_table, write_table
from deformctl.cli import app
from deformctl.errors import InputDataError
from deformctl.model import TrainOptions
from deformctl.table import impossible_rows
from deformctl.train import train_model

cli = CliRunner()
IDS = ["A", "B", "C", "D"]
WEIGHT = np.array([1.0, 2.0, 3.0, 4.0])  # μ = 0.5: F_w = W


def _coefficients(d: list[float] | None = None, quality: list[str] | None = None) -> pd.DataFrame:
    return pd.DataFrame(
        {
            "object_id": IDS,
            "deformability_n_per_cm": d or [10.0, 20.0, 30.0, 40.0],
            "damping_ns_per_cm": [0.5, 1.0, 1.5, 2.0],
            "quality": quality or ["ok", "ok", "low_r2", "ok"],
        }
    )


def _lift(lift_force_n: list[float] | None = None) -> pd.DataFrame:
    l_f = np.array(lift_force_n) if lift_force_n is not None else WEIGHT * 1.6
    return pd.DataFrame(
        {
            "object_id": IDS, "weight_n": WEIGHT, "friction_mu": 0.5, "f_w_n": WEIGHT,
            "lift_force_n": l_f, "f_d_n": l_f - WEIGHT, "attempts": 5, "converged": True,
            "protocol": "refine",
        }
    )  # fmt: skip


def _files(tmp_path: Path, coef: pd.DataFrame, lift: pd.DataFrame) -> tuple[Path, Path]:
    c, lf = tmp_path / "coefficients.parquet", tmp_path / "lift.parquet"
    write_table(coef, c, "coefficients", provenance=None)
    write_table(lift, lf, "lift_results", provenance=None)
    return c, lf


def _error_line(res: object, code: int = 65) -> str:
    assert res.exit_code == code, res.stderr  # type: ignore[attr-defined]
    lines = res.stderr.splitlines()  # type: ignore[attr-defined]
    assert len(lines) == 1, lines
    assert lines[0].startswith("error: ")
    return str(lines[0])


def test_good_tables_build_silently_and_keep_quality(tmp_path: Path) -> None:
    c, lf = _files(tmp_path, _coefficients(), _lift())
    out = tmp_path / "index.parquet"
    res = cli.invoke(app, ["table", str(c), str(lf), "-o", str(out)])
    assert res.exit_code == 0, res.stderr
    assert "warning" not in res.stderr
    assert list(read_table(out, "index_table")["quality"]) == ["ok", "ok", "low_r2", "ok"]


def test_negative_d_is_refused_unless_allowed_then_flagged(tmp_path: Path) -> None:
    coef = _coefficients(
        d=[10.0, -20.0, 30.0, 40.0], quality=["ok", "negative_stiffness", "ok", "ok"]
    )
    c, lf = _files(tmp_path, coef, _lift())
    out = tmp_path / "index.parquet"
    line = _error_line(cli.invoke(app, ["table", str(c), str(lf), "-o", str(out)]))
    assert line.endswith(
        "impossible rows in the coefficients: deformability_n_per_cm <= 0 for B (-20 N/cm) "
        "(use --allow-flagged to keep them, flagged)"
    )
    assert not out.exists()
    res = cli.invoke(app, ["table", str(c), str(lf), "-o", str(out), "--allow-flagged"])
    assert res.exit_code == 0, res.stderr
    assert "warning: 1 object(s) kept with impossible coefficients (flagged): B" in res.stderr
    index = read_table(out, "index_table").set_index("object_id")
    assert index.loc["B", "quality"] == "negative_stiffness,impossible_coefficients"
    # a lookup that lands on the flagged entry says so
    res = cli.invoke(
        app,
        [
            "table",
            str(out),
            "--lookup",
            "weight_n=2,deformability_n_per_cm=-20,damping_ns_per_cm=1",
        ],
    )
    assert res.exit_code == 0, res.stderr
    assert "warning: the nearest entry B has flagged coefficients" in res.stderr


@pytest.mark.parametrize(
    ("lift_force_n", "message"),
    [
        ([1.6, 1.0, 4.8, 6.4], "lift_force_n below F_w for B (1 N, F_w 2 N)"),
        ([1.6, 3.2, 1e308, 6.4], "lift_force_n above 10 x F_w for C (1e+308 N, F_w 3 N)"),
    ],
)
def test_impossible_lifting_forces_are_refused_by_table_and_lookup(
    tmp_path: Path, lift_force_n: list[float], message: str
) -> None:
    c, lf = _files(tmp_path, _coefficients(), _lift(lift_force_n))
    out = tmp_path / "index.parquet"
    line = _error_line(cli.invoke(app, ["table", str(c), str(lf), "-o", str(out)]))
    assert line.endswith(f"impossible rows in the lift results: {message}")
    assert not out.exists()
    # the same rows in an index table written by hand: a lookup refuses them, prints no force
    index = _lift(lift_force_n).assign(
        deformability_n_per_cm=[10.0, 20.0, 30.0, 40.0], damping_ns_per_cm=[0.5, 1.0, 1.5, 2.0]
    )
    write_table(index, out, "index_table", provenance=None)
    query = "weight_n=3,deformability_n_per_cm=30,damping_ns_per_cm=1.5"
    res = cli.invoke(app, ["table", str(out), "--lookup", query, "--interpolate", "2"])
    assert _error_line(res).endswith(f"impossible rows in the index table: {message}")
    assert res.stdout == ""


def test_train_refuses_impossible_rows_naming_them() -> None:
    rng = np.random.default_rng(0)
    n = 30
    w = rng.uniform(1, 10, n)
    table = pd.DataFrame(
        {
            "object_id": [f"P{i:02d}" for i in range(n)], "weight_n": w,
            "deformability_n_per_cm": rng.uniform(5, 50, n),
            "damping_ns_per_cm": rng.uniform(0, 5, n), "friction_mu": 0.5, "f_w_n": w,
            "lift_force_n": w * 1.5,
        }
    )  # fmt: skip
    table.loc[3, "lift_force_n"] = 1e308
    with pytest.raises(InputDataError, match=r"impossible rows in the index table: lift_force_n "):
        train_model(table, TrainOptions(train_size=20, seed=0, restarts=1))


def test_impossible_rows_is_silent_on_possible_rows() -> None:
    good = _lift().assign(deformability_n_per_cm=10.0, damping_ns_per_cm=-0.01)  # fit noise
    assert impossible_rows(good) == []
    bad = good.assign(damping_ns_per_cm=[0.1, -2.0, 0.1, np.nan])
    assert impossible_rows(bad) == [
        "damping_ns_per_cm not a finite number for D (nan)",
        "damping_ns_per_cm < 0 for B (-2)",
    ]
