"""The lifting-force estimator: (W, D, λ) -> L_f, a network that learns L_f / W (see
:mod:`deformctl.train` for why), and its inputs.

:class:`ScaledTargetRegressor` and :func:`make_model` are what a model file holds
(:mod:`deformctl.artifacts.model` checks and loads it) and what :mod:`deformctl.train` fits; this
module sits below both, so the file layer does not import the training stage.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin, clone
from sklearn.neural_network import MLPRegressor
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.utils.validation import check_is_fitted, validate_data

#: The model's inputs, in order: W (N), D (N/cm), λ (N·s/cm).
FEATURES: tuple[str, ...] = ("weight_n", "deformability_n_per_cm", "damping_ns_per_cm")
#: The model's output: the minimum lifting force L_f, N.
TARGET = "lift_force_n"

#: The network's defaults (the paper's 3-2-1 network, and our solver choices; see
#: :mod:`deformctl.train`).
DEFAULT_HIDDEN: tuple[int, ...] = (2,)
DEFAULT_ACTIVATION = "tanh"
DEFAULT_SOLVER = "lbfgs"
DEFAULT_ALPHA = 1e-4
DEFAULT_MAX_ITER = 3000
DEFAULT_TOL = 1e-6

TargetMode = Literal["ratio", "direct"]


class ScaledTargetRegressor(RegressorMixin, BaseEstimator):
    """Fit a regressor to ``y / x_s`` and predict ``regressor.predict(X) * x_s``.

    ``x_s`` is the input column ``scale_index`` (for the lifting-force model: the weight W, so the
    wrapped network learns ``L_f / W``). With ``scale_index=None`` the target is used as is. The
    wrapped regressor sees ``X`` unchanged (a DataFrame stays a DataFrame, so a ``Pipeline``
    inside records ``feature_names_in_`` and catches column drift).

    Parameters:
        regressor: the estimator to fit to the scaled target; default
            ``Pipeline(StandardScaler, MLPRegressor)`` with scikit-learn's defaults.
        scale_index: position of the scaling column in ``X``, or None.

    Attributes:
        regressor_: the fitted clone of ``regressor``.
        n_features_in_, feature_names_in_: as in scikit-learn.
        feature_min_, feature_max_: ``[n_features]`` per-feature minimum and maximum of the
            training inputs (the training range).

    Example:
        >>> X = np.array([[1.0, 0.0], [2.0, 1.0], [3.0, 0.0], [4.0, 1.0]])
        >>> from sklearn.linear_model import LinearRegression
        >>> m = ScaledTargetRegressor(LinearRegression(), scale_index=0).fit(X, 3.0 * X[:, 0])
        >>> np.round(m.predict([[10.0, 0.5]]), 6).tolist()
        [30.0]
    """

    def __init__(self, regressor: Any = None, *, scale_index: int | None = 0) -> None:
        self.regressor = regressor
        self.scale_index = scale_index

    def _scale(self, X_arr: np.ndarray) -> np.ndarray:
        if self.scale_index is None:
            return np.ones(X_arr.shape[0])
        s = X_arr[:, self.scale_index]
        if not np.all(s > 0):
            raise ValueError(f"scaling column {self.scale_index} must be > 0 everywhere")
        return s

    def fit(self, X: Any, y: Any) -> ScaledTargetRegressor:
        """Fit on ``X`` ``[n, n_features]`` and ``y`` ``[n]``; returns ``self``."""
        X_arr, y_arr = validate_data(self, X, y, y_numeric=True, reset=True)
        if self.scale_index is not None and not 0 <= self.scale_index < X_arr.shape[1]:
            raise ValueError(f"scale_index {self.scale_index} is out of range")
        scale = self._scale(X_arr)
        base = self.regressor
        if base is None:
            base = Pipeline([("scale", StandardScaler()), ("mlp", MLPRegressor())])
        self.regressor_ = clone(base)
        self.regressor_.fit(X, np.asarray(y_arr, dtype=np.float64) / scale)
        self.feature_min_ = X_arr.min(axis=0).astype(np.float64)
        self.feature_max_ = X_arr.max(axis=0).astype(np.float64)
        return self

    def predict(self, X: Any) -> np.ndarray:
        """Predict ``[n]`` targets for ``X`` ``[n, n_features]``."""
        check_is_fitted(self)
        X_arr = validate_data(self, X, reset=False)
        scale = self._scale(X_arr)
        inner = self.regressor_.predict(X)
        return np.asarray(inner, dtype=np.float64).reshape(-1) * scale


def scaled_mlp(
    *,
    hidden: tuple[int, ...],
    activation: str,
    solver: str,
    alpha: float,
    max_iter: int,
    tol: float,
    random_state: int,
) -> Pipeline:
    """``Pipeline(StandardScaler, MLPRegressor)``: the network inside every deformctl model."""
    mlp = MLPRegressor(
        hidden_layer_sizes=tuple(hidden),
        activation=activation,
        solver=solver,
        alpha=alpha,
        max_iter=max_iter,
        tol=tol,
        random_state=random_state,
    )
    return Pipeline([("scale", StandardScaler()), ("mlp", mlp)])


def make_model(
    *,
    hidden: tuple[int, ...] = DEFAULT_HIDDEN,
    activation: str = DEFAULT_ACTIVATION,
    solver: str = DEFAULT_SOLVER,
    alpha: float = DEFAULT_ALPHA,
    max_iter: int = DEFAULT_MAX_ITER,
    tol: float = DEFAULT_TOL,
    random_state: int = 0,
    target: TargetMode = "ratio",
) -> ScaledTargetRegressor:
    """An unfitted lifting-force model: ``ScaledTargetRegressor(Pipeline(StandardScaler, MLP))``.

    ``target="ratio"`` learns ``L_f / W`` (W is feature 0); ``"direct"`` learns L_f itself.
    """
    core = scaled_mlp(
        hidden=hidden,
        activation=activation,
        solver=solver,
        alpha=alpha,
        max_iter=max_iter,
        tol=tol,
        random_state=random_state,
    )
    return ScaledTargetRegressor(core, scale_index=0 if target == "ratio" else None)
