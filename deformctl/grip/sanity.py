"""Is a lifting-force model's output a lifting force?

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

**The calibration scores** (:func:`scores_problem`, on loading) are what an upper bound is made
of, so a file whose scores were changed must not load. Each score ``(y - ŷ) / ŷ`` compares two
lifting forces: a true one, y in [F_w, :data:`~deformctl.quantities.MAX_LIFT_RATIO` × F_w], and
a usable model's prediction, ŷ in [(1 - :data:`BELOW_F_W_REL`) F_w, 10 F_w]. So every score lies
in [:data:`SCORE_LOW`, :data:`SCORE_HIGH`] = [0.995 / 10 - 1, 10 / 0.995 - 1] ≈ [-0.90, 9.05]
(half the bundled model's scores are below 0: a prediction above the truth). Their count must
be the stored ``n_calibration``, and they must match the file's stored check: the digest
``conformal_digest`` (:func:`~deformctl.grip.conformal.scores_digest`, written by ``train`` and
``adapt``) or, in a file written before it, the margins at the coverages ``train`` reported
(``conformal``). **Every bound** is then ``max(ŷ (1 + max(q, 0)), F_w)``: never below the
prediction (a negative margin only comes from a low P) nor below F_w (no lifting force is), so
``F_w ≤ bound`` and ``ŷ ≤ bound`` hold by construction. A bound of a plausible prediction that
is not finite or is above ``(1 + SCORE_HIGH) ŷ`` (a margin no pair of lifting forces gives; the
absolute limit of a bound, at most about 100 × F_w) cannot come from valid scores: the file is
refused (:func:`bound_problem`, exit 65).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from deformctl.grip.conformal import conformal_margin, scores_digest
from deformctl.physics import rigid_grip_force_n
from deformctl.quantities import MAX_LIFT_RATIO

__all__ = [
    "BELOW_F_W_REL",
    "LOAD_FACTOR",
    "SCORE_HIGH",
    "SCORE_LOW",
    "TARGET_FACTOR",
    "bound_problem",
    "implausible",
    "implausible_line",
    "output_problem",
    "scores_problem",
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

#: The range of a calibration score (y - ŷ) / ŷ between two lifting forces (module doc).
SCORE_LOW = (1.0 - BELOW_F_W_REL) / MAX_LIFT_RATIO - 1.0
SCORE_HIGH = MAX_LIFT_RATIO / (1.0 - BELOW_F_W_REL) - 1.0
#: How closely a legacy file's stored margins must match the ones its scores give.
_MARGIN_RTOL = 1e-9

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
        f_w = rigid_grip_force_n(float(weight[i]), m)
        ratio = value / f_w
        if not (1.0 / LOAD_FACTOR <= ratio <= MAX_LIFT_RATIO * LOAD_FACTOR):
            return (
                f"it predicts L_f = {value:.6g} N = {ratio:.3g} x F_w at {where} (row {i}); a "
                f"lifting force lies within [1, {MAX_LIFT_RATIO:g}] x F_w"
            )
    return None


def scores_problem(scores: np.ndarray, metadata: Any) -> str | None:
    """What is wrong with a model file's calibration scores (None: nothing; module doc).

    Args:
        scores: the scores as stored (not sorted), float64.
        metadata: the model file's metadata.
    """
    if not np.all(np.isfinite(scores)):
        return "its calibration scores are not all finite"
    if scores.size == 0:
        return "it stores an empty list of calibration scores"
    low, high = float(np.min(scores)), float(np.max(scores))
    if low < SCORE_LOW or high > SCORE_HIGH:
        bad = low if low < SCORE_LOW else high
        return (
            f"a calibration score of {bad:.6g} is outside [{SCORE_LOW:.4g}, {SCORE_HIGH:.4g}], "
            f"the range between two lifting forces in [1, {MAX_LIFT_RATIO:g}] x F_w"
        )
    stored_n = metadata.get("n_calibration")
    if isinstance(stored_n, bool) or not isinstance(stored_n, int) or stored_n != scores.size:
        return f"it has {scores.size} calibration scores but states n_calibration = {stored_n!r}"
    digest = metadata.get("conformal_digest")
    if digest is not None:
        if digest != scores_digest(scores):
            return "its calibration scores do not match their stored digest"
        return None
    report = metadata.get("conformal")
    margins = [] if not isinstance(report, dict) else list(report.items())
    checked = 0
    for coverage, entry in margins:
        stored = entry.get("margin") if isinstance(entry, dict) else None
        try:
            q = conformal_margin(scores, float(coverage))
        except (TypeError, ValueError):
            return f"its stored conformal report has a coverage {coverage!r}"
        if stored is None and math.isinf(q):
            continue
        if not isinstance(stored, int | float) or not math.isclose(
            q, float(stored), rel_tol=_MARGIN_RTOL, abs_tol=1e-15
        ):
            return (
                f"its calibration scores give the margin {q:.6g} at P = {coverage}, "
                f"not the stored {stored!r}"
            )
        checked += 1
    if checked == 0:
        return "its calibration scores are covered by no stored check (digest or margins)"
    return None


def bound_problem(lift_force_n: Any, upper_n: Any, f_w_n: Any) -> int | None:
    """The first row whose bound is not ``F_w <= prediction <= bound <= (1 + SCORE_HIGH) x
    prediction`` (finite) for a plausible prediction, or None (module doc)."""
    lift = np.asarray(lift_force_n, dtype=np.float64)
    upper = np.broadcast_to(np.asarray(upper_n, dtype=np.float64), lift.shape)
    f_w = np.broadcast_to(np.asarray(f_w_n, dtype=np.float64), lift.shape)
    known = np.isfinite(f_w) & (f_w > 0)
    with np.errstate(invalid="ignore", over="ignore"):
        plausible = known & np.isfinite(lift) & (lift >= f_w * (1 - BELOW_F_W_REL))
        plausible &= lift <= MAX_LIFT_RATIO * f_w
        bad = plausible & ~(np.isfinite(upper) & (upper >= lift) & (upper >= f_w))
        bad |= plausible & (upper > (1.0 + SCORE_HIGH) * lift)
        bad |= np.isfinite(lift) & (lift > 0) & ~np.isnan(upper) & ~(upper >= lift)
    rows = np.flatnonzero(bad)
    return int(rows[0]) if rows.size else None
