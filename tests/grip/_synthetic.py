"""Synthetic grip data with a known law: L_f = F_w · r(ω_n, ζ) · (1 + ε).

``r`` is shaped like the simulator's landscape (2 undamped, about 1.1 heavily damped, lower at
high ω_n); ε is a seeded normal noise of a stated standard deviation standing in for the
search's tolerance and the object's size. Inputs come from :func:`deformctl.population.
grip_population` (the bundled model's law).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from deformctl.grip.groups import group_values
from deformctl.population import grip_population


def ratio(omega: np.ndarray, zeta: np.ndarray) -> np.ndarray:
    return 1.11 + (0.9 - 0.1 * np.log10(omega / 10.0)) / (1.0 + (zeta / 0.6) ** 1.3)


def grip_index(n: int, seed: int, noise: float = 0.0, prefix: str = "P") -> pd.DataFrame:
    """An index table of ``n`` objects whose L_f follows the known law (times 1 + N(0, noise²))."""
    cat = grip_population(n, seed=seed, id_prefix=prefix)
    w = cat["weight_n"].to_numpy()
    d = cat["material_stiffness_n_per_cm"].to_numpy()
    lam = cat["material_damping_ns_per_cm"].to_numpy()
    mu = cat["friction_mu"].to_numpy()
    omega, zeta = group_values(w, d, lam)
    f_w = w / (2 * mu)
    eps = np.random.default_rng(seed + 7919).normal(0.0, noise, n) if noise else np.zeros(n)
    return pd.DataFrame(
        {
            "object_id": cat["object_id"],
            "weight_n": w,
            "deformability_n_per_cm": d,
            "damping_ns_per_cm": lam,
            "lift_force_n": f_w * ratio(omega, zeta) * (1 + eps),
            "friction_mu": mu,
            "f_w_n": f_w,
            "converged": True,
        }
    )
