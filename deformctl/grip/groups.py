"""The grip model's inputs: the object's attributes and the dimensionless groups it learns from.

The simulated lifting force is ``L_f = F_w · r(ω_n, ζ)`` with ``F_w = W / (2 μ)`` and a ratio
``r`` that depends on the object only through two groups (measured, docs/explanation/model.md):

* the natural frequency of the lumped object, ``ω_n = √(D / m)``, ``m = W / g`` (rad/s; the
  lift protocol's fixed time scales make it dimensionless), and
* its damping ratio ``ζ = λ / (2 √(D m))``.

The model's regressor sees ``log10 ω_n`` and ``log10(ζ + ζ_0)``: both span decades over the
bundled ranges (ω_n 8-340 rad/s, ζ 0-150), the logarithm spreads them evenly, and the shift
``ζ_0`` keeps ``ζ = 0`` finite (below ``ζ_0`` the ratio no longer changes).

Numpy only: the fast predictor (:mod:`deformctl.grip.fast`) computes the same groups without
scikit-learn or pandas.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from deformctl.physics import damping_ratio, natural_frequency_rad_s

__all__ = [
    "GRIP_FEATURES",
    "GROUP_NAMES",
    "NEGATIVE_DAMPING_TOLERANCE_NS_PER_CM",
    "ZETA_SHIFT",
    "group_values",
    "groups",
]

#: The grip model's inputs, in order: W (N), D (N/cm), λ (N·s/cm), μ.
GRIP_FEATURES: tuple[str, str, str, str] = (
    "weight_n",
    "deformability_n_per_cm",
    "damping_ns_per_cm",
    "friction_mu",
)
#: The regressor's inputs, in order.
GROUP_NAMES: tuple[str, str] = ("log10_natural_frequency_rad_s", "log10_damping_ratio_shifted")
#: ζ_0 of ``log10(ζ + ζ_0)``.
ZETA_SHIFT = 0.01
#: A fitted λ this far below 0 (N·s/cm) is read as 0, "no measurable damping": ``characterize``
#: returns λ within -0.018..+0.052 N·s/cm of the truth for undamped simulated objects (600
#: objects of the grip population). Below it, λ is refused.
NEGATIVE_DAMPING_TOLERANCE_NS_PER_CM = 0.05


def group_values(
    weight_n: Any, deformability_n_per_cm: Any, damping_ns_per_cm: Any
) -> tuple[np.ndarray, np.ndarray]:
    """``(ω_n [n], ζ [n])``: the two groups in their own units (rad/s, dimensionless).

    λ < 0 (a fit's noise around 0, :data:`NEGATIVE_DAMPING_TOLERANCE_NS_PER_CM`) counts as 0.
    """
    omega = np.atleast_1d(natural_frequency_rad_s(weight_n, deformability_n_per_cm))
    lam = np.maximum(np.asarray(damping_ns_per_cm, dtype=np.float64), 0.0)
    zeta = np.atleast_1d(damping_ratio(weight_n, deformability_n_per_cm, lam))
    return np.asarray(omega, dtype=np.float64), np.asarray(zeta, dtype=np.float64)


def groups(X: Any, zeta_shift: float = ZETA_SHIFT) -> np.ndarray:
    """``[n, 2]`` regressor inputs (:data:`GROUP_NAMES`) of ``X`` ``[n, 4]`` (W, D, λ, μ).

    The caller validates ``X`` (W > 0, D > 0, λ >= -tolerance, finite); μ is not used here (it
    enters through F_w).
    """
    a = np.asarray(X, dtype=np.float64)
    omega, zeta = group_values(a[:, 0], a[:, 1], a[:, 2])
    return np.column_stack([np.log10(omega), np.log10(zeta + zeta_shift)])
