"""``adapt`` on a sim-to-real gap we control (``make bench``: bench_adapt).

"Reality" is the simulator's ``table`` preset (lifted from a table along an S-curve); the
"simulator" is the ``paper`` preset, which the bundled grip model was trained on. (The gap is a
property of the two presets' L_f on the same objects, so it is as large one way as the other,
up to the model's own error of about 0.3 %: this direction needs no second model.) 38 objects of
the grip population law with another seed than the model's (``population --grip -n 38 --seed
11``) are lifted with ``lift --sim --sim-preset table``; their features are the catalog's
material D and λ (what ``characterize`` recovers from a simulated squeeze to about 1 %). The
first 8 are the rig's lifts that :func:`deformctl.adapt.adapt_model` corrects the model with; the
30 others are the new objects it is judged on: the median relative error of the adapted and the
unadapted model, and how many of the 30 lie below the adapted model's P = 0.9 bound.

:data:`CACHE` holds the 38 lifts (``python -m bench.bench_adapt --write`` remakes it), so the test
(tests/repro/test_adapt_gap.py) adapts and judges without simulating.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

__all__ = ["CACHE", "N_RIG", "POPULATION", "gap_figures", "lifts_frame"]

#: the population command's arguments (38 objects, another seed than the model's 1)
POPULATION = ("--grip", "-n", "38", "--seed", "11")
#: the rig's lifts the model is adapted with (the rest are judged)
N_RIG = 8
#: the 38 objects' features and table-preset L_f
CACHE = Path(__file__).resolve().parents[2] / "tests" / "data" / "adapt_gap.csv"
_FEATURES = ("weight_n", "deformability_n_per_cm", "damping_ns_per_cm", "friction_mu")


def lifts_frame(catalog: pd.DataFrame, lift_results: pd.DataFrame) -> pd.DataFrame:
    """The objects' features (material D and λ) and L_f, as :data:`CACHE` holds them."""
    from deformctl.catalog import MATERIAL_COLUMNS

    df = catalog.merge(lift_results[["object_id", "lift_force_n", "converged"]], on="object_id")
    df["deformability_n_per_cm"] = df[MATERIAL_COLUMNS[0]]
    df["damping_ns_per_cm"] = df[MATERIAL_COLUMNS[1]]
    return df[["object_id", *_FEATURES, "lift_force_n", "converged"]]


def gap_figures(frame: pd.DataFrame, coverage: float = 0.9) -> dict[str, Any]:
    """Adapt the bundled grip model on the first :data:`N_RIG` rows of ``frame`` and judge it on
    the others: the median relative errors, their ratio and the bound's coverage."""
    from deformctl.adapt import adapt_model
    from deformctl.grip.fast import Predictor

    rig = frame.iloc[:N_RIG].assign(source="rig")
    new = frame.iloc[N_RIG:]
    base = Predictor.load("grip")
    result = adapt_model("grip", rig, index_path="rig")
    x = [new[c].to_numpy(dtype=np.float64) for c in _FEATURES]
    truth = new["lift_force_n"].to_numpy(dtype=np.float64)
    before = base.predict_many(*x).lift_force_n
    after = result.predictor.predict_many(*x, coverage=coverage)
    err_before = float(np.median(np.abs(before / truth - 1.0)))
    err_after = float(np.median(np.abs(after.lift_force_n / truth - 1.0)))
    below = truth <= after.lift_force_upper_n
    return {
        "n_rig": len(rig),
        "n_new": len(new),
        "median_error_unadapted": err_before,
        "median_error_adapted": err_after,
        "error_ratio": err_after / err_before,
        "coverage": coverage,
        "covered": int(below.sum()),
        "empirical_coverage": float(below.mean()),
        "mean_margin": float(np.mean(after.lift_force_upper_n / after.lift_force_n - 1.0)),
        "bound_guaranteed": bool(after.bound_guaranteed.all()),
        "alpha": result.alpha,
        "coefficients": result.metadata["adapted"]["coefficients"],
    }


def report_lines(fig: dict[str, Any]) -> list[str]:
    """The figures as ``make bench`` prints them."""
    pct = {k: f"{100 * fig[k]:.1f} %" for k in ("median_error_unadapted", "median_error_adapted")}
    return [
        f"reality: lift --sim-preset table; model: the bundled grip model (paper preset); "
        f"{fig['n_rig']} rig rows, {fig['n_new']} new objects",
        f"median relative error on the new objects: unadapted {pct['median_error_unadapted']}, "
        f"adapted {pct['median_error_adapted']} (ratio {fig['error_ratio']:.2f}; target <= 0.5)",
        f"P = {fig['coverage']:g} bound of the adapted model: {fig['covered']}/{fig['n_new']} "
        f"below it (coverage {fig['empirical_coverage']:.2f}; target >= 0.8), mean margin "
        f"{100 * fig['mean_margin']:.1f} %, guaranteed: {fig['bound_guaranteed']} "
        f"({fig['n_rig']} rows < the 9 a P = 0.9 guarantee needs: the largest score)",
        f"ridge alpha {fig['alpha']:.3g}, correction {np.round(fig['coefficients'], 3).tolist()}",
    ]
