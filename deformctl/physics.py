"""Closed forms of the grip shared by the catalog, the lift search and the simulator.

A module of its own, below both the catalog and the simulator, so that each can use them without
importing the other.
"""

from __future__ import annotations

from typing import Any, overload

import numpy as np

from deformctl.units import GRAVITY_M_S2

__all__ = ["damping_ratio", "natural_frequency_rad_s", "rigid_grip_force_n"]


@overload
def rigid_grip_force_n(weight_n: float, friction_mu: float) -> float: ...
@overload
def rigid_grip_force_n(weight_n: np.ndarray, friction_mu: np.ndarray | float) -> np.ndarray: ...
def rigid_grip_force_n(weight_n: Any, friction_mu: Any) -> Any:
    """F_w = W / (2 μ), N: the force two palms need to hold a rigid object of weight W at rest.

    The one place F_w is computed (the lift search starts at it, the index table and the model's
    baseline report it, the simulator's ``f_w_n`` restates it for a spec). Works elementwise on
    arrays.
    """
    return weight_n / (2.0 * friction_mu)


def damping_ratio(weight_n: Any, stiffness_n_per_cm: Any, damping_ns_per_cm: Any) -> Any:
    """ζ = λ / (2 √(D m)) with m = W / g: the lumped object's damping ratio (dimensionless).

    The axis of the paper's landscape: L_f / F_w falls from about 2 (an undamped object, whose
    hanging mode overshoots twice the static sag) towards ``1 + a/g`` as ζ grows. Computed in SI
    (D and λ given in the paper's N/cm and N·s/cm). Works elementwise on arrays.
    """
    mass_kg = np.asarray(weight_n, dtype=np.float64) / GRAVITY_M_S2
    d_n_per_m = np.asarray(stiffness_n_per_cm, dtype=np.float64) * 100.0
    lam_ns_per_m = np.asarray(damping_ns_per_cm, dtype=np.float64) * 100.0
    zeta = lam_ns_per_m / (2.0 * np.sqrt(d_n_per_m * mass_kg))
    return float(zeta) if np.ndim(zeta) == 0 else zeta


def natural_frequency_rad_s(weight_n: Any, stiffness_n_per_cm: Any) -> Any:
    """ω_n = √(D / m) with m = W / g: the lumped object's natural angular frequency, rad/s.

    With :func:`damping_ratio`, the second axis of the simulated landscape: L_f / F_w depends on
    W and D only through ω_n (objects of equal ω_n and ζ lift alike, docs/explanation/model.md).
    Computed in SI (D given in the paper's N/cm). Works elementwise on arrays.
    """
    mass_kg = np.asarray(weight_n, dtype=np.float64) / GRAVITY_M_S2
    d_n_per_m = np.asarray(stiffness_n_per_cm, dtype=np.float64) * 100.0
    omega = np.sqrt(d_n_per_m / mass_kg)
    return float(omega) if np.ndim(omega) == 0 else omega
