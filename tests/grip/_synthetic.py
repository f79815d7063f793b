"""Synthetic grip data with a known law: L_f = F_w · r(ω_n, ζ) · (1 + ε).

``r`` is shaped like the simulator's landscape (2 undamped, about 1.1 heavily damped, lower at
high ω_n); ε is a seeded normal noise of a stated standard deviation standing in for the
search's tolerance and the object's size. Inputs come from :func:`deformctl.population.
grip_population` (the bundled model's law).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from typer.testing import CliRunner

from deformctl.artifacts import write_table
from deformctl.cli import app
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


def law_ratio(law: np.ndarray, omega: np.ndarray, zeta: np.ndarray, n_exp: np.ndarray,
              k2_over_d: np.ndarray, tau_omega: np.ndarray,
              height_ratio: np.ndarray) -> np.ndarray:  # fmt: skip
    """The known law of :func:`law_index`: KV's ratio; HC's grows with n (+15 % per unit of
    n - 1, the study's 3-17 %) and with the height over the squeezed length L_z / L_x (+10 %
    per decade);
    SLS's with k2/D (+6 % per decade) and τ ω_n (+2 % per decade)."""
    r = ratio(omega, zeta)
    hc = r * (1.0 + 0.15 * (n_exp - 1.0)) * (1.0 + 0.1 * np.log10(height_ratio))
    sls = r * (1.0 + 0.06 * np.log10(np.maximum(k2_over_d, 1e-9)) + 0.02 * np.log10(
        np.maximum(tau_omega, 1e-9)))  # fmt: skip
    return np.where(law == "hc", hc, np.where(law == "sls", sls, r))


def law_index(
    n: int, seed: int, noise: float = 0.0, prefix: str = "L", laws: str = "kv=1,hc=1,sls=1"
) -> pd.DataFrame:
    """An index table with the coefficients columns of a material law (``model``, ``hc_*``,
    ``sls_*``) whose L_f follows :func:`law_ratio` (times 1 + N(0, noise²)); SLS rows state
    λ = k2 τ, as characterize does."""
    from deformctl.population import catalog_laws

    cat = grip_population(n, seed=seed, id_prefix=prefix, laws=laws)
    law = catalog_laws(cat)
    w = cat["weight_n"].to_numpy()
    d = cat["material_stiffness_n_per_cm"].to_numpy()

    def col(name: str, default: float) -> np.ndarray:
        return cat[name].to_numpy() if name in cat else np.full(n, default)

    n_exp = col("material_stiffness_exponent", 1.0)
    k2 = col("material_arm_stiffness_n_per_cm", 0.0)
    tau = col("material_relaxation_time_s", np.nan)
    lam = np.where(law == "sls", k2 * np.nan_to_num(tau), cat["material_damping_ns_per_cm"])
    mu = cat["friction_mu"].to_numpy()
    omega, zeta = group_values(w, d, lam)
    f_w = w / (2 * mu)
    eps = np.random.default_rng(seed + 7919).normal(0.0, noise, n) if noise else np.zeros(n)
    size = {a: cat[f"size_{a}_cm"].to_numpy() for a in "xyz"}
    height = size["z"] / size["x"]
    r = law_ratio(law, omega, zeta, n_exp, k2 / d, np.nan_to_num(tau) * omega, height)
    nan = np.full(n, np.nan)
    return pd.DataFrame(
        {
            "object_id": cat["object_id"],
            "weight_n": w,
            "deformability_n_per_cm": d,
            "damping_ns_per_cm": lam,
            "lift_force_n": f_w * r * (1 + eps),
            "friction_mu": mu,
            "f_w_n": f_w,
            "converged": True,
            "model": law,
            "hc_exponent": np.where(law == "hc", n_exp, nan),
            "sls_stiffness_n_per_cm": np.where(law == "sls", d, nan),
            "sls_arm_stiffness_n_per_cm": np.where(law == "sls", k2, nan),
            "sls_relaxation_time_s": np.where(law == "sls", tau, nan),
            **{f"size_{a}_cm": v for a, v in size.items()},
        }
    )


LAW_COLS = ["model", "hc_exponent", "sls_stiffness_n_per_cm", "sls_arm_stiffness_n_per_cm",
            "sls_relaxation_time_s", "size_x_cm", "size_y_cm", "size_z_cm"]  # fmt: skip


def train_cli(d: Path, index: pd.DataFrame, name: str, laws: bool = True) -> Path:
    write_table(index.drop(columns=LAW_COLS), d / f"{name}-index.parquet", "index_table",
                provenance=None)  # fmt: skip
    write_table(index, d / f"{name}-laws.parquet", "index_table", provenance=None)
    out = d / f"{name}.skops"
    args = ["train", str(d / f"{name}-index.parquet"), "-o", str(out), "--train-size", "70",
            "--calibration-size", "30", "--seed", "0"]  # fmt: skip
    result = CliRunner().invoke(app, [*args, *(["--laws", str(d / f"{name}-laws.parquet")] if laws
                                          else [])])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    return out
