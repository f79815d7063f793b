"""The lifting-force model: reproducibility, metrics, baselines, accuracy, prediction, bad inputs.

The data is synthetic (:func:`deformctl.repro.synthetic.synthetic_index_table`), from a known
smooth function shaped like the physics:
``L_f = F_w * (1 + 0.6 * W / D * (0.5 + 0.5 * exp(-λ / 4 N·s/cm)))`` with ``F_w = W / (2 μ)``,
on the paper's population (73 objects from :func:`make_population`), times a seeded ±1 %
multiplicative noise standing in for the tolerance of the lifting-force search.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from sklearn.linear_model import LinearRegression
from sklearn.metrics import mean_absolute_error, r2_score
from sklearn.neural_network import MLPRegressor
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler

from deformctl.errors import InputDataError, SchemaError, UsageError
from deformctl.model import TrainOptions
from deformctl.repro.synthetic import synthetic_index_table
from deformctl.table import lookup
from deformctl.train import (
    FEATURES,
    TrainResult,
    predict,
    regression_metrics,
    train_model,
)


@pytest.fixture(scope="module")
def table() -> pd.DataFrame:
    return synthetic_index_table()


@pytest.fixture(scope="module")
def trained(table: pd.DataFrame) -> TrainResult:
    return train_model(table, TrainOptions(seed=0))


def test_same_seed_gives_identical_predictions(table: pd.DataFrame) -> None:
    a = train_model(table, TrainOptions(seed=5, restarts=2))
    b = train_model(
        table.sample(frac=1.0, random_state=1), TrainOptions(seed=5, restarts=2)
    )  # row order
    pd.testing.assert_frame_equal(a.predictions, b.predictions, check_exact=True)
    assert a.split == b.split
    assert a.metrics == b.metrics
    assert a.metrics["seed"] == 5
    c = train_model(table, TrainOptions(seed=6, restarts=1))
    assert c.split != a.split


def test_split_sizes_and_recorded_hyperparameters(
    trained: TrainResult, table: pd.DataFrame
) -> None:
    assert len(trained.split.train) == 40
    assert len(trained.split.test) == 33
    assert set(trained.split.train).isdisjoint(trained.split.test)
    assert set(trained.split.train) | set(trained.split.test) == set(table["object_id"])
    m = trained.metrics
    assert m["seed"] == 0
    assert m["features"] == list(FEATURES)
    assert m["hyperparameters"]["hidden"] == [2]
    assert m["hyperparameters"]["solver"] == "lbfgs"
    assert len(m["restart_train_rms_rel_error"]) == m["hyperparameters"]["restarts"]
    # the chosen restart is the best on the training rows
    assert m["chosen_restart"] == int(np.argmin(m["restart_train_rms_rel_error"]))


def test_network_is_the_papers_3_2_1(trained: TrainResult) -> None:
    core = trained.model.regressor_
    assert isinstance(core, Pipeline)
    assert [type(s) for _, s in core.steps] == [StandardScaler, MLPRegressor]
    assert [c.shape for c in core[-1].coefs_] == [(3, 2), (2, 1)]
    assert list(trained.model.feature_names_in_) == list(FEATURES)


def _independent_metrics(y: np.ndarray, p: np.ndarray) -> dict[str, float]:
    rel = [abs(pi - yi) / abs(yi) for yi, pi in zip(y, p, strict=True)]
    rel_sorted = sorted(rel)
    k = len(rel_sorted)
    median = rel_sorted[k // 2] if k % 2 else 0.5 * (rel_sorted[k // 2 - 1] + rel_sorted[k // 2])
    return {
        "max_rel_error": max(rel),
        "median_rel_error": median,
        "mae_n": mean_absolute_error(y, p),
        "r2": r2_score(y, p),
    }


def test_metrics_match_an_independent_computation(trained: TrainResult) -> None:
    pred = trained.predictions
    for split in ("train", "test"):
        part = pred[pred["split"] == split]
        y = part["lift_force_n"].to_numpy()
        for key, column in (
            ("model", "predicted_lift_force_n"),
            ("baseline_nearest", "nearest_lift_force_n"),
            ("baseline_f_w", "f_w_n"),
        ):
            expected = _independent_metrics(y, part[column].to_numpy())
            got = trained.metrics[key][split]
            for name, value in expected.items():
                assert got[name] == pytest.approx(value, rel=1e-12, abs=1e-15), (key, split, name)


def test_baselines_are_what_they_claim(trained: TrainResult, table: pd.DataFrame) -> None:
    pred = trained.predictions.set_index("object_id")
    train_rows = table[table["object_id"].isin(trained.split.train)]
    for oid in trained.split.test[:10]:
        row = table.set_index("object_id").loc[oid]
        nearest = lookup(train_rows, **{f: float(row[f]) for f in FEATURES})
        assert pred.loc[oid, "nearest_lift_force_n"] == nearest.row["lift_force_n"]
        assert pred.loc[oid, "f_w_n"] == pytest.approx(row["weight_n"] / (2 * row["friction_mu"]))


def test_321_network_accuracy_on_synthetic_data(trained: TrainResult) -> None:
    # Measured on this data set (population seed 0, ±1 % noise, split seed 0): max 4.8 %,
    # median 0.79 %. The bound is looser on purpose: it is data dependent; over population
    # seeds 0-9 the max test error was 2.2-4.8 % with this noise and 1.6-6.0 % without noise.
    # Across the OpenBLAS kernels (make golden-spread's 5): max 4.79-4.90 %, median 0.75-0.79 %,
    # R² 0.9970-0.9971 (the chosen restart differs on Haswell), far inside these bounds.
    test = trained.metrics["model"]["test"]
    assert test["max_rel_error"] < 0.08
    assert test["median_rel_error"] < 0.015
    assert test["r2"] > 0.99
    for baseline in ("baseline_nearest", "baseline_f_w"):
        b = trained.metrics[baseline]["test"]
        assert test["median_rel_error"] * 5 < b["median_rel_error"]
        assert test["max_rel_error"] < b["max_rel_error"]


def test_predict_on_training_rows_matches_what_train_reported(
    trained: TrainResult, table: pd.DataFrame
) -> None:
    rows = table[table["object_id"].isin(trained.split.train)]
    out = predict(trained.model, rows)
    reported = trained.predictions.set_index("object_id")["predicted_lift_force_n"]
    got = out.frame.set_index("object_id")["predicted_lift_force_n"]
    rel = (got - reported.loc[got.index]).abs() / reported.loc[got.index]
    assert rel.max() < 0.01
    assert not out.frame["outside_training_range"].any()
    assert out.warnings == []


def test_predict_flags_inputs_outside_the_training_range(trained: TrainResult) -> None:
    lo, hi = trained.training_range["weight_n"]
    features = pd.DataFrame(
        {
            "object_id": ["in", "heavy"],
            "weight_n": [0.5 * (lo + hi), hi * 1.5],
            "deformability_n_per_cm": [40.0, 40.0],
            "damping_ns_per_cm": [5.0, 5.0],
        }
    )
    out = predict(trained.model, features)
    assert list(out.frame["outside_training_range"]) == [False, True]
    assert len(out.warnings) == 1
    assert out.warnings[0].startswith("heavy: outside the training range: weight_n = ")
    assert list(out.frame.columns) == [
        "object_id",
        *FEATURES,
        "predicted_lift_force_n",
        "outside_training_range",
    ]


def test_predict_bad_inputs(trained: TrainResult) -> None:
    good = pd.DataFrame(
        {"weight_n": [30.0], "deformability_n_per_cm": [40.0], "damping_ns_per_cm": [1.0]}
    )
    with pytest.raises(SchemaError, match="damping_ns_per_cm"):
        predict(trained.model, good.drop(columns=["damping_ns_per_cm"]))
    bad = good.assign(deformability_n_per_cm=[math.nan])
    with pytest.raises(InputDataError, match=r"deformability_n_per_cm is NaN .* row 0"):
        predict(trained.model, bad)
    with pytest.raises(UsageError, match="not a lifting-force model"):
        predict(LinearRegression(), good)  # type: ignore[arg-type]
    # column drift is caught by feature_names_in_ when the estimator is called directly
    with pytest.raises(ValueError, match="feature names"):
        trained.model.predict(good.rename(columns={"weight_n": "mass_n"}))


# --- bad index tables ---------------------------------------------------------------------


def test_fewer_rows_than_train_size_needs(table: pd.DataFrame) -> None:
    with pytest.raises(InputDataError) as exc:
        train_model(table.iloc[:40], TrainOptions(train_size=40))
    assert str(exc.value) == (
        "the index table has 40 rows; a training set of 40 needs at least 41 "
        "(40 train + at least 1 test)"
    )
    assert exc.value.exit_code == 65


def test_nan_feature_is_named(table: pd.DataFrame) -> None:
    bad = table.copy()
    bad.loc[3, "damping_ns_per_cm"] = math.nan
    with pytest.raises(InputDataError, match=r"damping_ns_per_cm is NaN .* 1 row\(s\): P03"):
        train_model(bad)


def test_constant_feature_column_is_named(table: pd.DataFrame) -> None:
    bad = table.assign(deformability_n_per_cm=40.0)
    with pytest.raises(InputDataError, match=r"feature deformability_n_per_cm is constant \(40\)"):
        train_model(bad)


def test_missing_column_and_bad_hyperparameters(table: pd.DataFrame) -> None:
    with pytest.raises(SchemaError, match="lift_force_n"):
        train_model(table.drop(columns=["lift_force_n"]))
    with pytest.raises(UsageError, match="hidden"):
        train_model(table, TrainOptions(hidden=(0,)))
    with pytest.raises(UsageError, match="cannot train"):
        train_model(table, TrainOptions(solver="newton", restarts=1))


def test_regression_metrics_small_example() -> None:
    m = regression_metrics(np.array([10.0, 20.0, 40.0]), np.array([11.0, 20.0, 36.0]))
    assert m["max_rel_error"] == pytest.approx(0.1)
    assert m["median_rel_error"] == pytest.approx(0.1)
    assert m["mae_n"] == pytest.approx(5.0 / 3.0)
    # SS_res = 1 + 0 + 16, SS_tot = sum((y - 70/3)**2) = 1400/3
    assert m["r2"] == pytest.approx(1 - 17.0 / (1400.0 / 3.0))
