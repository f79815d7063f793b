"""The ``adapt`` stage: a simulation-trained grip model corrected with a handful of rig lifts.

The simulator's world is not the robot's (its palms, its sensor, its objects), so a model trained
on simulated lifts is off by a gap that depends on the object. ``adapt`` closes it with the rig's
own lifts (an index table whose rows have ``source = rig``):

**The correction.** The grip model predicts ``log(L_f / F_w) = g(x)``, a network of its scaled
inputs ``x`` (the dimensionless groups log ω_n and log(ζ + c), standardised as the network sees
them). ``adapt`` adds a linear term::

    log(L_f / F_w) = g(x) + c0 + c · x

fitted to the rig rows' residuals ``r_i = log(L_f,i / L̂_f,i)`` by ridge regression with penalty
``α (c0² + |c|²)``: with few rows the coefficients shrink toward no correction (the simulator's
model), and with more rows toward the least-squares fit. ``α`` is chosen from a fixed grid
(:data:`ALPHAS`, and ``∞``: no correction) by the leave-one-out error, which ridge gives in
closed form (``e_i / (1 − h_ii)``, with ``H`` the ridge hat matrix); the smallest LOO mean
squared error wins, the larger α on a tie. Three rows are the fewest it accepts.

**The bound.** The model's conformal scores (from simulated calibration rows) do not describe
the rig, so they are replaced by the rig rows' leave-one-out scores ``s_i = L_f,i / L̂_f,(−i) − 1``
(each row predicted by the correction fitted without it). The bound at coverage P is then the
``k = ⌈(n + 1) P⌉``-th smallest of the n scores: this needs ``n ≥ P / (1 − P)`` rows (9 at
P = 0.9, 19 at P = 0.95). With fewer, the bound is the largest of the n scores, whose guarantee
is only ``n / (n + 1)``: the predictions say ``bound_guaranteed = false`` and a warning line
gives the numbers (:meth:`deformctl.grip.fast.Predictor.margin`). Leave-one-out scores are not
independent of the correction that is used, so the guarantee is the jackknife's (Barber et al.
2021, jackknife+: at least 1 − 2(1 − P) in the worst case), not split conformal's ``≥ P``; the
metadata says so.

The adapted model is the base model file with its network unchanged, the correction in its numpy
export, the rig scores as its calibration scores, new check points, and ``adapted`` in its
metadata: the base model, the rows (``object_id``, L_f, the prediction before and after), α, the
LOO errors and the rule of the bound.

Example:
    >>> import numpy as np
    >>> X = np.column_stack([np.ones(4), [-1.0, 0.0, 1.0, 2.0]])
    >>> coef, alpha, loo = ridge_loo(X, np.array([0.1, 0.1, 0.1, 0.1]))
    >>> bool(abs(coef[0] - 0.1) < 0.01 and abs(coef[1]) < 0.01)
    True
"""

from __future__ import annotations

import dataclasses
import io
import json
import math
import zipfile
from collections.abc import Sequence
from typing import Any

import numpy as np

from deformctl.errors import InputDataError
from deformctl.grip.conformal import scores_digest
from deformctl.grip.fast import Predictor, read_model_metadata, resolve_model_path
from deformctl.physics import rigid_grip_force_n

__all__ = ["ALPHAS", "MIN_ROWS", "AdaptResult", "adapt_model", "ridge_loo", "rig_rows"]

#: The fewest rig rows ``adapt`` accepts.
MIN_ROWS = 3
#: The ridge penalties tried (and ∞, no correction), chosen by leave-one-out.
ALPHAS: tuple[float, ...] = tuple(float(a) for a in np.logspace(-4, 3, 29))
#: The rule of the adapted model's bound, stored in its metadata.
BOUND_RULE = (
    "k = ceil((n + 1) P)-th smallest of the n rig rows' leave-one-out relative scores; "
    "needs n >= P / (1 - P) rows (9 at P = 0.9), with fewer the largest score, guaranteed at "
    "n / (n + 1) only (bound_guaranteed = false); jackknife guarantee (>= 1 - 2 (1 - P) worst "
    "case), not split conformal's >= P"
)


def ridge_loo(X: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """Ridge ``min |y − X c|² + α |c|²`` with α chosen by leave-one-out from :data:`ALPHAS`
    and ∞ (``c = 0``).

    Returns:
        The coefficients ``[p]``, the α chosen (``inf``: no correction) and the leave-one-out
        residuals ``[n]`` at that α (``y_i`` minus the fit without row i, predicting row i).
    """
    best = (float(np.mean(y**2)), math.inf, np.zeros(X.shape[1]), y.copy())
    p = X.shape[1]
    for alpha in sorted(ALPHAS, reverse=True):
        inv = np.linalg.inv(X.T @ X + alpha * np.eye(p))
        coef = inv @ X.T @ y
        hat = np.einsum("ij,jk,ik->i", X, inv, X)
        loo = (y - X @ coef) / (1.0 - hat)
        mse = float(np.mean(loo**2))
        if mse < best[0] * (1.0 - 1e-12):
            best = (mse, alpha, coef, loo)
    return best[2], best[1], best[3]


def rig_rows(index: Any, predictor: Predictor, path: str) -> Any:
    """The rig rows of an index table that ``adapt`` may use, validated.

    Raises:
        InputDataError: fewer than :data:`MIN_ROWS` rig rows, rows without the model's features
            (``friction_mu`` for the grip model), rows whose search did not converge, rows that
            are physically impossible (the refusal list ``table``, ``train`` and ``--lookup``
            apply, :func:`deformctl.table.impossible_rows`: L_f ≤ 0, below F_w beyond the
            search's tolerance, above 10 × F_w or not finite; D ≤ 0, λ < 0), or a model that is
            not a grip model (the messages name the rows; exit 65).
    """
    from deformctl.table import format_ids, refuse_impossible_rows

    if predictor.form != "grip":
        raise InputDataError(
            f"adapt corrects a grip model (features {', '.join(predictor.features)}); this model "
            f"is a {predictor.form} model with features {', '.join(predictor.features)}",
            path=str(predictor.path),
        )
    rows = index
    if "source" in index.columns:
        rows = index[index["source"].astype(str) == "rig"]
    ids = rows["object_id"].astype(str)
    missing = [c for c in predictor.features if c not in rows.columns]
    if missing:
        raise InputDataError(
            f"rows {format_ids(ids)} lack the model's feature(s) {', '.join(missing)} (from "
            "another model's feature set)",
            path=path,
        )
    values = rows[list(predictor.features)].to_numpy(dtype=np.float64)
    bad = ~np.isfinite(values).all(axis=1)
    if bad.any():
        raise InputDataError(
            f"rows {format_ids(ids[bad])} lack a value of the model's features "
            f"({', '.join(predictor.features)})",
            path=path,
        )
    if "converged" in rows.columns:
        unconverged = ~rows["converged"].astype(bool).to_numpy()
        if unconverged.any():
            raise InputDataError(
                f"rows {format_ids(ids[unconverged])}: the lift search did not converge (their "
                "L_f is only a bound); lift them again or leave them out",
                path=path,
            )
    refuse_impossible_rows(rows, "the rig rows", path=path)
    if len(rows) < MIN_ROWS:
        named = format_ids(ids) if len(ids) else "none"
        raise InputDataError(
            f"adapt needs at least {MIN_ROWS} rig rows; the table has {len(rows)} ({named})",
            path=path,
        )
    return rows.reset_index(drop=True)


@dataclasses.dataclass(frozen=True)
class AdaptResult:
    """What :func:`adapt_model` found.

    Attributes:
        predictor: the adapted predictor (numpy), as the written file loads.
        metadata: the adapted model file's metadata.
        alpha: the ridge penalty chosen (``inf``: no correction).
        loo_median_rel_error: the rig rows' median |L_f / L̂_f,(−i) − 1| with the correction.
        base_median_rel_error: the same of the base model (no correction).
    """

    predictor: Predictor
    metadata: dict[str, Any]
    alpha: float
    loo_median_rel_error: float
    base_median_rel_error: float


def _scaled_inputs(predictor: Predictor, rows: Any) -> np.ndarray:
    W, D, lam = (rows[c].to_numpy(dtype=np.float64) for c in predictor.features[:3])
    groups = predictor._groups(W, D, lam)
    return np.asarray((groups - predictor.mean) / predictor.scale)


def adapt_model(model: str, index: Any, *, index_path: str = "index") -> AdaptResult:
    """Correct ``model`` (a grip model file or a bundled name) with the rig rows of ``index``.

    Raises:
        InputDataError: see :func:`rig_rows`; a base model file that cannot be read (65).
    """
    base = Predictor.load(model)
    rows = rig_rows(index, base, index_path)
    W, D, lam, mu = (rows[c].to_numpy(dtype=np.float64) for c in base.features)
    y_true = rows["lift_force_n"].to_numpy(dtype=np.float64)
    before = base.predict_many(W, D, lam, mu).lift_force_n
    _refuse_non_positive(rows, before, "the base model's prediction", str(base.path))
    X = np.column_stack([np.ones(len(rows)), _scaled_inputs(base, rows)])
    residual = np.log(y_true / before)
    coef, alpha, loo = ridge_loo(X, residual)
    with np.errstate(over="ignore", invalid="ignore"):
        after = before * np.exp(X @ coef)
    _refuse_non_positive(rows, after, "the adapted prediction", index_path)
    scores = np.exp(loo) - 1.0  # L_f / L̂_f,(−i) − 1
    meta = dict(base.metadata)
    export = dict(meta["numpy_model"])
    export["correction"] = [float(c) for c in coef]
    meta["numpy_model"] = export
    meta["conformal_scores"] = [float(s) for s in scores]
    meta["conformal_digest"] = scores_digest(meta["conformal_scores"])  # grip.sanity
    meta["target_range"] = _widened_targets(meta, y_true / rigid_grip_force_n(W, mu))
    meta["conformal"] = {}
    meta["n_calibration"] = len(rows)
    check = dict(meta.get("check_points") or {})
    adapted = Predictor.from_export(export, meta, base.path, check_points=False)
    if check.get("inputs") is not None:
        inputs = np.asarray(check["inputs"], dtype=np.float64)
        check["lift_force_n"] = [float(v) for v in adapted._lift_force(inputs)]
        meta["check_points"] = check
    meta["adapted"] = {
        "base_model": model,
        "index": index_path,
        "correction": "log(L_f / F_w) += c0 + c . x (x: the network's scaled inputs)",
        "coefficients": [float(c) for c in coef],
        "alpha": None if math.isinf(alpha) else alpha,
        "alpha_rule": "leave-one-out mean squared error over ALPHAS and inf (no correction)",
        "bound_rule": BOUND_RULE,
        "rows": [
            {
                "object_id": str(oid),
                "lift_force_n": float(t),
                "predicted_before_n": float(b),
                "predicted_after_n": float(a),
                "loo_score": float(s),
            }
            for oid, t, b, a, s in zip(
                rows["object_id"], y_true, before, after, scores, strict=True
            )
        ],
    }
    adapted = Predictor.from_export(export, meta, base.path, check_points=False)
    return AdaptResult(
        predictor=adapted,
        metadata=meta,
        alpha=alpha,
        loo_median_rel_error=float(np.median(np.abs(scores))),
        base_median_rel_error=float(np.median(np.abs(y_true / before - 1.0))),
    )


def _widened_targets(meta: dict[str, Any], rig_ratio: np.ndarray) -> dict[str, list[float]]:
    """The base model's training targets' L_f / F_w range widened to the rig rows' (a
    prediction far outside both is flagged, :mod:`deformctl.grip.sanity`)."""
    from deformctl.grip.sanity import target_ratio_range

    base = target_ratio_range(meta)
    low, high = float(rig_ratio.min()), float(rig_ratio.max())
    if base is not None:
        low, high = min(low, base[0]), max(high, base[1])
    return {"lift_ratio_f_w": [low, high]}


def _refuse_non_positive(rows: Any, forces: np.ndarray, what: str, path: str) -> None:
    """Refuse (65) when a force about to be fitted, stored or printed is not finite and > 0.

    Raises:
        InputDataError: ``rows A, B: <what> is not a finite force > 0 (inf N)``.
    """
    from deformctl.table import format_ids

    bad = ~(np.isfinite(forces) & (forces > 0))
    if bad.any():
        ids = rows["object_id"].astype(str).to_numpy()
        raise InputDataError(
            f"rows {format_ids(ids[bad])}: {what} is not a finite force > 0 "
            f"({forces[bad][0]:.6g} N); nothing written",
            path=path,
        )


def model_file_bytes(base: str, metadata: dict[str, Any]) -> bytes:
    """The base model file (a skops archive) with its metadata replaced by ``metadata``."""
    path = resolve_model_path(base)
    read_model_metadata(path)  # a deformctl model file, or exit 65
    out = io.BytesIO()
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            data = src.read(info)
            if info.filename == "schema.json":
                schema = json.loads(data)
                node = schema["content"]["metadata_json"]
                node["content"] = json.dumps(json.dumps(metadata, allow_nan=True))
                data = json.dumps(schema).encode()
            dst.writestr(info, data)
    return out.getvalue()


def write_adapted(result: AdaptResult, base: str, output: str, *, force: bool = False) -> None:
    """Write the adapted model file atomically.

    Raises:
        OutputExistsError: ``output`` exists and ``force`` is false.
    """
    from deformctl.artifacts.io import atomic_output

    data = model_file_bytes(base, result.metadata)
    with atomic_output(output, force=force) as tmp:
        tmp.write_bytes(data)


def describe_rows(rows: Sequence[dict[str, Any]]) -> list[str]:
    """One line per adapting row: its L_f, and the prediction before and after."""
    return [
        f"{r['object_id']}: L_f {r['lift_force_n']:.4g} N, predicted {r['predicted_before_n']:.4g}"
        f" N before, {r['predicted_after_n']:.4g} N after (leave-one-out score "
        f"{100 * r['loo_score']:+.1f} %)"
        for r in rows
    ]
