"""One-sided split-conformal upper bounds with a relative (normalised) score.

Split conformal prediction (Vovk et al.; Lei et al. 2018, "Distribution-free predictive
inference for regression") turns any fitted point predictor into a bound with a finite-sample
guarantee. Rows that the model was *not* fitted on (the calibration rows) give the scores

    s_i = (y_i - ŷ_i) / ŷ_i,   i = 1..n

(the relative shortfall of the prediction: positive when the true lifting force is above it).
For a coverage P in (0, 1) the bound's margin is the k-th smallest score with

    k = ⌈(n + 1) P⌉,

and the upper bound of a new object is ``ŷ (1 + q_P)``. When the calibration rows and the new
object are exchangeable (drawn alike, for example by the same seeded population law), then
``Pr(y ≤ ŷ (1 + q_P)) ≥ P`` -- for any model, however wrong, and any n (Lei et al., Theorem 2.2;
the event ``y ≤ ŷ(1 + q)`` is ``s ≤ q`` because ŷ > 0). The coverage is also at most
``P + 1/(n + 1)`` when the scores have no ties. When ``k > n`` (too few calibration rows for P:
``n < P / (1 - P)``) no finite bound has the guarantee: the margin is ``inf``.

The score is relative so that the margin scales with the force: a 5 % margin on a 2 N object and
on a 200 N one, instead of one margin in newtons that is too wide for the light objects and too
narrow for the heavy ones.

Numpy only (the fast predictor, :mod:`deformctl.grip.fast`, uses it without scikit-learn).

Example:
    >>> import numpy as np
    >>> scores = relative_scores(np.array([10.0, 11.0, 9.0, 12.0]), np.array([10.0] * 4))
    >>> scores.tolist()
    [0.0, 0.1, -0.1, 0.2]
    >>> conformal_margin(scores, 0.5)  # k = ceil(5 * 0.5) = 3: the 3rd smallest
    0.1
    >>> conformal_margin(scores, 0.9)  # k = ceil(4.5) = 5 > 4 scores: no finite bound
    inf
"""

from __future__ import annotations

import hashlib
import math
from typing import Any

import numpy as np

__all__ = [
    "COVERAGES_REPORTED",
    "check_coverage",
    "conformal_margin",
    "conformal_min_scores",
    "conformal_rank",
    "coverage_report",
    "min_coverage",
    "relative_scores",
    "scores_digest",
    "upper_bound",
]

#: The coverages ``train`` reports (empirical coverage and mean margin on its test rows).
COVERAGES_REPORTED: tuple[float, ...] = (0.9, 0.95)


def check_coverage(coverage: float) -> float:
    """``coverage`` as a float if it is a finite number in (0, 1); ValueError otherwise."""
    value = float(coverage)
    if not (math.isfinite(value) and 0.0 < value < 1.0):
        raise ValueError(f"coverage must be a number in (0, 1), got {coverage!r}")
    return value


def relative_scores(y_true: Any, y_pred: Any) -> np.ndarray:
    """``[n]`` scores ``(y - ŷ) / ŷ``; ŷ must be > 0 and everything finite (ValueError)."""
    y = np.asarray(y_true, dtype=np.float64).reshape(-1)
    p = np.asarray(y_pred, dtype=np.float64).reshape(-1)
    if y.shape != p.shape:
        raise ValueError(f"{y.shape[0]} true values but {p.shape[0]} predictions")
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(p))):
        raise ValueError("scores need finite true values and predictions")
    if np.any(p <= 0):
        raise ValueError("a relative score needs predictions > 0")
    return np.asarray((y - p) / p)


def conformal_rank(n: int, coverage: float) -> int:
    """k = ⌈(n + 1) P⌉: the rank (1-based) of the score that is the margin (at least 1).

    Computed so that a product that should be an integer (for example n = 9, P = 0.9) is not
    pushed one rank up by rounding: ``(n + 1) P`` is rounded to 12 decimals first. Below
    :func:`min_coverage` that rounding gives 0; the rank is then 1 (the smallest score), never
    the 0th (which numpy would read as the largest).
    """
    p = check_coverage(coverage)
    return max(1, math.ceil(round((n + 1) * p, 12)))


def min_coverage(n: int) -> float:
    """The smallest meaningful coverage with ``n`` calibration scores: 1 / (n + 1).

    At or below it the rank ⌈(n + 1) P⌉ is 1 for every P: the bound is the smallest score's,
    whatever P is asked, so a P below it states a guarantee the bound does not depend on.
    ``predict --coverage`` refuses a P below it (exit 2).
    """
    return 1.0 / (n + 1)


def scores_digest(scores: Any) -> str:
    """``sha256:<hex>`` of the calibration scores as stored (float64, little-endian, in order):
    the stored check a model file keeps of its scores, recomputed when it is loaded."""
    s = np.asarray(scores, dtype="<f8").reshape(-1)
    return "sha256:" + hashlib.sha256(s.tobytes()).hexdigest()


def conformal_min_scores(coverage: float) -> int:
    """The fewest calibration scores with a finite margin at P: the least n with
    ⌈(n + 1) P⌉ <= n (for example 9 at P = 0.9, 19 at P = 0.95)."""
    p = check_coverage(coverage)
    n = max(1, math.floor(p / (1.0 - p)) - 1)
    while conformal_rank(n, p) > n:
        n += 1
    return n


def conformal_margin(scores: Any, coverage: float) -> float:
    """The split-conformal margin q_P: the ⌈(n + 1) P⌉-th smallest score (inf when k > n).

    Args:
        scores: ``[n]`` calibration scores (:func:`relative_scores`), finite.
        coverage: P in (0, 1).
    """
    s = np.sort(np.asarray(scores, dtype=np.float64).reshape(-1))
    if not np.all(np.isfinite(s)):
        raise ValueError("calibration scores must be finite")
    k = conformal_rank(s.size, coverage)
    return math.inf if k > s.size else float(s[k - 1])


def upper_bound(prediction: Any, margin: float) -> np.ndarray:
    """``ŷ (1 + q)``: the upper bound of predictions ``ŷ`` with margin ``q`` (inf stays inf)."""
    p = np.asarray(prediction, dtype=np.float64)
    return np.asarray(p * (1.0 + margin)) if math.isfinite(margin) else np.full_like(p, np.inf)


def coverage_report(
    scores: Any, y_true: Any, y_pred: Any, coverages: tuple[float, ...] = COVERAGES_REPORTED
) -> dict[str, dict[str, float | int | None]]:
    """Empirical coverage and mean margin of the bound on held-out rows, per coverage.

    Args:
        scores: ``[n_cal]`` calibration scores.
        y_true, y_pred: ``[m]`` true values and predictions of rows that are neither training
            nor calibration rows (the test rows).
        coverages: the P to report.

    Returns:
        ``{"0.9": {"coverage": ..., "margin": q_P, "mean_margin": ..., "n_calibration": ...,
        "n_test": m, "rank": k}, ...}``: ``coverage`` is the fraction of rows with
        ``y <= upper``, ``mean_margin`` the mean of ``upper / y - 1`` (how much more force the
        bound asks for than the true L_f, as a fraction). None where no finite bound exists.
    """
    s = np.asarray(scores, dtype=np.float64).reshape(-1)
    y = np.asarray(y_true, dtype=np.float64).reshape(-1)
    p = np.asarray(y_pred, dtype=np.float64).reshape(-1)
    out: dict[str, dict[str, float | int | None]] = {}
    for coverage in coverages:
        q = conformal_margin(s, coverage)
        upper = upper_bound(p, q)
        finite = math.isfinite(q) and y.size > 0
        out[f"{coverage:g}"] = {
            "coverage": float(np.mean(y <= upper)) if finite else None,
            "margin": q if math.isfinite(q) else None,
            "mean_margin": float(np.mean(upper / y - 1.0)) if finite else None,
            "n_calibration": int(s.size),
            "n_test": int(y.size),
            "rank": conformal_rank(s.size, coverage),
        }
    return out
