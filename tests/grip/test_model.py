"""The grip model's form: F_w carries μ and the scale, a network learns r(ω_n, ζ)."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.neural_network import MLPRegressor
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler

from deformctl.grip.groups import group_values, groups
from deformctl.grip.model import GripForceRegressor


def synthetic_ratio(omega: np.ndarray, zeta: np.ndarray) -> np.ndarray:
    """A landscape shaped like the simulator's: 2 undamped, 1.11 heavily damped, softer at
    high ω_n."""
    return 1.11 + (0.9 - 0.1 * np.log10(omega / 10.0)) / (1.0 + (zeta / 0.6) ** 1.3)


def synthetic_objects(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    X = np.column_stack(
        [
            np.exp(rng.uniform(np.log(0.5), np.log(80), n)),
            np.exp(rng.uniform(np.log(5), np.log(60), n)),
            np.exp(rng.uniform(np.log(0.01), np.log(15.01), n)) - 0.01,
            rng.uniform(0.2, 1.0, n),
        ]
    )
    omega, zeta = group_values(X[:, 0], X[:, 1], X[:, 2])
    y = synthetic_ratio(omega, zeta) * X[:, 0] / (2 * X[:, 3])
    return X, y


def fitted(X: np.ndarray, y: np.ndarray) -> GripForceRegressor:
    mlp = MLPRegressor(
        hidden_layer_sizes=(8, 8), solver="lbfgs", max_iter=3000, tol=1e-8, random_state=0
    )
    return GripForceRegressor(Pipeline([("scale", StandardScaler()), ("mlp", mlp)])).fit(X, y)


def test_learns_a_known_landscape_and_carries_mu_exactly() -> None:
    X, y = synthetic_objects(300, seed=1)
    model = fitted(X, y)
    X_new, y_new = synthetic_objects(200, seed=2)
    rel = np.abs(model.predict(X_new) / y_new - 1)
    assert np.median(rel) < 0.005
    assert rel.max() < 0.03
    # μ only enters through F_w = W / (2 μ): the same object at μ 0.25 and 1.0 differs by 4x
    a, b = X_new[:5].copy(), X_new[:5].copy()
    a[:, 3], b[:, 3] = 0.25, 1.0
    np.testing.assert_allclose(model.predict(a) / model.predict(b), 4.0, rtol=1e-12)


def test_objects_with_the_same_groups_get_the_same_ratio() -> None:
    X, y = synthetic_objects(100, seed=3)
    model = fitted(X, y)
    # W x4 and D x4 keep ω_n; λ x4 keeps ζ: the ratio L_f / F_w is the same
    a = np.array([[2.0, 10.0, 0.3, 0.5]])
    b = a * np.array([[4.0, 4.0, 4.0, 1.0]])
    np.testing.assert_allclose(groups(a), groups(b), rtol=1e-12)
    np.testing.assert_allclose(model.predict_ratio(a), model.predict_ratio(b), rtol=1e-12)
    assert model.predict(b)[0] == pytest.approx(4 * model.predict(a)[0], rel=1e-12)


@pytest.mark.parametrize(
    ("row", "match"),
    [
        ([1.0, 10.0, -0.06, 0.5], "λ must be >= 0"),
        ([1.0, 0.0, 0.1, 0.5], "must be > 0"),
        ([1.0, 10.0, 0.1, 0.0], "must be > 0"),
        ([np.nan, 10.0, 0.1, 0.5], "NaN"),
    ],
)
def test_impossible_inputs_are_refused(row: list[float], match: str) -> None:
    X, y = synthetic_objects(50, seed=4)
    model = fitted(X, y)
    with pytest.raises(ValueError, match=match):
        model.predict(np.array([row]))


def test_a_fitted_lambda_slightly_below_zero_counts_as_zero() -> None:
    X, y = synthetic_objects(50, seed=5)
    model = fitted(X, y)
    zero = model.predict(np.array([[3.0, 10.0, 0.0, 0.5]]))
    np.testing.assert_array_equal(model.predict(np.array([[3.0, 10.0, -0.04, 0.5]])), zero)
