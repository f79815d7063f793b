"""The lifting-force model: (W, D, λ) -> L_f with the paper's 3-2-1 network, metrics, baselines.

The paper (section V.A) trains a network with 3 inputs (weight, deformability, damping), one
hidden layer of 2 nodes and 1 output (the minimum lifting force) on 40 objects and tests it on 33.
Here the network is scikit-learn's ``Pipeline(StandardScaler, MLPRegressor)``; everything about
it is chosen for a tiny data set and a tiny network:

* **Target normalisation.** Physics says ``L_f = F_w + F_d`` with ``F_w = W / (2 μ)``: the force
  grows with the weight, and the dynamic surplus ``F_d`` is a *fraction* of it that depends on
  how soft and how damped the object is. So the network learns the dimensionless ratio
  ``L_f / W`` and the model multiplies its output by the input W again
  (:class:`ScaledTargetRegressor`). The inputs are still exactly (W, D, λ), unscaled, and the
  core is still ``Pipeline(StandardScaler, MLPRegressor)`` (``model.regressor_``). With 2 hidden
  nodes this matters: the product ``W · r(W, D, λ)`` is hard to express as a sum of two
  ``tanh`` units, the ratio ``r`` is not. On the synthetic data of the tests (10 populations)
  it halves the median relative test error compared to fitting L_f directly (0.6 % vs 1.1 %),
  and the direct fit failed on one population (max error 37 %) where the ratio fit did not.
* **Solver.** ``lbfgs`` (full-batch quasi-Newton): on 40 samples and 11 weights it converges in a
  few hundred iterations to a much better minimum than ``adam``/``sgd`` in thousands of epochs.
* **Activation.** ``tanh``: smooth and zero-centred, suits standardized inputs.
* **Restarts.** A 2-node network has poor local minima, so :func:`train_model` fits
  ``restarts`` networks from seeded initialisations and keeps the one with the smallest RMS
  relative error **on the training rows** (the test rows are never looked at).
* **alpha** (L2 penalty) small (1e-4): 11 weights on 40 rows cannot overfit much.
* **One BLAS thread** while fitting and predicting (``threadpoolctl``): the matrices are
  ``[40, 3]``, threads only cost time, and a fixed thread count keeps results bit-identical.
  The BLAS kernel is another matter: OpenBLAS picks one per CPU, and ``lbfgs`` amplifies its
  last bits (``make golden-spread``: the chosen restart and the test errors move between
  kernels), so ``metrics["blas"]`` records the libraries, kernels and thread count of the fit
  (:func:`deformctl.blas.blas_info`); the model file and ``--metrics`` keep it.

Everything random is seeded from ``seed``: the train/test split (a permutation of the rows
sorted by ``object_id``) and the restarts' initial weights, so the same table and seed give
bit-identical predictions.

Metrics (:func:`regression_metrics`) are fractions, not percent: ``max_rel_error``,
``median_rel_error`` (of ``|pred - true| / |true|``), ``mae_n`` (N) and ``r2``. Three baselines
are scored on the same split: ``nearest`` (the nearest *training* row of the index table in
standardized units, see :mod:`deformctl.table`; for training rows leave-one-out), ``f_w``
(``F_w = W / (2 μ)`` alone) and ``constant_ratio`` (``F_w`` times the median of ``L_f / F_w`` over
the training rows: what a model that ignores D and λ can do; a network is only worth having
when it beats this one).
"""

from __future__ import annotations

import itertools
import math
import warnings
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import pandas as pd
from sklearn.exceptions import ConvergenceWarning
from sklearn.utils.validation import check_is_fitted
from threadpoolctl import threadpool_limits

from deformctl.blas import blas_info
from deformctl.catalog import rigid_grip_force_n
from deformctl.errors import InputDataError, SchemaError, UsageError
from deformctl.grip.conformal import coverage_report, relative_scores, scores_digest
from deformctl.grip.groups import (
    GRIP_FEATURES,
    NEGATIVE_DAMPING_TOLERANCE_NS_PER_CM,
    group_values,
)
from deformctl.grip.model import DEFAULT_GRIP_HIDDEN, GripForceRegressor, make_grip_model
from deformctl.model import (
    DEFAULT_HIDDEN,
    DEFAULT_TRAIN,
    FEATURES,
    TARGET,
    ScaledTargetRegressor,
    TrainOptions,
    make_model,
)
from deformctl.reprs import short_repr
from deformctl.table import (
    format_ids,
    refuse_impossible_rows,
    standard_scales,
    standardized_distances,
)

#: ``paper``: the paper's network on (W, D, λ) (a table with one μ); ``grip``: L_f / F_w from
#: the groups (ω_n, ζ), μ as an input (:class:`deformctl.grip.model.GripForceRegressor`).
ModelForm = Literal["paper", "grip"]
#: How many training rows ``train`` stores with their predictions, for checking a loaded model.
N_CHECK_POINTS = 5


def model_form(table: pd.DataFrame) -> ModelForm:
    """``"grip"`` when the table's ``friction_mu`` varies, else ``"paper"``."""
    if "friction_mu" not in table.columns:
        return "paper"
    mu = pd.to_numeric(table["friction_mu"], errors="coerce").to_numpy(dtype=np.float64)
    finite = mu[np.isfinite(mu)]
    return "grip" if finite.size and not np.all(finite == finite[0]) else "paper"


def regression_metrics(y_true: np.ndarray, y_pred: np.ndarray) -> dict[str, float]:
    """Max and median relative error (fractions), MAE (N) and R² of ``[n]`` forces.

    R² is NaN when ``y_true`` has no spread or fewer than 2 values.
    """
    t = np.asarray(y_true, dtype=np.float64)
    p = np.asarray(y_pred, dtype=np.float64)
    rel = np.abs(p - t) / np.abs(t)
    ss_tot = float(np.sum((t - t.mean()) ** 2))
    r2 = 1.0 - float(np.sum((t - p) ** 2)) / ss_tot if len(t) > 1 and ss_tot > 0 else math.nan
    return {
        "max_rel_error": float(rel.max()),
        "median_rel_error": float(np.median(rel)),
        "mae_n": float(np.mean(np.abs(p - t))),
        "r2": r2,
        "n": len(t),
    }


@dataclass(frozen=True)
class Split:
    """The train/calibration/test split, as object ids in the order the permutation drew them."""

    __repr__ = short_repr

    train: tuple[str, ...]
    test: tuple[str, ...]
    calibration: tuple[str, ...] = ()


@dataclass(frozen=True)
class TrainResult:
    """What :func:`train_model` returns.

    Attributes:
        model: the fitted :class:`ScaledTargetRegressor` (paper form) or
            :class:`~deformctl.grip.model.GripForceRegressor` (grip form); its core
            ``model.regressor_`` is ``Pipeline(StandardScaler, MLPRegressor)``.
        metrics: JSON-friendly dict: seed, hyper-parameters, features, split sizes, the restarts'
            training losses and the chosen one, and ``model`` / ``baseline_nearest`` /
            ``baseline_f_w`` metrics, each ``{"train": {...}, "test": {...}}``; ``blas``:
            the BLAS libraries, kernels and thread count of the fit (:func:`~deformctl.blas.
            blas_info`).
        split: train / calibration / test object ids.
        predictions: one row per object: ``object_id``, ``split`` (train, calibration, test), the
            features, ``lift_force_n``, ``predicted_lift_force_n``, ``rel_error``,
            ``nearest_lift_force_n``, ``f_w_n`` (NaN when unknown).
        training_range: feature (and, grip form, group) -> (min, max) over the training rows.
        calibration_scores: the relative scores ``(L_f - pred) / pred`` of the calibration rows
            (:mod:`deformctl.grip.conformal`), empty without calibration rows.
    """

    __repr__ = short_repr

    model: ScaledTargetRegressor | GripForceRegressor
    metrics: dict[str, Any]
    split: Split
    predictions: pd.DataFrame
    training_range: dict[str, tuple[float, float]] = field(default_factory=dict)
    calibration_scores: tuple[float, ...] = ()


def _validate_table(
    table: pd.DataFrame,
    train_size: int,
    features: tuple[str, ...] = FEATURES,
    calibration_size: int = 0,
) -> pd.DataFrame:
    for col in ("object_id", *features, TARGET):
        if col not in table.columns:
            raise SchemaError(f"the index table has no column {col!r}", field=col)
    n = len(table)
    if n < train_size + calibration_size + 1:
        what = (
            f"{train_size} train + {calibration_size} calibration"
            if calibration_size
            else (f"{train_size} train")
        )
        raise InputDataError(
            f"the index table has {n} rows; a training set of {train_size} needs at least "
            f"{train_size + calibration_size + 1} ({what} + at least 1 test)"
        )
    ids = table["object_id"].astype(str)
    dup = sorted(ids[ids.duplicated()].unique())
    if dup:
        raise InputDataError(f"the index table lists object(s) more than once: {format_ids(dup)}")
    for col in (*features, TARGET):
        values = pd.to_numeric(table[col], errors="coerce").to_numpy(dtype=np.float64)
        bad = ~np.isfinite(values)
        if bad.any():
            raise InputDataError(
                f"{col} is NaN or not a finite number for {bad.sum()} row(s): "
                f"{format_ids(ids[bad])}"
            )
    positive: tuple[str, ...] = ("weight_n", TARGET)
    if "friction_mu" in features:
        positive = ("weight_n", "deformability_n_per_cm", "friction_mu", TARGET)
    for col in positive:
        bad = table[col].to_numpy(dtype=np.float64) <= 0
        if bad.any():
            raise InputDataError(f"{col} must be > 0; it is not for {format_ids(ids[bad])}")
    if "friction_mu" in features:
        lam = table["damping_ns_per_cm"].to_numpy(dtype=np.float64)
        bad = lam < -NEGATIVE_DAMPING_TOLERANCE_NS_PER_CM
        if bad.any():
            raise InputDataError(
                f"damping_ns_per_cm must be >= 0 (a fit's -{NEGATIVE_DAMPING_TOLERANCE_NS_PER_CM:g}"
                f" reads as 0); it is {lam[bad][0]:g} for {format_ids(ids[bad])}"
            )
    refuse_impossible_rows(table, "the index table")  # L_f below F_w or absurd, D <= 0, λ < 0
    for col in features:
        values = table[col].to_numpy(dtype=np.float64)
        if np.all(values == values[0]):
            raise InputDataError(
                f"feature {col} is constant ({values[0]:g}) over the index table; "
                "the model cannot learn its effect"
            )
    out = table.copy()
    out["object_id"] = ids
    return out.sort_values("object_id", kind="stable").reset_index(drop=True)


def _f_w(table: pd.DataFrame) -> np.ndarray:
    """F_w per row: the ``f_w_n`` column, else W / (2 μ), else NaN."""
    if "f_w_n" in table.columns:
        return table["f_w_n"].to_numpy(dtype=np.float64)
    if "friction_mu" in table.columns:
        return rigid_grip_force_n(
            table["weight_n"].to_numpy(dtype=np.float64),
            table["friction_mu"].to_numpy(dtype=np.float64),
        )
    return np.full(len(table), np.nan)


def _target_range(lift_force_n: np.ndarray, f_w_n: np.ndarray) -> dict[str, list[float]]:
    """The training targets' L_f / F_w range, ``{"lift_ratio_f_w": [low, high]}`` (empty
    without F_w): a prediction far outside it is flagged (:mod:`deformctl.grip.sanity`)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.asarray(lift_force_n, dtype=np.float64) / np.asarray(f_w_n, dtype=np.float64)
    ratio = ratio[np.isfinite(ratio) & (ratio > 0)]
    return {"lift_ratio_f_w": [float(ratio.min()), float(ratio.max())]} if ratio.size else {}


def constant_ratio(lift_force_n: np.ndarray, f_w_n: np.ndarray) -> float:
    """The median of ``L_f / F_w`` over the rows where both are finite (NaN when there are none)."""
    ratio = np.asarray(lift_force_n, dtype=np.float64) / np.asarray(f_w_n, dtype=np.float64)
    ratio = ratio[np.isfinite(ratio)]
    return float(np.median(ratio)) if ratio.size else math.nan


def _nearest_baseline(
    train: pd.DataFrame, test: pd.DataFrame, *, ratio: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """Nearest training row's L_f for test rows, and leave-one-out for training rows.

    Nearest in standardized (W, D, λ). With ``ratio`` (the grip form, whose rows have other μ)
    the entry's L_f / F_w times the row's own F_w, as ``lift --start-table`` predicts.
    """
    scales = standard_scales(train)
    y_train = train[TARGET].to_numpy(dtype=np.float64)
    d_test = standardized_distances(train, test[list(FEATURES)].to_numpy(), scales)
    d_train = standardized_distances(train, train[list(FEATURES)].to_numpy(), scales)
    np.fill_diagonal(d_train, np.inf)
    i_train, i_test = np.argmin(d_train, axis=1), np.argmin(d_test, axis=1)
    if not ratio:
        return y_train[i_train], y_train[i_test]
    r = y_train / _f_w(train)
    return r[i_train] * _f_w(train), r[i_test] * _f_w(test)


def _rms_rel_error(model: Any, X: pd.DataFrame, y: np.ndarray) -> float:
    rel = (model.predict(X) - y) / y
    return float(np.sqrt(np.mean(rel * rel)))


def _check_points(model: Any, X: pd.DataFrame) -> dict[str, Any]:
    """The first :data:`N_CHECK_POINTS` training rows and the model's predictions for them."""
    rows = X.iloc[:N_CHECK_POINTS]
    with threadpool_limits(limits=1):
        pred = model.predict(rows)
    return {
        "inputs": rows.to_numpy(dtype=np.float64).tolist(),
        "lift_force_n": [float(v) for v in pred],
    }


def _training_range(
    model: Any, form: ModelForm, features: tuple[str, ...], X: pd.DataFrame
) -> dict[str, tuple[float, float]]:
    """Feature -> (min, max) over the training rows; the grip form adds its groups' ranges."""
    out = {
        col: (float(lo), float(hi))
        for col, lo, hi in zip(features, model.feature_min_, model.feature_max_, strict=True)
    }
    if form == "grip":  # λ below 0 (a fit's noise) counts as 0, in the range as in the model
        lam = X["damping_ns_per_cm"].to_numpy(dtype=np.float64)
        out["damping_ns_per_cm"] = (float(max(lam.min(), 0.0)), float(max(lam.max(), 0.0)))
        w, d, lam, mu = (X[c].to_numpy(dtype=np.float64) for c in GRIP_FEATURES)
        omega, zeta = group_values(w, d, lam)
        compression = rigid_grip_force_n(w, mu) / d
        for name, values in (
            ("natural_frequency_rad_s", omega),
            ("damping_ratio", zeta),
            ("compression_at_f_w_cm", compression),
        ):
            out[name] = (float(values.min()), float(values.max()))
    return out


def train_model(
    index_table: pd.DataFrame,
    options: TrainOptions = DEFAULT_TRAIN,
    *,
    form: ModelForm | None = None,
) -> TrainResult:
    """Train the lifting-force model on a seeded split of ``index_table`` and score it.

    Two forms (:func:`model_form` chooses when ``form`` is None):

    * ``paper`` (the table has one μ): the paper's network on (W, D, λ), learning L_f / W
      (:class:`ScaledTargetRegressor`);
    * ``grip`` (μ varies): inputs (W, D, λ, μ), the network learns log(L_f / F_w) from the
      dimensionless groups (ω_n, ζ) (:class:`~deformctl.grip.model.GripForceRegressor`).

    The rows (sorted by ``object_id``) are split by a seeded permutation: the first
    ``train_size`` train the network, the next ``calibration_size`` are held out to calibrate
    the split-conformal bound (:mod:`deformctl.grip.conformal`; their relative scores are
    returned and stored in the model file), the rest are the test rows, on which the metrics,
    the baselines and the bound's empirical coverage (P = 0.9, 0.95) are reported.

    Args:
        index_table: an index table (:mod:`deformctl.table`): ``object_id``, the features,
            :data:`TARGET`, and ``f_w_n`` or ``friction_mu`` for the F_w baseline.
        options: the split, the seed, the network and its fit
            (:class:`~deformctl.model.TrainOptions`, checked when it was built).
        form: ``"paper"``, ``"grip"`` or None (by the table).

    Returns:
        A :class:`TrainResult`.

    Raises:
        UsageError: an unknown form, or a solver or activation scikit-learn refuses.
        SchemaError: a required column is missing.
        InputDataError: too few rows, a duplicated object, a NaN or non-finite feature or
            lifting force, a non-positive weight or lifting force (grip form: also D, μ; a λ
            below -0.05 N·s/cm), or a constant feature column (the message names it).
    """
    if form not in (None, "paper", "grip"):
        raise UsageError(f"form must be 'paper' or 'grip', got {form!r}")
    o = options
    train_size, calibration_size, restarts = o.train_size, o.calibration_size, o.restarts
    chosen: ModelForm = form or model_form(index_table)
    features = GRIP_FEATURES if chosen == "grip" else FEATURES
    hidden = o.hidden or (DEFAULT_GRIP_HIDDEN if chosen == "grip" else DEFAULT_HIDDEN)
    table = _validate_table(index_table, train_size, features, calibration_size)

    rng = np.random.default_rng(o.seed)
    order = rng.permutation(len(table))
    restart_seeds = [int(s) for s in rng.integers(0, 2**31 - 1, size=restarts)]
    n_fit = train_size + calibration_size
    train = table.iloc[order[:train_size]].reset_index(drop=True)
    calib = table.iloc[order[train_size:n_fit]].reset_index(drop=True)
    test = table.iloc[order[n_fit:]].reset_index(drop=True)
    # μ is constant on purpose in a paper-form table; every other feature must vary
    for col in (c for c in features if c != "friction_mu"):
        values = train[col].to_numpy(dtype=np.float64)
        if np.all(values == values[0]):
            raise InputDataError(
                f"feature {col} is constant ({values[0]:g}) over the {train_size} training rows"
            )

    X_train = train[list(features)].astype(np.float64)
    X_calib = calib[list(features)].astype(np.float64)
    X_test = test[list(features)].astype(np.float64)
    y_train = train[TARGET].to_numpy(dtype=np.float64)
    y_calib = calib[TARGET].to_numpy(dtype=np.float64)
    y_test = test[TARGET].to_numpy(dtype=np.float64)

    params: dict[str, Any] = {
        "hidden": [int(h) for h in hidden],
        "activation": o.activation,
        "solver": o.solver,
        "alpha": float(o.alpha),
        "max_iter": int(o.max_iter),
        "tol": float(o.tol),
        "restarts": int(restarts),
        "target": o.target if chosen == "paper" else "log_ratio_f_w",
    }
    losses: list[float] = []
    best: ScaledTargetRegressor | GripForceRegressor | None = None
    best_loss = math.inf
    best_index = -1
    best_converged = False
    for i, rs in enumerate(restart_seeds):
        candidate: ScaledTargetRegressor | GripForceRegressor = (
            make_grip_model(o, random_state=rs)
            if chosen == "grip"
            else make_model(o, random_state=rs)
        )
        # One BLAS thread: the matrices are tiny, so threads only add overhead (20x slower on a
        # loaded 2-core machine) and a thread-count-dependent summation order.
        with warnings.catch_warnings(record=True) as caught, threadpool_limits(limits=1):
            warnings.simplefilter("always", ConvergenceWarning)
            try:
                candidate.fit(X_train, y_train)
            except ValueError as err:  # e.g. an invalid solver / activation name
                raise UsageError(f"cannot train the network: {err}") from None
            loss = _rms_rel_error(candidate, X_train, y_train)
        losses.append(loss)
        if loss < best_loss:  # strict: ties keep the earlier restart
            best, best_loss, best_index = candidate, loss, i
            best_converged = not any(issubclass(w.category, ConvergenceWarning) for w in caught)
    assert best is not None

    with threadpool_limits(limits=1):
        pred_train = best.predict(X_train)
        pred_calib = best.predict(X_calib) if len(X_calib) else np.empty(0)
        pred_test = best.predict(X_test)
        blas = blas_info()  # the kernel and the 1 thread the fit and these predictions ran on
    nn_train, nn_test = _nearest_baseline(train, test, ratio=chosen == "grip")
    fw_train, fw_test = _f_w(train), _f_w(test)
    ratio = constant_ratio(y_train, fw_train)
    cr_train, cr_test = ratio * fw_train, ratio * fw_test

    def both(p_train: np.ndarray, p_test: np.ndarray) -> dict[str, dict[str, float]] | None:
        if not (np.isfinite(p_train).all() and np.isfinite(p_test).all()):
            return None
        return {
            "train": regression_metrics(y_train, p_train),
            "test": regression_metrics(y_test, p_test),
        }

    training_range = _training_range(best, chosen, features, X_train)
    scores: tuple[float, ...] = ()
    conformal = None
    if calibration_size:
        if not (np.all(np.isfinite(pred_calib)) and np.all(pred_calib > 0)):
            raise InputDataError("the network predicts a lifting force <= 0 for a calibration row")
        scores = tuple(float(v) for v in relative_scores(y_calib, pred_calib))
        conformal = coverage_report(np.asarray(scores), y_test, pred_test)
    mu_values = table["friction_mu"].to_numpy(dtype=np.float64) if "friction_mu" in table else None
    single_mu = (
        float(mu_values[0])
        if mu_values is not None
        and np.all(np.isfinite(mu_values))
        and np.all(mu_values == mu_values[0])
        else None
    )
    lam_all = table["damping_ns_per_cm"].to_numpy(dtype=np.float64)
    metrics: dict[str, Any] = {
        "seed": int(o.seed),
        "form": chosen,
        "hyperparameters": params,
        "features": list(features),
        "target": TARGET,
        "n_rows": len(table),
        "n_train": len(train),
        "n_calibration": len(calib),
        "n_test": len(test),
        "restart_seeds": restart_seeds,
        "restart_train_rms_rel_error": losses,
        "chosen_restart": best_index,
        "n_iter": int(best.regressor_[-1].n_iter_),
        "converged": bool(best_converged),
        "training_range": {k: list(v) for k, v in training_range.items()},
        "training_friction_mu": single_mu,
        "target_range": _target_range(y_train, fw_train),
        "negative_damping_read_as_zero": int(np.sum(lam_all < 0)) if chosen == "grip" else 0,
        "model": both(pred_train, pred_test),
        "baseline_nearest": both(nn_train, nn_test),
        "baseline_f_w": both(fw_train, fw_test),
        "baseline_constant_ratio": both(cr_train, cr_test),
        "constant_ratio": None if not math.isfinite(ratio) else ratio,
        "conformal": conformal,
        "blas": blas,
    }

    frames = []
    parts = [
        ("train", train, pred_train, nn_train, fw_train, cr_train),
        ("test", test, pred_test, nn_test, fw_test, cr_test),
    ]
    if len(calib):
        fw_calib = _f_w(calib)
        nan = np.full(len(calib), np.nan)
        parts.insert(1, ("calibration", calib, pred_calib, nan, fw_calib, ratio * fw_calib))
    for name, part, pred, nn, fw, cr in parts:
        y = part[TARGET].to_numpy(dtype=np.float64)
        frames.append(
            pd.DataFrame(
                {
                    "object_id": part["object_id"].to_numpy(),
                    "split": name,
                    **{col: part[col].to_numpy(dtype=np.float64) for col in features},
                    TARGET: y,
                    "predicted_lift_force_n": pred,
                    "rel_error": np.abs(pred - y) / y,
                    "nearest_lift_force_n": nn,
                    "f_w_n": fw,
                    "constant_ratio_lift_force_n": cr,
                }
            )
        )
    predictions = pd.concat(frames, ignore_index=True)
    return TrainResult(
        model=best,
        metrics=metrics,
        split=Split(
            train=tuple(train["object_id"].tolist()),
            test=tuple(test["object_id"].tolist()),
            calibration=tuple(calib["object_id"].tolist()),
        ),
        predictions=predictions,
        training_range=training_range,
        calibration_scores=scores,
    )


def model_metadata(result: TrainResult) -> dict[str, Any]:
    """What a model file stores besides the estimator: :func:`train_report` without the
    per-row predictions, plus the numpy export (:mod:`deformctl.grip.export`), the check points
    (a few training rows and their predictions, which a loaded model must reproduce) and the
    calibration scores (when there were calibration rows)."""
    from deformctl.grip.export import export_model

    report = train_report(result)
    meta = {k: v for k, v in report.items() if k != "predictions"}
    features = list(result.metrics["features"])
    X = result.predictions.loc[result.predictions["split"] == "train", features]
    meta["numpy_model"] = export_model(result.model)
    meta["check_points"] = _check_points(result.model, X.astype(np.float64))
    if result.calibration_scores:
        meta["conformal_scores"] = list(result.calibration_scores)
        meta["conformal_digest"] = scores_digest(meta["conformal_scores"])  # grip.sanity
    return meta


@dataclass(frozen=True)
class Prediction:
    """What :func:`predict` returns.

    Attributes:
        frame: the input's ``object_id`` (when present) and :data:`FEATURES`, plus
            ``predicted_lift_force_n`` (N) and ``outside_training_range`` (bool).
        warnings: one line per input row outside the training range, naming the feature(s).
    """

    __repr__ = short_repr

    frame: pd.DataFrame
    warnings: list[str]


def predict(model: ScaledTargetRegressor, features: pd.DataFrame) -> Prediction:
    """Predict L_f for each row of ``features`` and flag rows outside the training range.

    Args:
        model: a fitted model from :func:`train_model` (or :func:`~deformctl.artifacts.model.
            load_model`).
        features: rows with the :data:`FEATURES` columns (paper units); other columns are
            ignored except ``object_id``, which is carried over.

    Raises:
        UsageError: ``model`` is not a fitted lifting-force model.
        SchemaError: a feature column is missing.
        InputDataError: a feature is NaN / not finite, or a weight is not > 0.
    """
    if not isinstance(model, ScaledTargetRegressor):
        raise UsageError(f"not a lifting-force model: {type(model).__name__}")
    check_is_fitted(model)
    for col in FEATURES:
        if col not in features.columns:
            raise SchemaError(f"the input has no column {col!r}", field=col)
    names = (
        features["object_id"].astype(str).to_numpy()
        if "object_id" in features.columns
        else np.array([f"row {i}" for i in range(len(features))])
    )
    X = features[list(FEATURES)].apply(pd.to_numeric, errors="coerce").astype(np.float64)
    for col in FEATURES:
        bad = ~np.isfinite(X[col].to_numpy())
        if bad.any():
            raise InputDataError(
                f"{col} is NaN or not a finite number for {format_ids(names[bad])}"
            )
    bad = X["weight_n"].to_numpy() <= 0
    if bad.any():
        raise InputDataError(f"weight_n must be > 0; it is not for {format_ids(names[bad])}")

    with threadpool_limits(limits=1):
        pred = model.predict(X) if len(X) else np.empty(0)
    values = X.to_numpy()
    lo, hi = model.feature_min_, model.feature_max_
    outside = (values < lo) | (values > hi)
    messages: list[str] = []
    for i in np.flatnonzero(outside.any(axis=1)):
        parts = [
            f"{col} = {values[i, j]:g} not in [{lo[j]:g}, {hi[j]:g}]"
            for j, col in enumerate(FEATURES)
            if outside[i, j]
        ]
        messages.append(f"{names[i]}: outside the training range: {'; '.join(parts)}")
    frame = pd.DataFrame({col: X[col].to_numpy() for col in FEATURES})
    if "object_id" in features.columns:
        frame.insert(0, "object_id", names)
    frame["predicted_lift_force_n"] = pred
    frame["outside_training_range"] = outside.any(axis=1)
    return Prediction(frame=frame, warnings=messages)


#: The most weights (and biases) a network may have, the default of ``train --max-parameters``:
#: the paper's 3-2-1 network has 11, a generous 64,64 one 4,481; ``--hidden 100000000`` (400
#: million weights, 8 restarts) used to run until the kernel killed it.
MAX_PARAMETERS = 100_000


def parameter_count(hidden: tuple[int, ...], n_features: int = 3) -> int:
    """Weights and biases of an MLP with ``hidden`` layers on ``n_features`` inputs, one output."""
    sizes = [n_features, *hidden, 1]
    return sum((a + 1) * b for a, b in itertools.pairwise(sizes))


def parse_notes(notes: list[str] | None) -> dict[str, str]:
    """``KEY=VALUE`` pairs of ``train --note`` (exit 2 for a note without ``=`` or an empty key)."""
    out: dict[str, str] = {}
    for note in notes or []:
        key, sep, value = note.partition("=")
        if not sep or not key.strip():
            raise UsageError(f"--note takes KEY=VALUE, got {note!r}")
        out[key.strip()] = value.strip()
    return out


def parse_hidden(text: str, *, max_parameters: int = MAX_PARAMETERS) -> tuple[int, ...]:
    """Hidden layer sizes from ``"2"`` or a comma list such as ``"8,4"`` (each size's rule is
    checked where they are used, by :class:`~deformctl.model.TrainOptions`).

    Raises:
        UsageError: an empty list, an item that is not an integer, or a network of more than
            ``max_parameters`` weights (checked before anything is allocated).
    """
    items = [s.strip() for s in str(text).split(",")]
    sizes: list[int] = []
    for item in items:
        try:
            size = int(item)
        except ValueError:
            raise UsageError(
                f"hidden layer sizes must be integers like 2 or 8,4; got {text!r}"
            ) from None
        sizes.append(size)
    n_weights = parameter_count(tuple(sizes))
    if n_weights > max_parameters:
        raise UsageError(
            f"--hidden {text}: the network has {n_weights:,} weights, above the budget of "
            f"{max_parameters:,} (raise it with --max-parameters)"
        )
    return tuple(sizes)


def json_safe(value: Any) -> Any:
    """A copy of ``value`` that strict JSON accepts: NaN/inf -> None, numpy scalars -> Python."""
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def train_report(result: TrainResult) -> dict[str, Any]:
    """Everything :func:`train_model` measured, as strict-JSON data (NaN -> null).

    Returns:
        ``result.metrics`` plus ``split`` (``{"train": [ids], "test": [ids]}``) and
        ``predictions``: one record per object with ``object_id``, ``split``, ``lift_force_n``,
        ``predicted_lift_force_n``, ``rel_error``, ``nearest_lift_force_n``, ``f_w_n`` and
        ``constant_ratio_lift_force_n``.
    """
    cols = [
        "object_id",
        "split",
        TARGET,
        "predicted_lift_force_n",
        "rel_error",
        "nearest_lift_force_n",
        "f_w_n",
        "constant_ratio_lift_force_n",
    ]
    records = result.predictions[cols].to_dict("records")
    return json_safe(
        {
            **result.metrics,
            "split": {
                "train": list(result.split.train),
                "calibration": list(result.split.calibration),
                "test": list(result.split.test),
            },
            "predictions": records,
        }
    )


def train_with_laws(
    table: pd.DataFrame, laws: pd.DataFrame | None, options: TrainOptions = DEFAULT_TRAIN
) -> tuple[TrainResult, dict[str, Any] | None, dict[str, Any]]:
    """``train`` (``laws`` None: :func:`train_model`) or ``train --laws``: the Kelvin–Voigt rows
    through :func:`train_model`, every other law's rows through its own network
    (:func:`deformctl.grip.lawtrain.train_laws`). Returns the result, the model file's ``laws``
    section (None without) and the metrics report (:func:`train_report`, with the laws')."""
    if laws is None:
        result, section = train_model(table, options), None
    else:
        from deformctl.grip.lawtrain import train_laws

        result, section = train_laws(table, laws, options, train_main=train_model)
    report = train_report(result)
    if section is not None:
        from deformctl.grip.lawtrain import law_report

        report["laws"] = law_report(section)
    return result, section, report
