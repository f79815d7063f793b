"""A fitted lifting-force model as plain numbers: what the numpy-only predictor evaluates.

``train`` stores :func:`export_model`'s dict in the model file's metadata (key
``"numpy_model"``), next to the scikit-learn estimator. :mod:`deformctl.grip.fast` evaluates it
with a few numpy operations, the same operations in the same order as scikit-learn's
``StandardScaler.transform`` and ``MLPRegressor.predict``, so both give the same numbers (tested
to the last bits), without importing scikit-learn, skops or pandas (a CLI call in well under a
second, a library call in microseconds).

The dict (JSON; floats written by ``json.dumps`` read back bit-identical)::

    {"form": "grip" | "paper", "features": [...], "activation": "tanh",
     "scaler_mean": [...], "scaler_scale": [...],
     "weights": [[[...], ...], ...], "biases": [[...], ...],
     "zeta_shift": 0.01,          # grip: groups log10 ω_n, log10(ζ + ζ_0); target log(L_f / F_w)
     "scale_index": 0 | None}     # paper: target L_f / X[scale_index] (or L_f itself)
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["export_model"]

#: The activations the numpy predictor evaluates.
EXPORT_ACTIVATIONS = ("tanh", "relu", "logistic", "identity")


def _core(pipe: Any) -> dict[str, Any]:
    scaler, mlp = pipe[0], pipe[-1]
    if mlp.activation not in EXPORT_ACTIVATIONS:
        raise ValueError(f"cannot export activation {mlp.activation!r}")
    return {
        "activation": str(mlp.activation),
        "scaler_mean": [float(v) for v in scaler.mean_],
        "scaler_scale": [float(v) for v in scaler.scale_],
        "weights": [np.asarray(w, dtype=np.float64).tolist() for w in mlp.coefs_],
        "biases": [np.asarray(b, dtype=np.float64).tolist() for b in mlp.intercepts_],
    }


def export_model(model: Any) -> dict[str, Any]:
    """The numpy form of a fitted :class:`~deformctl.grip.model.GripForceRegressor` or of the
    paper's ``ScaledTargetRegressor`` (both wrap ``Pipeline(StandardScaler, MLPRegressor)``).

    Raises:
        ValueError: another kind of model, or an activation the predictor does not evaluate.
    """
    from deformctl.grip.model import GripForceRegressor

    if isinstance(model, GripForceRegressor):
        return {
            "form": "grip",
            "features": [str(c) for c in model.feature_names_in_],
            "zeta_shift": float(model.zeta_shift),
            **_core(model.regressor_),
        }
    if type(model).__name__ == "ScaledTargetRegressor":
        return {
            "form": "paper",
            "features": [str(c) for c in model.feature_names_in_],
            "scale_index": None if model.scale_index is None else int(model.scale_index),
            **_core(model.regressor_),
        }
    raise ValueError(f"cannot export a {type(model).__name__}")
