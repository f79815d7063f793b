"""Closed forms of the grip shared by the catalog, the lift search and the simulator.

A module of its own, below both the catalog and the simulator, so that each can use them without
importing the other.
"""

from __future__ import annotations

from typing import Any, overload

import numpy as np

__all__ = ["rigid_grip_force_n"]


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
