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
from typing import Any

import numpy as np
import pandas as pd
from sklearn.exceptions import ConvergenceWarning
from sklearn.utils.validation import check_is_fitted
from threadpoolctl import threadpool_limits

from deformctl.catalog import catalog_weights, rigid_grip_force_n
from deformctl.errors import InputDataError, SchemaError, UsageError
from deformctl.model import (
    DEFAULT_ACTIVATION,
    DEFAULT_ALPHA,
    DEFAULT_HIDDEN,
    DEFAULT_MAX_ITER,
    DEFAULT_SOLVER,
    DEFAULT_TOL,
    FEATURES,
    TARGET,
    ScaledTargetRegressor,
    TargetMode,
    make_model,
)
from deformctl.reprs import short_repr
from deformctl.table import format_ids, standard_scales, standardized_distances

#: Defaults of :func:`train_model` besides the network's: the paper's split, our restarts.
DEFAULT_TRAIN_SIZE = 40
DEFAULT_RESTARTS = 8


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
    """The train/test split, as object ids in the order the seeded permutation drew them."""

    __repr__ = short_repr

    train: tuple[str, ...]
    test: tuple[str, ...]


@dataclass(frozen=True)
class TrainResult:
    """What :func:`train_model` returns.

    Attributes:
        model: the fitted :class:`ScaledTargetRegressor`; its core ``model.regressor_`` is
            ``Pipeline(StandardScaler, MLPRegressor)``.
        metrics: JSON-friendly dict: seed, hyper-parameters, features, split sizes, the restarts'
            training losses and the chosen one, and ``model`` / ``baseline_nearest`` /
            ``baseline_f_w`` metrics, each ``{"train": {...}, "test": {...}}``.
        split: train / test object ids.
        predictions: one row per object: ``object_id``, ``split`` ("train"/"test"), the
            features, ``lift_force_n``, ``predicted_lift_force_n``, ``rel_error``,
            ``nearest_lift_force_n``, ``f_w_n`` (NaN when unknown).
        training_range: feature -> (min, max) over the training rows.
    """

    __repr__ = short_repr

    model: ScaledTargetRegressor
    metrics: dict[str, Any]
    split: Split
    predictions: pd.DataFrame
    training_range: dict[str, tuple[float, float]] = field(default_factory=dict)


def _validate_table(table: pd.DataFrame, train_size: int) -> pd.DataFrame:
    for col in ("object_id", *FEATURES, TARGET):
        if col not in table.columns:
            raise SchemaError(f"the index table has no column {col!r}", field=col)
    n = len(table)
    if n < train_size + 1:
        raise InputDataError(
            f"the index table has {n} rows; a training set of {train_size} needs at least "
            f"{train_size + 1} ({train_size} train + at least 1 test)"
        )
    ids = table["object_id"].astype(str)
    dup = sorted(ids[ids.duplicated()].unique())
    if dup:
        raise InputDataError(f"the index table lists object(s) more than once: {format_ids(dup)}")
    for col in (*FEATURES, TARGET):
        values = pd.to_numeric(table[col], errors="coerce").to_numpy(dtype=np.float64)
        bad = ~np.isfinite(values)
        if bad.any():
            raise InputDataError(
                f"{col} is NaN or not a finite number for {bad.sum()} row(s): "
                f"{format_ids(ids[bad])}"
            )
    for col in ("weight_n", TARGET):
        bad = table[col].to_numpy(dtype=np.float64) <= 0
        if bad.any():
            raise InputDataError(f"{col} must be > 0; it is not for {format_ids(ids[bad])}")
    for col in FEATURES:
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


def constant_ratio(lift_force_n: np.ndarray, f_w_n: np.ndarray) -> float:
    """The median of ``L_f / F_w`` over the rows where both are finite (NaN when there are none)."""
    ratio = np.asarray(lift_force_n, dtype=np.float64) / np.asarray(f_w_n, dtype=np.float64)
    ratio = ratio[np.isfinite(ratio)]
    return float(np.median(ratio)) if ratio.size else math.nan


def _nearest_baseline(train: pd.DataFrame, test: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """Nearest training row's L_f for test rows, and leave-one-out for training rows."""
    scales = standard_scales(train)
    y_train = train[TARGET].to_numpy(dtype=np.float64)
    d_test = standardized_distances(train, test[list(FEATURES)].to_numpy(), scales)
    d_train = standardized_distances(train, train[list(FEATURES)].to_numpy(), scales)
    np.fill_diagonal(d_train, np.inf)
    return y_train[np.argmin(d_train, axis=1)], y_train[np.argmin(d_test, axis=1)]


def _rms_rel_error(model: ScaledTargetRegressor, X: pd.DataFrame, y: np.ndarray) -> float:
    rel = (model.predict(X) - y) / y
    return float(np.sqrt(np.mean(rel * rel)))


def train_model(
    index_table: pd.DataFrame,
    *,
    hidden: tuple[int, ...] = DEFAULT_HIDDEN,
    train_size: int = DEFAULT_TRAIN_SIZE,
    seed: int = 0,
    max_iter: int = DEFAULT_MAX_ITER,
    solver: str = DEFAULT_SOLVER,
    activation: str = DEFAULT_ACTIVATION,
    alpha: float = DEFAULT_ALPHA,
    tol: float = DEFAULT_TOL,
    restarts: int = DEFAULT_RESTARTS,
    target: TargetMode = "ratio",
) -> TrainResult:
    """Train the lifting-force model on a seeded split of ``index_table`` and score it.

    Args:
        index_table: an index table (:mod:`deformctl.table`): ``object_id``, :data:`FEATURES`,
            :data:`TARGET`, and ``f_w_n`` or ``friction_mu`` for the F_w baseline.
        hidden: hidden layer sizes; the paper's network is ``(2,)``.
        train_size: number of training rows (paper: 40); the rest is the test set.
        seed: seeds the split and the restarts' initial weights.
        max_iter, solver, activation, alpha, tol: passed to ``MLPRegressor``.
        restarts: number of seeded initialisations; the best on the training rows is kept.
        target: ``"ratio"`` (learn L_f / W, default) or ``"direct"`` (learn L_f).

    Returns:
        A :class:`TrainResult`.

    Raises:
        UsageError: a hyper-parameter out of range.
        SchemaError: a required column is missing.
        InputDataError: fewer than ``train_size + 1`` rows, a duplicated object, a NaN or
            non-finite feature or lifting force, a non-positive weight or lifting force, or a
            constant feature column (the message names it).
    """
    if train_size < 2:
        raise UsageError(f"train size must be >= 2, got {train_size}")
    if not hidden or any(int(h) < 1 for h in hidden):
        raise UsageError(f"hidden layer sizes must be >= 1, got {hidden}")
    if restarts < 1:
        raise UsageError(f"restarts must be >= 1, got {restarts}")
    if max_iter < 1:
        raise UsageError(f"max_iter must be >= 1, got {max_iter}")
    if target not in ("ratio", "direct"):
        raise UsageError(f"target must be 'ratio' or 'direct', got {target!r}")
    table = _validate_table(index_table, train_size)

    rng = np.random.default_rng(seed)
    order = rng.permutation(len(table))
    restart_seeds = [int(s) for s in rng.integers(0, 2**31 - 1, size=restarts)]
    train = table.iloc[order[:train_size]].reset_index(drop=True)
    test = table.iloc[order[train_size:]].reset_index(drop=True)
    for col in FEATURES:
        values = train[col].to_numpy(dtype=np.float64)
        if np.all(values == values[0]):
            raise InputDataError(
                f"feature {col} is constant ({values[0]:g}) over the {train_size} training rows"
            )

    X_train = train[list(FEATURES)].astype(np.float64)
    X_test = test[list(FEATURES)].astype(np.float64)
    y_train = train[TARGET].to_numpy(dtype=np.float64)
    y_test = test[TARGET].to_numpy(dtype=np.float64)

    params = {
        "hidden": [int(h) for h in hidden],
        "activation": activation,
        "solver": solver,
        "alpha": float(alpha),
        "max_iter": int(max_iter),
        "tol": float(tol),
        "restarts": int(restarts),
        "target": target,
    }
    losses: list[float] = []
    best: ScaledTargetRegressor | None = None
    best_loss = math.inf
    best_index = -1
    best_converged = False
    for i, rs in enumerate(restart_seeds):
        candidate = make_model(
            hidden=tuple(int(h) for h in hidden),
            activation=activation,
            solver=solver,
            alpha=alpha,
            max_iter=max_iter,
            tol=tol,
            random_state=rs,
            target=target,
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
        pred_test = best.predict(X_test)
    nn_train, nn_test = _nearest_baseline(train, test)
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

    training_range = {
        col: (float(lo), float(hi))
        for col, lo, hi in zip(FEATURES, best.feature_min_, best.feature_max_, strict=True)
    }
    metrics: dict[str, Any] = {
        "seed": int(seed),
        "hyperparameters": params,
        "features": list(FEATURES),
        "target": TARGET,
        "n_rows": len(table),
        "n_train": len(train),
        "n_test": len(test),
        "restart_seeds": restart_seeds,
        "restart_train_rms_rel_error": losses,
        "chosen_restart": best_index,
        "n_iter": int(best.regressor_[-1].n_iter_),
        "converged": bool(best_converged),
        "training_range": {k: list(v) for k, v in training_range.items()},
        "model": both(pred_train, pred_test),
        "baseline_nearest": both(nn_train, nn_test),
        "baseline_f_w": both(fw_train, fw_test),
        "baseline_constant_ratio": both(cr_train, cr_test),
        "constant_ratio": None if not math.isfinite(ratio) else ratio,
    }

    frames = []
    for name, part, pred, nn, fw, cr in (
        ("train", train, pred_train, nn_train, fw_train, cr_train),
        ("test", test, pred_test, nn_test, fw_test, cr_test),
    ):
        y = part[TARGET].to_numpy(dtype=np.float64)
        frames.append(
            pd.DataFrame(
                {
                    "object_id": part["object_id"].to_numpy(),
                    "split": name,
                    **{col: part[col].to_numpy(dtype=np.float64) for col in FEATURES},
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
            train=tuple(train["object_id"].tolist()), test=tuple(test["object_id"].tolist())
        ),
        predictions=predictions,
        training_range=training_range,
    )


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


def parse_hidden(text: str, *, max_parameters: int = MAX_PARAMETERS) -> tuple[int, ...]:
    """Hidden layer sizes from ``"2"`` or a comma list such as ``"8,4"``.

    Raises:
        UsageError: an empty list, an item that is not an integer, a size < 1, or a network of
            more than ``max_parameters`` weights (checked before anything is allocated).
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
        if size < 1:
            raise UsageError(f"hidden layer sizes must be >= 1, got {text!r}")
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
            "split": {"train": list(result.split.train), "test": list(result.split.test)},
            "predictions": records,
        }
    )


def prediction_inputs(table: pd.DataFrame, catalog: pd.DataFrame | None = None) -> pd.DataFrame:
    """The :data:`FEATURES` per object from a table, taking ``weight_n`` from ``catalog``.

    The table (an index table, a predictions table or a coefficients table) must have
    ``deformability_n_per_cm`` and ``damping_ns_per_cm``; ``weight_n`` comes from the table
    itself or, when ``catalog`` is given, from the catalog row with the same ``object_id``.
    When both have a weight they must agree (relative 1e-6).

    Args:
        table: ``[n]`` rows, with ``object_id`` when a catalog is to be joined.
        catalog: a validated object catalog (:func:`deformctl.artifacts.read_catalog`), or None.

    Returns:
        ``[n]`` rows in the table's order: ``object_id`` (when the table has it) and
        :data:`FEATURES`.

    Raises:
        SchemaError: a feature column is missing and cannot be joined; ``object_id`` missing
            when a catalog is given.
        InputDataError: an object missing from the catalog, or a weight that differs between
            the table and the catalog (the messages name the ids).
    """
    frame = table.copy()
    if catalog is not None:
        if "object_id" not in frame.columns:
            raise SchemaError("the input has no column 'object_id' to join on", field="object_id")
        weights = catalog_weights(catalog)
        ids = frame["object_id"].astype(str)
        missing = sorted(set(ids) - set(weights))
        if missing:
            raise InputDataError(
                f"{len(missing)} object(s) are not in the catalog: {format_ids(missing)}"
            )
        joined = ids.map(weights).to_numpy(dtype=np.float64)
        if "weight_n" in frame.columns:
            own = pd.to_numeric(frame["weight_n"], errors="coerce").to_numpy(dtype=np.float64)
            bad = ~np.isclose(own, joined, rtol=1e-6, atol=0.0, equal_nan=True)
            if bad.any():
                raise InputDataError(
                    f"weight_n differs between the input and the catalog for {format_ids(ids[bad])}"
                )
        frame["weight_n"] = joined
    for col in FEATURES:
        if col not in frame.columns:
            hint = " (pass --catalog to join weights by object_id)" if col == "weight_n" else ""
            raise SchemaError(f"the input has no column {col!r}{hint}", field=col)
    keep = (["object_id"] if "object_id" in frame.columns else []) + list(FEATURES)
    return frame[keep].reset_index(drop=True)
