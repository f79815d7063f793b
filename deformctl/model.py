"""The lifting-force estimator: (W, D, λ) -> L_f, a network that learns L_f / W (see
:mod:`deformctl.train` for why), and its inputs.

:class:`ScaledTargetRegressor` and :func:`make_model` are what a model file holds
(:mod:`deformctl.artifacts.model` checks and loads it) and what :mod:`deformctl.train` fits; this
module sits below both, so the file layer does not import the training stage.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin, clone
from sklearn.neural_network import MLPRegressor
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.utils.validation import check_is_fitted, validate_data

from deformctl.errors import UsageError
from deformctl.quantities import (
    CALIBRATION_SIZE,
    HIDDEN_SIZE,
    L2_ALPHA,
    LAW_TRAIN_SIZE,
    MAX_ITER,
    RESTARTS,
    SEED,
    TOL,
    TRAIN_SIZE,
)

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


@dataclass(frozen=True)
class TrainOptions:
    """How ``train`` splits the index table and fits the network (frozen; checked when built,
    each number by its :mod:`deformctl.quantities` rule; :func:`deformctl.train.train_model`).

    Attributes:
        hidden: hidden layer sizes (``--hidden``); None: the form's default, ``(2,)`` (the
            paper's) or :data:`deformctl.grip.model.DEFAULT_GRIP_HIDDEN`.
        train_size: training rows (``--train-size``; the paper's 40).
        calibration_size: rows held out to calibrate the conformal bound (0: no bound).
        seed: seeds the split and the restarts' initial weights (``--seed``).
        restarts: seeded initialisations; the best on the training rows is kept.
        max_iter, solver, activation, alpha, tol: the ``MLPRegressor``'s (a bad solver or
            activation name is refused by scikit-learn as the network is fitted).
        target: the paper form's target: ``"ratio"`` (L_f / W) or ``"direct"`` (L_f).
        law_train_size: with ``train --laws``, at most this many rows train each other law's
            network (``--law-train-size``; a law with fewer rows trains on every row not
            calibrating); None: ``train_size`` rows, as the Kelvin–Voigt network.

    Raises:
        UsageError: a number outside its rule, or an unknown target (exit 2).
    """

    hidden: tuple[int, ...] | None = None
    train_size: int = 40
    calibration_size: int = 0
    seed: int = 0
    restarts: int = 8
    max_iter: int = DEFAULT_MAX_ITER
    solver: str = DEFAULT_SOLVER
    activation: str = DEFAULT_ACTIVATION
    alpha: float = DEFAULT_ALPHA
    tol: float = DEFAULT_TOL
    target: TargetMode = "ratio"
    law_train_size: int | None = None

    def __post_init__(self) -> None:
        if self.hidden == ():
            raise UsageError("--hidden needs at least one layer size")
        for size in self.hidden or ():
            HIDDEN_SIZE.check(size)
        TRAIN_SIZE.check(self.train_size)
        CALIBRATION_SIZE.check(self.calibration_size)
        SEED.check(self.seed)
        RESTARTS.check(self.restarts)
        MAX_ITER.check(self.max_iter)
        L2_ALPHA.check(self.alpha)
        TOL.check(self.tol)
        if self.law_train_size is not None:
            LAW_TRAIN_SIZE.check(self.law_train_size)
        if self.target not in ("ratio", "direct"):
            raise UsageError(f"target must be 'ratio' or 'direct', got {self.target!r}")


#: The command's defaults, for signatures.
DEFAULT_TRAIN = TrainOptions()


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


def scaled_mlp(options: TrainOptions, hidden: tuple[int, ...], random_state: int) -> Pipeline:
    """``Pipeline(StandardScaler, MLPRegressor)``: the network inside every deformctl model, with
    ``hidden`` layers, seeded by ``random_state``, fitted as ``options`` say."""
    o = options
    mlp = MLPRegressor(
        hidden_layer_sizes=tuple(int(h) for h in hidden),
        activation=o.activation,
        solver=o.solver,
        alpha=o.alpha,
        max_iter=o.max_iter,
        tol=o.tol,
        random_state=random_state,
    )
    return Pipeline([("scale", StandardScaler()), ("mlp", mlp)])


def make_model(
    options: TrainOptions = DEFAULT_TRAIN, *, random_state: int = 0
) -> ScaledTargetRegressor:
    """An unfitted lifting-force model: ``ScaledTargetRegressor(Pipeline(StandardScaler, MLP))``
    with ``options``' network (its hidden layers by default :data:`DEFAULT_HIDDEN`).

    ``options.target`` ``"ratio"`` learns ``L_f / W`` (W is feature 0); ``"direct"`` learns L_f
    itself.
    """
    core = scaled_mlp(options, options.hidden or DEFAULT_HIDDEN, random_state)
    return ScaledTargetRegressor(core, scale_index=0 if options.target == "ratio" else None)
