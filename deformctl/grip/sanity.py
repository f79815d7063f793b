"""Is a lifting-force model's output a lifting force? (issue 34 point 3)

A model file can be structurally sound (the right layers, finite weights) and still predict
nonsense: weights scaled by 10^300 predict 10^301 N. Two checks, on the physics of the answer:

* **On loading** (:func:`output_problem`), the model is evaluated at its own training points
  (the metadata's ``check_points``, training rows ``train`` stored; without them, the middle of
  the stored training range). A prediction there that is not finite, or whose L_f / F_w lies
  outside the plausible band [1, :data:`~deformctl.quantities.MAX_LIFT_RATIO`] by more than
  :data:`LOAD_FACTOR`, refuses the model (exit 65): a trained model reproduces its training
  targets far better than that (the grip model: L_f / F_w 1.11–2.04 over its range).
* **On every prediction** (:func:`implausible`), an L_f that is not finite, ≤ 0, below F_w (by
  more than :data:`~deformctl.table.F_W_TOLERANCE_REL`'s 0.5 %) or above 10 × F_w is flagged
  ``prediction_implausible`` with a warning line naming the object; ``predict`` then refuses a
  force that is not finite and positive rather than print it.
* **Far from the training targets** (the same flag): ``train`` stores the range [r_lo, r_hi] of
  the training rows' L_f / F_w in the model's metadata (``target_range.lift_ratio_f_w``; ``adapt``
  widens it to its rig rows). A prediction whose L_f / F_w lies outside
  [r_lo / :data:`TARGET_FACTOR`, r_hi × :data:`TARGET_FACTOR`] is more than the network ever
  learned, not an interpolation: flagged, and the warning names the range. The bundled grip
  model's targets span 1.11–2.06, so it flags a prediction above 3.09 × F_w; over 20,000 random
  objects inside its training range (17,793 of them) it predicts 1.108–2.023 × F_w
  (tests/grip/test_targets.py).
  A model without a stored range (trained before it was stored) gets the [1, 10] × F_w check only.

F_w = W / (2 μ) needs μ: a μ-aware model has it per row, a single-μ model from its metadata;
without μ only finiteness and sign are checked.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from deformctl.quantities import MAX_LIFT_RATIO

__all__ = [
    "BELOW_F_W_REL",
    "LOAD_FACTOR",
    "TARGET_FACTOR",
    "implausible",
    "implausible_line",
    "output_problem",
    "target_ratio_range",
]

#: A model is refused on loading when a training point's L_f / F_w is outside
#: [1 / LOAD_FACTOR, MAX_LIFT_RATIO * LOAD_FACTOR].
LOAD_FACTOR = 2.0
#: A prediction below F_w by more than this (relative) is flagged (a search never finds less).
BELOW_F_W_REL = 0.005
#: A prediction whose L_f / F_w is more than this factor outside the training targets' range is
#: flagged (module doc): the network's output there is an extrapolation of its last layer, not a
#: lifting force it learned. 1.5 leaves the bundled model's in-range predictions (at most 1 %
#: outside its targets' range) a wide margin and catches a ratio of 3.1 where it learned 2.06.
TARGET_FACTOR = 1.5

#: (low, high) of the training targets' L_f / F_w, or None.
RatioRange = tuple[float, float] | None


def target_ratio_range(metadata: Any) -> RatioRange:
    """The training targets' L_f / F_w range a model file stores, or None (none stored).

    Raises:
        ValueError: a stored range that is not ``0 < low <= high``, finite.
    """
    stored = (metadata.get("target_range") or {}) if isinstance(metadata, dict) else {}
    if not isinstance(stored, dict) or stored.get("lift_ratio_f_w") is None:
        return None
    low, high = (float(v) for v in stored["lift_ratio_f_w"])
    if not (math.isfinite(low) and math.isfinite(high) and 0 < low <= high):
        raise ValueError(f"target range ({low!r}, {high!r})")
    return low, high


def _far_band(targets: RatioRange) -> tuple[float, float] | None:
    return None if targets is None else (targets[0] / TARGET_FACTOR, targets[1] * TARGET_FACTOR)


def implausible(
    lift_force_n: np.ndarray, f_w_n: np.ndarray, targets: RatioRange = None
) -> np.ndarray:
    """``[n]`` True where a prediction cannot be a lifting force, or lies far from the
    training targets ``targets`` (their L_f / F_w range; module doc)."""
    lift = np.asarray(lift_force_n, dtype=np.float64)
    f_w = np.broadcast_to(np.asarray(f_w_n, dtype=np.float64), lift.shape)
    bad = ~np.isfinite(lift) | ~(lift > 0)
    known = np.isfinite(f_w) & (f_w > 0)
    with np.errstate(invalid="ignore", over="ignore"):
        bad |= known & ((lift < f_w * (1 - BELOW_F_W_REL)) | (lift > MAX_LIFT_RATIO * f_w))
        band = _far_band(targets)
        if band is not None:
            bad |= known & ((lift < band[0] * f_w) | (lift > band[1] * f_w))
    return np.asarray(bad, dtype=bool)


def implausible_line(
    name: str, lift_force_n: float, f_w_n: float, targets: RatioRange = None
) -> str:
    """The warning of one implausible prediction (no ``warning:`` prefix)."""
    known = math.isfinite(f_w_n) and f_w_n > 0
    head = f"{name}: predicted L_f {lift_force_n:.6g} N"
    ratio = lift_force_n / f_w_n if known else math.nan
    plausible = known and math.isfinite(lift_force_n) and lift_force_n > 0
    plausible = plausible and (1 - BELOW_F_W_REL) <= ratio <= MAX_LIFT_RATIO
    band = _far_band(targets)
    if plausible and band is not None:
        assert targets is not None
        return (
            f"{head} = {ratio:.3g} x F_w is implausible: far from the training targets (L_f / "
            f"F_w {targets[0]:.3g}-{targets[1]:.3g}; flagged outside x/÷ {TARGET_FACTOR:g}: "
            f"{band[0]:.3g}-{band[1]:.3g})"
        )
    why = (
        f"outside [F_w, {MAX_LIFT_RATIO:g} x F_w] = [{f_w_n:.6g}, {MAX_LIFT_RATIO * f_w_n:.6g}] N"
        if known
        else "not a positive force"
    )
    return f"{head} is implausible: {why}"


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
