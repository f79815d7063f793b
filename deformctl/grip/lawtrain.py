"""Train the grip model per material law (:mod:`deformctl.grip.laws`): ``train --laws``.

The index table's objects are split by the law their coefficients row states (``model``). The
Kelvin–Voigt rows train the model file's main network exactly as ``train`` always has
(:func:`deformctl.train.train_model`); each other law's rows train that law's network on its
own groups, with their own seeded split (the first ``train_size`` rows train it, the next
``calibration_size`` calibrate its split-conformal bound, the rest are its test rows). The
bound of a law is therefore calibrated on that law's objects only (group-conditional split
conformal). :func:`law_section` is what the model file stores under ``laws``: the mix, every
range, each network, its scores and check points, and each law's test figures.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from deformctl.errors import InputDataError, SchemaError
from deformctl.grip.conformal import coverage_report, relative_scores, scores_digest
from deformctl.grip.groups import ZETA_SHIFT, group_values
from deformctl.grip.laws import (
    KNOWN_LAWS,
    LAW_COLUMN,
    LAW_PARAMETER_COLUMNS,
    LAW_PARAMETERS,
    law_features,
    law_groups,
    law_parameter_values,
    network_line,
    read_laws,
)
from deformctl.physics import rigid_grip_force_n

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

    from deformctl.model import TrainOptions

__all__ = ["best_network", "fit_law", "join_laws", "known_rows", "law_inputs", "law_section"]

_TARGET = "lift_force_n"
_CHECK_POINTS = 5


def join_laws(index_table: pd.DataFrame, coefficients: pd.DataFrame) -> pd.DataFrame:
    """The index table with each object's law (``model``) and law columns joined by
    ``object_id`` from a coefficients table.

    Raises:
        SchemaError: no ``object_id`` or ``model`` column.
        InputDataError: an object without a coefficients row, an unknown or blank law (65).
    """
    for frame, what in ((index_table, "index table"), (coefficients, "coefficients table")):
        if "object_id" not in frame.columns:
            raise SchemaError(f"the {what} has no column 'object_id'", field="object_id")
    if LAW_COLUMN not in coefficients.columns:
        raise SchemaError(f"the coefficients table has no column {LAW_COLUMN!r}", field="model")
    cols = [LAW_COLUMN, *(c for cs in LAW_PARAMETER_COLUMNS.values() for c in cs)]
    have = ["object_id", *(c for c in cols if c in coefficients.columns)]
    coef = coefficients[have].drop_duplicates("object_id").set_index("object_id")
    ids = index_table["object_id"].astype(str)
    missing = sorted(set(ids) - set(coef.index.astype(str)))
    if missing:
        raise InputDataError(
            f"{len(missing)} object(s) have no coefficients row: {', '.join(missing[:5])}"
        )
    out = index_table.drop(columns=[c for c in have[1:] if c in index_table.columns]).copy()
    coef.index = coef.index.astype(str)
    for c in have[1:]:
        out[c] = ids.map(coef[c]).to_numpy()
    laws = read_laws(out[LAW_COLUMN].tolist(), ids.tolist())
    if np.any(laws == ""):
        raise InputDataError(
            f"column {LAW_COLUMN!r} is blank for {', '.join(ids[laws == ''][:5])}: a training "
            "object's law must be known"
        )
    other = [law for law in dict.fromkeys(laws) if law not in KNOWN_LAWS]
    if other:
        raise InputDataError(
            f"the grip model has no network for the law {other[0]!r} (objects "
            f"{', '.join(ids[laws == other[0]][:5])}); it learns {', '.join(KNOWN_LAWS)}"
        )
    out[LAW_COLUMN] = laws
    return out


def _params(law: str, frame: pd.DataFrame) -> dict[str, np.ndarray]:
    nan = np.full(len(frame), np.nan)
    cols = {
        c: frame[c].to_numpy(dtype=np.float64) if c in frame.columns else nan
        for c in LAW_PARAMETER_COLUMNS[law]
    }
    W = frame["weight_n"].to_numpy(dtype=np.float64)
    D = frame["deformability_n_per_cm"].to_numpy(dtype=np.float64)
    return law_parameter_values(law, cols, W, D)


def known_rows(law: str, rows: pd.DataFrame) -> tuple[pd.DataFrame, list[str]]:
    """``(rows sorted by id with every law parameter known, the ids of the others)``: a NaN or
    non-positive parameter (damping not identifiable, or no object size for ``hc``)."""
    table = rows.sort_values("object_id").reset_index(drop=True)
    usable = np.all([np.isfinite(v) & (v > 0) for v in _params(law, table).values()], axis=0)
    dropped = table["object_id"].astype(str)[~usable].tolist()
    return table[usable].reset_index(drop=True), dropped


def best_network(
    options: TrainOptions, Z: np.ndarray, y: np.ndarray, f_w: np.ndarray, seeds: Sequence[int]
) -> tuple[Any, float]:
    """The law network (``options``' hidden layers, default the grip model's) fitted to
    ``log(y / F_w)`` from each seed in ``seeds``, the one with the smallest RMS relative error
    of L_f on these rows kept (one BLAS thread): ``(network, that error)``."""
    from sklearn.exceptions import ConvergenceWarning
    from threadpoolctl import threadpool_limits

    from deformctl.grip.model import DEFAULT_GRIP_HIDDEN
    from deformctl.model import scaled_mlp

    target = np.log(y / f_w)
    best, best_loss = None, math.inf
    for rs in seeds:
        net = scaled_mlp(options, options.hidden or DEFAULT_GRIP_HIDDEN, rs)
        with warnings.catch_warnings(), threadpool_limits(limits=1):
            warnings.simplefilter("ignore", ConvergenceWarning)
            net.fit(Z, target)
            pred = np.exp(net.predict(Z)) * f_w
        loss = float(np.sqrt(np.mean(((pred - y) / y) ** 2)))
        if loss < best_loss:
            best, best_loss = net, loss
    assert best is not None
    return best, best_loss


def law_inputs(
    law: str, frame: pd.DataFrame, features: Sequence[str] | None = None
) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """(network inputs, F_w, parameters) of a law's rows (``features``: the law's inputs by
    default, :func:`~deformctl.grip.laws.law_groups`); a NaN or non-positive parameter is
    refused (InputDataError)."""
    W, D, lam, mu = (
        frame[c].to_numpy(dtype=np.float64)
        for c in ("weight_n", "deformability_n_per_cm", "damping_ns_per_cm", "friction_mu")
    )
    params = _params(law, frame)
    for k, v in params.items():
        if not (np.all(np.isfinite(v)) and np.all(v > 0)):
            bad = frame["object_id"].astype(str)[~(np.isfinite(v) & (v > 0))].tolist()
            raise InputDataError(f"{law} parameter {k} is missing or <= 0 for {', '.join(bad[:5])}")
    lam0 = np.maximum(np.where(np.isfinite(lam), lam, 0.0), 0.0)
    Z = law_groups(law, W, D, lam0, mu, params, ZETA_SHIFT, features)
    return Z, rigid_grip_force_n(W, mu), params


def _ranges(law: str, frame: pd.DataFrame, params: dict[str, np.ndarray]) -> dict[str, list[float]]:
    W, D, lam, mu = (
        frame[c].to_numpy(dtype=np.float64)
        for c in ("weight_n", "deformability_n_per_cm", "damping_ns_per_cm", "friction_mu")
    )
    lam0 = np.maximum(lam, 0.0)
    omega, zeta = group_values(W, D, lam0)
    values = {
        "weight_n": W,
        "deformability_n_per_cm": D,
        "damping_ns_per_cm": lam0,
        "friction_mu": mu,
        "natural_frequency_rad_s": omega,
        "damping_ratio": zeta,
        **params,
    }
    return {k: [float(np.min(v)), float(np.max(v))] for k, v in values.items()}


def fit_law(law: str, rows: pd.DataFrame, options: TrainOptions) -> dict[str, Any]:
    """One law's network, trained and calibrated on that law's rows (module doc) under
    ``options`` (its hidden layers default to the grip model's; at most ``law_train_size``
    training rows when given): its ``laws.models`` entry.

    A row whose law parameters are not all known (NaN: damping not identifiable, or no object
    size for ``hc``) is left out and named under ``dropped_unidentified``.
    """
    from threadpoolctl import threadpool_limits

    from deformctl.grip.export import _core

    o = options
    calibration_size = o.calibration_size
    table, dropped = known_rows(law, rows)
    if o.law_train_size is None:
        train_size, flag = o.train_size, "--train-size"
    else:  # at most law_train_size: a smaller law trains on every row not calibrating
        train_size = min(o.law_train_size, len(table) - calibration_size)
        flag = "--law-train-size"
    known = f" ({len(dropped)} more with a parameter unknown)" if dropped else ""
    if train_size < 2 or len(table) < train_size + calibration_size:
        raise InputDataError(
            f"{len(table)} {law} rows with every parameter known{known}: fewer than {flag} "
            f"{max(train_size, 2)} + --calibration-size {calibration_size}"
        )
    rng = np.random.default_rng(o.seed)
    order = rng.permutation(len(table))
    restart_seeds = [int(s) for s in rng.integers(0, 2**31 - 1, size=o.restarts)]
    parts = {
        "train": table.iloc[order[:train_size]],
        "calibration": table.iloc[order[train_size : train_size + calibration_size]],
        "test": table.iloc[order[train_size + calibration_size :]],
    }
    Z, f_w, params = law_inputs(law, parts["train"])
    y = parts["train"][_TARGET].to_numpy(dtype=np.float64)
    best, best_loss = best_network(o, Z, y, f_w, restart_seeds)

    def predict(frame: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
        if not len(frame):
            return np.empty(0), np.empty(0)
        z, fw, _ = law_inputs(law, frame)
        with threadpool_limits(limits=1):
            return np.exp(best.predict(z)) * fw, frame[_TARGET].to_numpy(dtype=np.float64)

    p_cal, y_cal = predict(parts["calibration"])
    p_test, y_test = predict(parts["test"])
    scores = [float(v) for v in relative_scores(y_cal, p_cal)] if len(y_cal) else []
    rel = np.abs(p_test - y_test) / y_test if len(y_test) else np.empty(0)
    ratio = y / f_w
    entry: dict[str, Any] = {
        "features": list(law_features(law)),
        "zeta_shift": ZETA_SHIFT,
        **_core(best),
        "training_range": _ranges(law, parts["train"], params),
        "target_range": {"lift_ratio_f_w": [float(ratio.min()), float(ratio.max())]},
        "n_train": len(parts["train"]),
        "n_calibration": len(scores),
        "n_test": len(y_test),
        "train_rms_rel_error": best_loss,
        "test_median_rel_error": float(np.median(rel)) if rel.size else None,
        "test_max_rel_error": float(np.max(rel)) if rel.size else None,
        "conformal": coverage_report(np.asarray(scores), y_test, p_test) if scores else None,
        "check_points": {
            "groups": Z[:_CHECK_POINTS].tolist(),
            "log_ratio": [float(v) for v in best.predict(Z[:_CHECK_POINTS])],
        },
        "split": {k: v["object_id"].astype(str).tolist() for k, v in parts.items()},
        "dropped_unidentified": dropped,
    }
    if scores:
        entry["conformal_scores"] = scores
        entry["conformal_digest"] = scores_digest(scores)
    return entry


def law_section(
    table: pd.DataFrame,
    kv_training_range: dict[str, Any] | None,
    models: dict[str, dict[str, Any]],
    population: Any = None,
) -> dict[str, Any]:
    """The ``laws`` metadata: ``trained_laws``, ``mix`` (rows per law in the table and their
    fractions), ``ranges`` (each law's training ranges: inputs, groups, law parameters),
    ``parameters`` (each law's parameter names), ``models`` and the ``population`` law spec
    (when known)."""
    laws = table[LAW_COLUMN].to_numpy(dtype=object)
    counts = {law: int(np.sum(laws == law)) for law in KNOWN_LAWS if np.any(laws == law)}
    trained = [law for law in KNOWN_LAWS if law in counts and (law == "kv" or law in models)]
    ranges: dict[str, Any] = {}
    if kv_training_range is not None and "kv" in counts:
        ranges["kv"] = {k: list(v) for k, v in kv_training_range.items()}
    for law, entry in models.items():
        ranges[law] = entry["training_range"]
    total = sum(counts.values())
    return {
        "trained_laws": trained,
        "mix": {law: {"rows": n, "fraction": n / total} for law, n in counts.items()},
        "parameters": {law: list(LAW_PARAMETERS[law]) for law in trained},
        "ranges": ranges,
        "models": models,
        "population": population,
    }


def train_laws(
    index_table: pd.DataFrame,
    coefficients: pd.DataFrame,
    options: TrainOptions,
    *,
    train_main: Any,
) -> tuple[Any, dict[str, Any]]:
    """``(TrainResult of the Kelvin–Voigt rows, the laws section)``: ``train --laws``
    (:func:`deformctl.train.train_with_laws`, which passes ``train_main``, the stage's
    :func:`deformctl.train.train_model`: the grip package sits below the training stage).

    ``options``' ``train_size`` and ``calibration_size`` are per law. The Kelvin–Voigt rows go
    through :func:`deformctl.train.train_model` unchanged (the model file's main network); every
    other law with rows gets its network (:func:`fit_law`, same options).

    Raises:
        InputDataError: no Kelvin–Voigt rows (the main network needs them), or as
            :func:`join_laws`, :func:`fit_law` and ``train_model``.
    """
    joined = join_laws(index_table, coefficients)
    laws = joined[LAW_COLUMN].to_numpy(dtype=object)
    if not np.any(laws == "kv"):
        raise InputDataError(
            "train --laws needs Kelvin–Voigt rows (model = kv): they train the main network"
        )
    kv_rows = index_table[laws == "kv"].reset_index(drop=True)
    result = train_main(kv_rows, options, form="grip")
    models = {
        law: fit_law(law, joined[laws == law], options)
        for law in KNOWN_LAWS
        if law != "kv" and np.any(laws == law)
    }
    population = coefficients.attrs.get("grip_laws") if hasattr(coefficients, "attrs") else None
    return result, law_section(joined, result.training_range, models, population)


#: A law network's entries left out of the printed report (arrays, ids).
_LAW_BULK = ("weights", "biases", "scaler_mean", "scaler_scale", "conformal_scores",
             "check_points", "split")  # fmt: skip


def law_report(section: dict[str, Any]) -> dict[str, Any]:
    """The metrics file's ``laws``: :func:`law_section` without the networks' arrays."""
    report = {k: v for k, v in section.items() if k != "models"}
    report["models"] = {
        law: {k: v for k, v in m.items() if k not in _LAW_BULK}
        for law, m in section["models"].items()
    }
    return report


def law_lines(report: dict[str, Any]) -> list[str]:
    """One line per law network of ``train --laws``: its rows and its test figures."""
    section = report.get("laws") or {}
    return [f"{law}: {network_line(m)}" for law, m in (section.get("models") or {}).items()]
