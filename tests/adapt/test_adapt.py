"""The library and the command: ``adapt`` corrects a grip model with rig rows.

Known truth: a "reality" whose L_f is the bundled model's times ``exp(c0 + c · x)`` (x: the
network's scaled inputs) with 1 % noise. The ridge correction recovers c, the adapted model's
error on 30 new objects is at most half the base model's, the closed-form leave-one-out equals
refitting without each row, the bound follows the finite-sample rule, and bad adapt sets are one
exit-65 line naming the rows. (The gap between the simulator's presets: bench/bench_adapt.py.)
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.adapt import adapt_model, ridge_loo
from deformctl.artifacts import write_table
from deformctl.cli import app
from deformctl.grip.fast import Predictor, read_model_metadata
from tests._helpers.cli import _error

GAP = np.array([0.15, 0.05, 0.0])  # c0, c_ω, c_ζ of the synthetic reality
runner = CliRunner()


def _objects(n: int, rng: np.random.Generator, prefix: str = "R") -> pd.DataFrame:
    return pd.DataFrame({
        "object_id": [f"{prefix}{i:02d}" for i in range(n)], "weight_n": rng.uniform(1, 40, n),
        "deformability_n_per_cm": rng.uniform(8, 50, n), "damping_ns_per_cm": rng.uniform(0, 10, n),
        "friction_mu": rng.uniform(0.3, 0.9, n),
    })  # fmt: skip


def _reality(base: Predictor, df: pd.DataFrame, rng: np.random.Generator) -> np.ndarray:
    cols = [df[c].to_numpy() for c in base.features]
    x = (base._groups(*cols[:3]) - base.mean) / base.scale
    gap = GAP[0] + x @ GAP[1:]
    return base.predict_many(*cols).lift_force_n * np.exp(gap + rng.normal(0, 0.01, len(df)))


def _index(base: Predictor, n: int, seed: int) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    rows = _objects(n, rng)
    rows["lift_force_n"] = _reality(base, rows, rng)
    rows["f_w_n"] = rows["weight_n"] / (2 * rows["friction_mu"])
    rows["converged"] = True
    rows["source"] = "rig"
    return rows


@pytest.fixture(scope="module")
def base() -> Predictor:
    return Predictor.load("grip")


def test_the_correction_is_recovered_and_halves_the_error(base: Predictor) -> None:
    result = adapt_model("grip", _index(base, 20, seed=1))
    np.testing.assert_allclose(result.metadata["adapted"]["coefficients"], GAP, atol=0.02)
    rng = np.random.default_rng(2)
    new = _objects(30, rng, "N")
    truth = _reality(base, new, rng)
    cols = [new[c].to_numpy() for c in base.features]
    before = np.median(np.abs(base.predict_many(*cols).lift_force_n / truth - 1))
    after = np.median(np.abs(result.predictor.predict_many(*cols).lift_force_n / truth - 1))
    assert after <= 0.5 * before
    assert after < 0.02  # the 1 % noise, not the 15 % gap


def test_no_gap_means_no_correction(base: Predictor) -> None:
    rows = _index(base, 8, seed=3)
    cols = [rows[c].to_numpy() for c in base.features]
    rows["lift_force_n"] = base.predict_many(*cols).lift_force_n  # reality = the model
    result = adapt_model("grip", rows)
    assert np.max(np.abs(result.metadata["adapted"]["coefficients"])) < 1e-9


def test_closed_form_leave_one_out_is_refitting_without_each_row() -> None:
    rng = np.random.default_rng(4)
    X = np.column_stack([np.ones(7), rng.normal(size=(7, 2))])
    y = X @ np.array([0.1, 0.2, -0.1]) + rng.normal(0, 0.05, 7)
    _, alpha, loo = ridge_loo(X, y)
    assert np.isfinite(alpha)
    for i in range(7):
        keep = np.arange(7) != i
        ci = np.linalg.solve(X[keep].T @ X[keep] + alpha * np.eye(3), X[keep].T @ y[keep])
        assert loo[i] == pytest.approx(y[i] - X[i] @ ci, rel=1e-9, abs=1e-12)


def test_the_command_writes_a_model_predict_and_lift_use(base: Predictor, tmp_path: Path) -> None:
    write_table(_index(base, 20, seed=5), tmp_path / "rig.parquet", "index_table", provenance=None)
    out = tmp_path / "adapted.skops"
    result = runner.invoke(app, ["adapt", "grip", str(tmp_path / "rig.parquet"), "-o", str(out)])
    assert result.exit_code == 0, result.stderr
    assert "wrote" in result.stderr.splitlines()[-1]
    meta = read_model_metadata(out)
    assert [r["object_id"] for r in meta["adapted"]["rows"]] == [f"R{i:02d}" for i in range(20)]
    assert "ceil((n + 1) P)" in meta["adapted"]["bound_rule"]
    shown = runner.invoke(app, ["inspect", str(out)]).stdout
    assert f"adapted: from grip with 20 rig rows of {tmp_path / 'rig.parquet'}" in shown
    assert "  R07: L_f " in shown
    flags = ["--weight-n", "10", "--deformability-n-per-cm", "20", "--damping-ns-per-cm", "2",
             "--friction-mu", "0.5", "--coverage", "0.9"]  # fmt: skip
    got = pd.read_csv(io.StringIO(runner.invoke(app, ["predict", str(out), *flags]).stdout))
    one = Predictor.load(out).predict_many([10.0], [20.0], [2.0], [0.5], coverage=0.9)
    assert got.loc[0, "predicted_lift_force_n"] == pytest.approx(one.lift_force_n[0], rel=1e-5)
    assert got.loc[0, "predicted_lift_force_n"] > 1.1 * float(
        base.predict_many([10.0], [20.0], [2.0], [0.5]).lift_force_n[0]
    )  # the 15 % gap is corrected
    # the bound: the k = ceil(21 * 0.9) = 19th of the 20 leave-one-out scores
    scores = np.sort([r["loo_score"] for r in meta["adapted"]["rows"]])
    assert one.lift_force_upper_n[0] == pytest.approx(one.lift_force_n[0] * (1 + scores[18]))


def test_eight_rows_give_the_largest_score_flagged(base: Predictor, tmp_path: Path) -> None:
    write_table(_index(base, 8, seed=6), tmp_path / "rig.parquet", "index_table", provenance=None)
    out = tmp_path / "adapted.skops"
    args = ["adapt", "grip", str(tmp_path / "rig.parquet"), "-o", str(out)]
    assert runner.invoke(app, args).exit_code == 0
    flags = ["--weight-n", "10", "--deformability-n-per-cm", "20", "--damping-ns-per-cm", "2",
             "--friction-mu", "0.5"]  # fmt: skip
    result = runner.invoke(app, ["predict", str(out), *flags, "--coverage", "0.9"])
    assert result.exit_code == 0, result.stderr
    assert result.stderr.splitlines() == [
        "warning: the bound at P = 0.9 rests on 8 rig rows, fewer than the 9 it needs: it is "
        "their largest score, guaranteed at n / (n + 1) = 0.889 only (bound_guaranteed = false)"
    ]
    got = pd.read_csv(io.StringIO(result.stdout)).iloc[0]
    scores = [r["loo_score"] for r in read_model_metadata(out)["adapted"]["rows"]]
    assert not got["bound_guaranteed"]
    want = got["predicted_lift_force_n"] * (1 + max(scores))
    assert got["lift_force_upper_n"] == pytest.approx(want, rel=1e-5)
    result = runner.invoke(app, ["predict", str(out), *flags, "--coverage", "0.8"])  # k = 8 <= 8
    assert result.stderr == ""
    assert bool(pd.read_csv(io.StringIO(result.stdout)).loc[0, "bound_guaranteed"])


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda t: t.iloc[:2], "adapt needs at least 3 rig rows; the table has 2 (R00, R01)"),
        (lambda t: t.assign(converged=[True, False, True, False, True]),
         "rows R01, R03: the lift search did not converge"),
        (lambda t: t.drop(columns=["friction_mu", "f_w_n"]),
         "rows R00, R01, R02, R03, R04 lack the model's feature(s) friction_mu"),
        (lambda t: t.assign(source=["rig", "sim", "sim", "sim", "rig"]),
         "adapt needs at least 3 rig rows; the table has 2 (R00, R04)"),
    ],
)  # fmt: skip
def test_bad_adapt_sets_are_one_line_naming_the_rows(
    base: Predictor, tmp_path: Path, change: object, message: str
) -> None:
    table = change(_index(base, 5, seed=7))  # type: ignore[operator]
    write_table(table, tmp_path / "rig.parquet", "index_table", provenance=None)
    out = tmp_path / "adapted.skops"
    result = runner.invoke(app, ["adapt", "grip", str(tmp_path / "rig.parquet"), "-o", str(out)])
    line = _error(result, 65)
    assert message in line
    assert str(tmp_path / "rig.parquet") in line
    assert not out.exists()
