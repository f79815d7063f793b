"""Small valid artifacts of every kind, built with the public writers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from deformctl.artifacts import LiftAttempt, Provenance
from deformctl.series import LiftAttemptSeries, SqueezeSeries, TrialOutcome

REPO = Path(__file__).resolve().parents[2]
PAPER_OBJECTS = REPO / "datasets" / "paper" / "objects.csv"


def make_provenance() -> Provenance:
    return Provenance.from_invocation(
        [PAPER_OBJECTS],
        seed=7,
        settings={"dt_s": 1e-4, "lattice": [2, 2, 2]},
        argv=["/usr/bin/deformctl", "measure", "--sim", str(PAPER_OBJECTS)],
    )


def make_squeezes(n: int = 5) -> list[SqueezeSeries]:
    """Two objects, two squeezes each; palm positions on two of them only."""
    rng = np.random.default_rng(0)
    out = []
    for k, (oid, idx) in enumerate([("A", 0), ("A", 1), ("B", 0), ("B", 1)]):
        t = np.arange(n) * 0.25
        d = 0.001 * t + 1e-6 * rng.standard_normal(n)
        left = -0.05 + d / 2
        right = 0.05 - d / 2
        with_palms = k % 2 == 0
        out.append(
            SqueezeSeries(
                oid,
                idx,
                t,
                force_n=49.18 * 100 * d,
                compression_m=d,
                commanded_force_n=np.full(n, 5.0),
                palm_left_x_m=left if with_palms else None,
                palm_right_x_m=right if with_palms else None,
            )
        )
    return out


def make_attempts(n: int = 4) -> list[LiftAttempt]:
    t = np.arange(n) * 0.1
    series = LiftAttemptSeries(t, 0.01 * t, 0.008 * t, 0.002 * t, np.full(n, 0.7), np.full(n, 0.7))
    return [
        LiftAttempt("A", 0, TrialOutcome(0.7, False, 0.0125, series, {"note": "slipped"})),
        LiftAttempt("A", 1, TrialOutcome(0.84, True, float("nan"), None, {})),
    ]


def make_tables() -> dict[str, pd.DataFrame]:
    """One valid frame per table kind (spec columns plus an extra column where useful)."""
    return {
        "catalog": pd.read_csv(PAPER_OBJECTS, dtype={"object_id": str}),
        "coefficients": pd.DataFrame(
            {
                "object_id": ["A", "B"],
                "deformability_n_per_cm": [49.18, 13.03],
                "damping_ns_per_cm": [6.47, 0.33],
                "method": ["lsq", "lsq"],
                "r2": [0.99, float("nan")],
                "n_samples": [300, 300],
                "n_squeezes": [3, 3],
            }
        ),
        "lift_results": pd.DataFrame(
            {
                "object_id": ["A", "B"],
                "weight_n": [0.7, 1.4],
                "friction_mu": [0.5, 0.5],
                "f_w_n": [0.7, 1.4],
                "lift_force_n": [0.84, float("nan")],
                "f_d_n": [0.14, float("nan")],
                "attempts": [2, 12],
                "converged": [True, False],
                "protocol": ["paper", "paper"],
                "runner": ["sim", "sim"],
                "error": [None, "did not converge"],
            }
        ),
        "index_table": pd.DataFrame(
            {
                "object_id": ["A", "B"],
                "weight_n": [0.7, 1.4],
                "deformability_n_per_cm": [49.18, 13.03],
                "damping_ns_per_cm": [6.47, 0.33],
                "lift_force_n": [0.84, 1.72],
                "friction_mu": [0.5, 0.5],
            }
        ),
        "predictions": pd.DataFrame(
            {
                "object_id": [None, "q1"],
                "weight_n": [40.81, 56.33],
                "deformability_n_per_cm": [41.66, 45.99],
                "damping_ns_per_cm": [0.15, 12.32],
                "predicted_lift_force_n": [74.41, 73.95],
                "outside_training_range": [False, True],
                "model": ["m1", "m1"],
            }
        ),
    }
