"""A synthetic index table whose lifting force is a known function of (W, D, λ).

The objects are the paper's population (:func:`deformctl.population.make_population`: W 20-60 N,
D 30-50 N/cm, λ 0-13 N·s/cm, μ = 0.5) and their "measured" coefficients are the catalog's true
material values. The minimum lifting force is not simulated but given by a smooth formula shaped
like the physics, the rigid-object force F_w = W / (2 μ) plus a surplus that grows with W / D and
shrinks with damping::

    L_f = F_w * (1 + 0.6 * W / D * (0.5 + 0.5 * exp(-λ / 4 N·s/cm)))

times a seeded uniform ±``noise_rel`` standing in for the tolerance of the lifting-force search.
It trains the 3-2-1 network on as many rows as the paper's (40 of 73) in a second, without the
simulator: the model tests and the golden run's reference network
(:mod:`deformctl.repro.golden`) use it. ``examples/synthetic_index.py`` writes the same numbers
as the coefficients and lift-results files of the CLI.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from deformctl.catalog import catalog_objects
from deformctl.physics import rigid_grip_force_n
from deformctl.population import PAPER_POPULATION_SIZE, make_population

#: Relative amplitude of the uniform noise on L_f.
NOISE_REL = 0.01


def synthetic_lift_force_n(
    weight_n: np.ndarray,
    deformability_n_per_cm: np.ndarray,
    damping_ns_per_cm: np.ndarray,
    friction_mu: np.ndarray,
) -> np.ndarray:
    """The noise-free L_f (N) of the formula in the module docstring, element-wise."""
    w = np.asarray(weight_n, dtype=np.float64)
    d = np.asarray(deformability_n_per_cm, dtype=np.float64)
    lam = np.asarray(damping_ns_per_cm, dtype=np.float64)
    f_w = rigid_grip_force_n(w, np.asarray(friction_mu, dtype=np.float64))
    return f_w * (1.0 + 0.6 * w / d * (0.5 + 0.5 * np.exp(-lam / 4.0)))


def synthetic_index_table(
    seed: int = 0, n: int = PAPER_POPULATION_SIZE, noise_rel: float = NOISE_REL
) -> pd.DataFrame:
    """An index table of ``n`` objects with the known L_f of the module docstring.

    Args:
        seed: seeds the population (``make_population(n, seed=seed)``) and, as ``seed + 1000``,
            the noise.
        n: number of objects.
        noise_rel: amplitude of the uniform multiplicative noise on L_f (0: none).

    Returns:
        ``[n]`` rows: ``object_id``, ``weight_n``, ``deformability_n_per_cm``,
        ``damping_ns_per_cm``, ``lift_force_n``, ``friction_mu``, ``f_w_n``, ``converged``.
    """
    objects = catalog_objects(make_population(n, seed=seed))  # the catalog module reads columns
    w = np.array([o.weight_n for o in objects], dtype=np.float64)
    d = np.array([o.material_stiffness_n_per_cm for o in objects], dtype=np.float64)
    lam = np.array([o.material_damping_ns_per_cm for o in objects], dtype=np.float64)
    mu = np.array([o.friction_mu for o in objects], dtype=np.float64)
    lift = synthetic_lift_force_n(w, d, lam, mu)
    lift *= 1.0 + noise_rel * np.random.default_rng(seed + 1000).uniform(-1.0, 1.0, n)
    return pd.DataFrame(
        {
            "object_id": [o.object_id for o in objects],
            "weight_n": w,
            "deformability_n_per_cm": d,
            "damping_ns_per_cm": lam,
            "lift_force_n": lift,
            "friction_mu": mu,
            "f_w_n": rigid_grip_force_n(w, mu),
            "converged": True,
        }
    )
