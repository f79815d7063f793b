"""The grip model: L_f = F_w · r(ω_n, ζ), with r learned by a small network from two groups.

:class:`GripForceRegressor` is a scikit-learn regressor over the object's attributes
``X = [W, D, λ, μ]`` (:data:`~deformctl.grip.groups.GRIP_FEATURES`, paper units). It

1. computes the rigid-object force ``F_w = W / (2 μ)`` (:func:`deformctl.physics.
   rigid_grip_force_n`) and the two dimensionless groups ``[log10 ω_n, log10(ζ + ζ_0)]``
   (:func:`deformctl.grip.groups.groups`),
2. fits the wrapped regressor (default ``Pipeline(StandardScaler, MLPRegressor)``) to
   ``log(L_f / F_w)`` over the groups, and
3. predicts ``F_w · exp(regressor(groups))``.

Why this form (the measurements are in docs/explanation/model.md): in the simulator, L_f / F_w
of one object does not change with μ (to the search's tolerance), and depends on W and D only
through ω_n; so μ and the scale of the force are carried exactly by F_w, and the network only
has to learn a smooth function of two variables, which it can do from a few hundred objects and
which stays right between and beyond the training points in W and μ. The logarithm makes the
fit's squared error a relative error, the measure the model is judged by.

Example:
    >>> import numpy as np
    >>> from sklearn.linear_model import LinearRegression
    >>> from deformctl.physics import rigid_grip_force_n
    >>> X = np.array([[2.0, 10.0, 0.0, 0.5], [4.0, 10.0, 1.0, 1.0], [8.0, 40.0, 0.2, 0.3]])
    >>> y = 1.5 * rigid_grip_force_n(X[:, 0], X[:, 3])  # L_f = 1.5 F_w
    >>> m = GripForceRegressor(LinearRegression()).fit(X, y)
    >>> np.round(m.predict([[10.0, 20.0, 0.5, 0.25]]), 6).tolist()  # 1.5 * 10 / 0.5
    [30.0]
"""

from __future__ import annotations

from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin, clone
from sklearn.neural_network import MLPRegressor
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.utils.validation import check_is_fitted, validate_data

from deformctl.grip.groups import (
    GRIP_FEATURES,
    NEGATIVE_DAMPING_TOLERANCE_NS_PER_CM,
    ZETA_SHIFT,
    groups,
)
from deformctl.model import DEFAULT_TRAIN, TrainOptions, scaled_mlp
from deformctl.physics import rigid_grip_force_n

__all__ = ["DEFAULT_GRIP_HIDDEN", "GripForceRegressor", "check_grip_inputs", "make_grip_model"]

#: The grip model's default hidden layers (the paper's network has ``(2,)``).
DEFAULT_GRIP_HIDDEN: tuple[int, ...] = (8, 8)


def check_grip_inputs(X: np.ndarray) -> None:
    """ValueError unless every row has W > 0, D > 0, λ >= -0.05 and μ > 0 (all finite).

    λ between -0.05 N·s/cm and 0 (:data:`~deformctl.grip.groups.
    NEGATIVE_DAMPING_TOLERANCE_NS_PER_CM`) is a fit's noise around 0 and counts as 0.
    """
    if X.ndim != 2 or X.shape[1] != len(GRIP_FEATURES):
        raise ValueError(f"expected [n, {len(GRIP_FEATURES)}] inputs {GRIP_FEATURES}")
    if not np.all(np.isfinite(X)):
        raise ValueError("inputs must be finite")
    if not (np.all(X[:, 0] > 0) and np.all(X[:, 1] > 0) and np.all(X[:, 3] > 0)):
        raise ValueError("W, D and μ must be > 0")
    if not np.all(X[:, 2] >= -NEGATIVE_DAMPING_TOLERANCE_NS_PER_CM):
        raise ValueError(f"λ must be >= 0 (or at least -{NEGATIVE_DAMPING_TOLERANCE_NS_PER_CM:g})")


class GripForceRegressor(RegressorMixin, BaseEstimator):
    """Learn ``log(L_f / F_w)`` from ``[log10 ω_n, log10(ζ + ζ_0)]``; predict ``L_f``.

    Parameters:
        regressor: the estimator fitted on the groups; default
            ``Pipeline(StandardScaler, MLPRegressor)`` with scikit-learn's defaults.
        zeta_shift: ζ_0 (:data:`~deformctl.grip.groups.ZETA_SHIFT`).

    Attributes:
        regressor_: the fitted clone of ``regressor``.
        n_features_in_, feature_names_in_: as in scikit-learn (4 features).
        feature_min_, feature_max_: ``[4]`` range of the training inputs.
        group_min_, group_max_: ``[2]`` range of the training groups.
    """

    def __init__(self, regressor: Any = None, *, zeta_shift: float = ZETA_SHIFT) -> None:
        self.regressor = regressor
        self.zeta_shift = zeta_shift

    def fit(self, X: Any, y: Any) -> GripForceRegressor:
        """Fit on ``X`` ``[n, 4]`` (W, D, λ, μ) and ``y`` ``[n]`` (L_f, N, > 0)."""
        X_arr, y_arr = validate_data(self, X, y, y_numeric=True, reset=True)
        check_grip_inputs(X_arr)
        y_arr = np.asarray(y_arr, dtype=np.float64)
        if not (np.all(np.isfinite(y_arr)) and np.all(y_arr > 0)):
            raise ValueError("lifting forces must be finite and > 0")
        g = groups(X_arr, self.zeta_shift)
        target = np.log(y_arr / rigid_grip_force_n(X_arr[:, 0], X_arr[:, 3]))
        base = self.regressor
        if base is None:
            base = Pipeline([("scale", StandardScaler()), ("mlp", MLPRegressor())])
        self.regressor_ = clone(base)
        self.regressor_.fit(g, target)
        self.feature_min_ = X_arr.min(axis=0).astype(np.float64)
        self.feature_max_ = X_arr.max(axis=0).astype(np.float64)
        self.group_min_ = g.min(axis=0).astype(np.float64)
        self.group_max_ = g.max(axis=0).astype(np.float64)
        return self

    def predict_ratio(self, X: Any) -> np.ndarray:
        """``[n]`` predicted L_f / F_w."""
        check_is_fitted(self)
        X_arr = validate_data(self, X, reset=False)
        check_grip_inputs(X_arr)
        inner = self.regressor_.predict(groups(X_arr, self.zeta_shift))
        return np.exp(np.asarray(inner, dtype=np.float64).reshape(-1))

    def predict(self, X: Any) -> np.ndarray:
        """``[n]`` predicted L_f, N."""
        X_arr = np.asarray(validate_data(self, X, reset=False), dtype=np.float64)
        return self.predict_ratio(X) * rigid_grip_force_n(X_arr[:, 0], X_arr[:, 3])


def make_grip_model(
    options: TrainOptions = DEFAULT_TRAIN, *, random_state: int = 0
) -> GripForceRegressor:
    """An unfitted grip model: ``GripForceRegressor(Pipeline(StandardScaler, MLP))`` with
    ``options``' network (its hidden layers by default :data:`DEFAULT_GRIP_HIDDEN`)."""
    return GripForceRegressor(
        scaled_mlp(options, options.hidden or DEFAULT_GRIP_HIDDEN, random_state)
    )
