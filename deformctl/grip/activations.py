"""The network's activation functions, on numpy arrays (in place) and on plain floats, as
scikit-learn's MLP computes them (:mod:`deformctl.grip.fast` evaluates the exported network)."""

from __future__ import annotations

import math

import numpy as np


def _activation_scalar(name: str, x: float) -> float:
    if name == "tanh":
        return math.tanh(x)
    if name == "relu":
        return max(x, 0.0)
    if name == "logistic":
        return 1.0 / (1.0 + math.exp(-x)) if x >= -700 else 0.0
    return x


def _activation(name: str, x: np.ndarray) -> np.ndarray:
    if name == "tanh":
        return np.tanh(x, out=x)
    if name == "relu":
        return np.maximum(x, 0, out=x)
    if name == "logistic":
        return np.divide(1.0, 1.0 + np.exp(-x, out=x), out=x)
    return x
