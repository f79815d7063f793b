"""``train_model`` on a table whose μ varies: the grip form, its split, bound and metadata."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from deformctl.errors import InputDataError
from deformctl.grip.conformal import conformal_margin
from deformctl.grip.fast import Predictor
from deformctl.grip.groups import GRIP_FEATURES
from deformctl.grip.model import GripForceRegressor
from deformctl.model import TrainOptions
from deformctl.train import TrainResult, model_form, model_metadata, train_model
from tests.grip._synthetic import grip_index

NOISE = 0.02


@pytest.fixture(scope="module")
def table() -> pd.DataFrame:
    return grip_index(260, seed=3, noise=NOISE)


@pytest.fixture(scope="module")
def trained(table: pd.DataFrame) -> TrainResult:
    return train_model(table, TrainOptions(train_size=120, calibration_size=60, seed=0, restarts=2))


def test_a_table_whose_mu_varies_trains_the_grip_form(
    table: pd.DataFrame, trained: TrainResult
) -> None:
    assert model_form(table) == "grip"
    assert model_form(table.assign(friction_mu=0.5)) == "paper"
    assert model_form(table.drop(columns=["friction_mu"])) == "paper"
    assert isinstance(trained.model, GripForceRegressor)
    m = trained.metrics
    assert m["form"] == "grip"
    assert m["features"] == list(GRIP_FEATURES)
    assert m["hyperparameters"]["hidden"] == [8, 8]
    assert (m["n_train"], m["n_calibration"], m["n_test"]) == (120, 60, 80)
    assert m["training_friction_mu"] is None
    assert len(trained.split.calibration) == 60
    assert set(trained.split.train).isdisjoint(trained.split.calibration)
    assert set(trained.split.calibration).isdisjoint(trained.split.test)
    for key in ("natural_frequency_rad_s", "damping_ratio", "compression_at_f_w_cm"):
        assert key in m["training_range"]


def test_the_network_recovers_the_known_law_to_its_noise(trained: TrainResult) -> None:
    test = trained.metrics["model"]["test"]
    # noise 2 %: the median |error| of a perfect model is 0.67 x 2 % = 1.35 %
    assert test["median_rel_error"] < 0.02
    assert test["max_rel_error"] < 0.08
    cr = trained.metrics["baseline_constant_ratio"]["test"]["median_rel_error"]
    assert test["median_rel_error"] < cr / 3


def test_calibration_scores_and_the_reported_coverage(trained: TrainResult) -> None:
    scores = np.asarray(trained.calibration_scores)
    assert scores.shape == (60,)
    pred = trained.predictions
    cal = pred[pred["split"] == "calibration"]
    np.testing.assert_allclose(
        scores,
        (cal["lift_force_n"] - cal["predicted_lift_force_n"]) / cal["predicted_lift_force_n"],
    )
    report = trained.metrics["conformal"]
    test = pred[pred["split"] == "test"]
    for p in (0.9, 0.95):
        entry = report[f"{p:g}"]
        q = conformal_margin(scores, p)
        assert entry["margin"] == pytest.approx(q)
        upper = test["predicted_lift_force_n"] * (1 + q)
        assert entry["coverage"] == pytest.approx(np.mean(test["lift_force_n"] <= upper))
        assert entry["mean_margin"] == pytest.approx(np.mean(upper / test["lift_force_n"] - 1))
        # the margin of a 2 % normal noise at P is about 2 % x z_P (1.28, 1.64)
        assert 0.5 * NOISE < entry["margin"] < 3 * NOISE


def test_bound_coverage_on_fresh_objects_drawn_like_the_training_ones(
    trained: TrainResult, tmp_path_factory: pytest.TempPathFactory
) -> None:
    """4000 fresh objects of the same law: the stored bound covers about P of them. Given these
    60 scores, the coverage is the noise law's CDF at the margin; over calibration draws it is
    Beta(k, n + 1 - k) with mean k / (n + 1) >= P (sd 0.038 at P = 0.9, n = 60): it must be
    within 3 sd of P."""
    from deformctl.artifacts.model import save_model

    path = tmp_path_factory.mktemp("m") / "grip.skops"
    save_model(path, trained.model, metadata=model_metadata(trained))
    fresh = grip_index(4000, seed=99, noise=NOISE)
    predictor = Predictor.load(path)
    for p, sd in ((0.9, 0.038), (0.95, 0.027)):
        est = predictor.predict_many(*(fresh[c].to_numpy() for c in GRIP_FEATURES), coverage=p)
        covered = np.mean(fresh["lift_force_n"].to_numpy() <= est.lift_force_upper_n)
        assert covered > p - 3 * sd


def test_a_lambda_below_the_tolerance_is_refused(table: pd.DataFrame) -> None:
    bad = table.copy()
    bad.loc[3, "damping_ns_per_cm"] = -0.2
    with pytest.raises(InputDataError, match=r"damping_ns_per_cm must be >= 0 .* for P003"):
        train_model(bad, TrainOptions(train_size=120, calibration_size=60, restarts=1))
    small = table.copy()
    small.loc[3, "damping_ns_per_cm"] = -0.01  # a fit's noise around 0: counts as 0
    result = train_model(small, TrainOptions(train_size=120, calibration_size=60, restarts=1))
    assert result.metrics["negative_damping_read_as_zero"] == 1
    assert result.metrics["training_range"]["damping_ns_per_cm"][0] >= 0


def test_too_few_rows_for_train_calibration_and_test(table: pd.DataFrame) -> None:
    with pytest.raises(InputDataError, match="120 train \\+ 140 calibration"):
        train_model(table, TrainOptions(train_size=120, calibration_size=140))


def test_the_paper_form_records_its_single_mu(table: pd.DataFrame) -> None:
    ratio = table["lift_force_n"] / table["f_w_n"]  # kept: an L_f below F_w is refused
    single = table.assign(
        friction_mu=0.5, f_w_n=table["weight_n"], lift_force_n=ratio * table["weight_n"]
    )
    result = train_model(single, TrainOptions(train_size=120, seed=0, restarts=1))
    assert result.metrics["form"] == "paper"
    assert result.metrics["training_friction_mu"] == 0.5
    assert result.metrics["conformal"] is None
    assert math.isfinite(result.metrics["model"]["test"]["median_rel_error"])
