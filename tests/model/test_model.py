"""deformctl.model: the estimator a model file holds. ScaledTargetRegressor on known linear
targets and scikit-learn's estimator checks (moved here from tests/train/test_train.py), and the
settings make_model puts into the network."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from sklearn.linear_model import LinearRegression
from sklearn.utils.estimator_checks import parametrize_with_checks

from deformctl.model import (
    DEFAULT_ACTIVATION,
    DEFAULT_ALPHA,
    DEFAULT_HIDDEN,
    DEFAULT_MAX_ITER,
    DEFAULT_SOLVER,
    DEFAULT_TOL,
    FEATURES,
    ScaledTargetRegressor,
    TrainOptions,
    make_model,
)


def test_scaled_target_regressor_learns_the_ratio_exactly() -> None:
    rng = np.random.default_rng(0)
    X = pd.DataFrame({"w": rng.uniform(1, 5, 30), "z": rng.uniform(0, 1, 30)})
    y = X["w"] * (2.0 + 3.0 * X["z"])  # y / w is linear in z: a linear model recovers it
    m = ScaledTargetRegressor(LinearRegression(), scale_index=0).fit(X, y)
    np.testing.assert_allclose(m.predict(X), y, rtol=1e-12)
    np.testing.assert_allclose(m.regressor_.coef_, [0.0, 3.0], atol=1e-12)
    np.testing.assert_array_equal(m.feature_min_, X.min().to_numpy())
    with pytest.raises(ValueError, match="must be > 0"):
        m.predict(X.assign(w=-1.0))


@parametrize_with_checks([ScaledTargetRegressor(LinearRegression(), scale_index=None)])
def test_sklearn_estimator_contract(estimator: object, check: object) -> None:
    check(estimator)  # type: ignore[operator]


def test_without_scaling_the_target_is_learned_as_is() -> None:
    rng = np.random.default_rng(1)
    X = np.column_stack([rng.uniform(-5, 5, 20), rng.uniform(0, 1, 20)])  # w may be <= 0 here
    y = 2.0 + 3.0 * X[:, 1]
    m = ScaledTargetRegressor(LinearRegression(), scale_index=None).fit(X, y)
    np.testing.assert_allclose(m.predict(X), y, rtol=1e-12)
    np.testing.assert_allclose(m.regressor_.coef_, [0.0, 3.0], atol=1e-12)
    with pytest.raises(ValueError, match="scale_index 2 is out of range"):
        ScaledTargetRegressor(LinearRegression(), scale_index=2).fit(X, y)


def test_make_model_puts_its_settings_into_the_network() -> None:
    assert FEATURES == ("weight_n", "deformability_n_per_cm", "damping_ns_per_cm")
    ratio = make_model()
    assert ratio.scale_index == 0  # W is feature 0: the network learns L_f / W
    assert FEATURES[ratio.scale_index] == "weight_n"
    assert [name for name, _ in ratio.regressor.steps] == ["scale", "mlp"]
    mlp = ratio.regressor.named_steps["mlp"]
    assert (mlp.hidden_layer_sizes, mlp.activation, mlp.solver) == (
        DEFAULT_HIDDEN,
        DEFAULT_ACTIVATION,
        DEFAULT_SOLVER,
    )
    assert (mlp.alpha, mlp.max_iter, mlp.tol, mlp.random_state) == (
        DEFAULT_ALPHA,
        DEFAULT_MAX_ITER,
        DEFAULT_TOL,
        0,
    )
    direct = make_model(TrainOptions(hidden=(4, 3), target="direct", alpha=0.5), random_state=7)
    assert direct.scale_index is None
    inner = direct.regressor.named_steps["mlp"]
    assert (inner.hidden_layer_sizes, inner.random_state, inner.alpha) == ((4, 3), 7, 0.5)
