"""Is a lifting-force model's output a lifting force? (issue 34 point 3)

A model file can be structurally sound (the right layers, finite weights) and still predict
nonsense: weights scaled by 10^300 predict 10^301 N. Two checks, on the physics of the answer:

* **On loading** (:func:`output_problem`), the model is evaluated at its own training points
  (the metadata's ``check_points``, training rows ``train`` stored; without them, the middle of
  the stored training range). A prediction there that is not finite, or whose L_f / F_w lies
  outside the plausible band [1, :data:`~deformctl.plausibility.MAX_LIFT_RATIO`] by more than
  :data:`LOAD_FACTOR`, refuses the model (exit 65): a trained model reproduces its training
  targets far better than that (the grip model: L_f / F_w 1.11–2.04 over its range).
* **On every prediction** (:func:`implausible`), an L_f that is not finite, ≤ 0, below F_w (by
  more than :data:`~deformctl.table.F_W_TOLERANCE_REL`'s 0.5 %) or above 10 × F_w is flagged
  ``prediction_implausible`` with a warning line naming the object; ``predict`` then refuses a
  force that is not finite and positive rather than print it.

F_w = W / (2 μ) needs μ: a μ-aware model has it per row, a single-μ model from its metadata;
without μ only finiteness and sign are checked.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from deformctl.plausibility import MAX_LIFT_RATIO

__all__ = ["BELOW_F_W_REL", "LOAD_FACTOR", "implausible", "implausible_line", "output_problem"]

#: A model is refused on loading when a training point's L_f / F_w is outside
#: [1 / LOAD_FACTOR, MAX_LIFT_RATIO * LOAD_FACTOR].
LOAD_FACTOR = 2.0
#: A prediction below F_w by more than this (relative) is flagged (a search never finds less).
BELOW_F_W_REL = 0.005


def implausible(lift_force_n: np.ndarray, f_w_n: np.ndarray) -> np.ndarray:
    """``[n]`` True where a prediction cannot be a lifting force (module doc)."""
    lift = np.asarray(lift_force_n, dtype=np.float64)
    f_w = np.broadcast_to(np.asarray(f_w_n, dtype=np.float64), lift.shape)
    bad = ~np.isfinite(lift) | ~(lift > 0)
    known = np.isfinite(f_w) & (f_w > 0)
    with np.errstate(invalid="ignore", over="ignore"):
        bad |= known & ((lift < f_w * (1 - BELOW_F_W_REL)) | (lift > MAX_LIFT_RATIO * f_w))
    return np.asarray(bad, dtype=bool)


def implausible_line(name: str, lift_force_n: float, f_w_n: float) -> str:
    """The warning of one implausible prediction (no ``warning:`` prefix)."""
    band = (
        f"outside [F_w, {MAX_LIFT_RATIO:g} x F_w] = [{f_w_n:.6g}, {MAX_LIFT_RATIO * f_w_n:.6g}] N"
        if math.isfinite(f_w_n) and f_w_n > 0
        else "not a positive force"
    )
    return f"{name}: predicted L_f {lift_force_n:.6g} N is implausible: {band}"


def output_problem(predictor: Any) -> str | None:
    """What is wrong with the model's output at its own training points (None: nothing).

    Args:
        predictor: a :class:`deformctl.grip.fast.Predictor`.
    """
    features = list(predictor.features)
    check = predictor.metadata.get("check_points")
    points: np.ndarray | None = None
    if isinstance(check, dict):
        try:
            points = np.asarray(check["inputs"], dtype=np.float64).reshape(-1, len(features))
        except (KeyError, TypeError, ValueError):
            points = None
    where = "a stored training point"
    if points is None or len(points) == 0:
        try:
            points = np.array([[sum(predictor.ranges[c]) / 2.0 for c in features]])
        except KeyError:
            return None  # nothing stored to check against
        where = "the middle of its training range"
    with np.errstate(all="ignore"):
        lift = np.asarray(predictor._lift_force(points), dtype=np.float64)
    weight = points[:, features.index("weight_n")] if "weight_n" in features else None
    if "friction_mu" in features:
        mu: Any = points[:, features.index("friction_mu")]
    else:
        mu = predictor.training_friction_mu
    for i, value in enumerate(lift):
        if not (math.isfinite(value) and value > 0):
            return f"it predicts {float(value)!r} N at {where} (row {i})"
        if weight is None or mu is None:
            continue
        m = float(mu[i]) if isinstance(mu, np.ndarray) else float(mu)
        f_w = float(weight[i]) / (2.0 * m)
        ratio = value / f_w
        if not (1.0 / LOAD_FACTOR <= ratio <= MAX_LIFT_RATIO * LOAD_FACTOR):
            return (
                f"it predicts L_f = {value:.6g} N = {ratio:.3g} x F_w at {where} (row {i}); a "
                f"lifting force lies within [1, {MAX_LIFT_RATIO:g}] x F_w"
            )
    return None
