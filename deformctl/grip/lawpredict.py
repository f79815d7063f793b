"""Predict rows of any material law with a model file's law networks (:mod:`deformctl.grip.laws`).

:func:`law_models` reads (and checks) the networks a model file states under ``laws``;
:func:`predict_laws` predicts a table's rows: Kelvin–Voigt rows exactly as
:meth:`~deformctl.grip.fast.Predictor.predict_many` does, the other laws' rows with their own
network, ranges and calibration scores. ``bound_guaranteed`` is false, with a warning line
naming the cause, when

* the row's law is not among the model's training laws (it is predicted by the Kelvin–Voigt
  network from its D and λ at F_w);
* one of its law parameters lies outside that law's training range (the line names the
  parameter and the range);
* a law parameter or (``hc``) the object's size is unknown: the row is predicted at the most
  cautious value of the law's training range, flagged ``damping_assumed`` or ``shape_assumed``;
* its law is unknown (a blank ``model`` cell: characterize could not tell): it is predicted by
  every law the model knows and the row has parameters for, and the most cautious one (the
  largest bound, or L_f without a coverage) is used, flagged ``law_assumed``.

A model file without a law mix (written before) predicts Kelvin–Voigt rows as always and
refuses the other laws' rows (exit 65).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from deformctl.errors import InputDataError
from deformctl.grip.fast import Estimates, Predictor, _window
from deformctl.grip.laws import (
    EARLIER_LAW_FEATURES,
    KNOWN_LAWS,
    LAW_MIX_KEY,
    LAW_PARAMETER_COLUMNS,
    LAW_PARAMETERS,
    OPTIONAL_PARAMETER_COLUMNS,
    SHAPE_PARAMETERS,
    law_features,
    law_groups,
    law_parameter_values,
    network_parameters,
    sls_damping_ns_per_cm,
)
from deformctl.grip.sanity import implausible, implausible_line, scores_problem, target_ratio_range

__all__ = ["LawPrediction", "law_mix", "law_models", "predict_laws"]

#: Grid points per law parameter tried for a row whose parameter is unknown (NaN).
_PARAMETER_GRID = 9


@dataclass(frozen=True)
class LawPrediction:
    """:class:`Estimates` with the law each row was predicted with.

    Attributes:
        estimates: the predictions (KV rows as the main network gives them).
        law_used: ``[n]`` the law whose network predicted the row.
        law_assumed: ``[n]`` True where the row's law was unknown (the most cautious law used).
        parameters_assumed: ``[n]`` True where a law parameter was unknown (the most cautious
            value over the law's training range used; the CLI flags it ``damping_assumed``).
        shape_assumed: ``[n]`` True where the network needs the object's size and the row has
            none (the most cautious shape of the training range used; ``shape_assumed``).
    """

    estimates: Estimates
    law_used: np.ndarray
    law_assumed: np.ndarray
    parameters_assumed: np.ndarray
    shape_assumed: np.ndarray


def law_mix(predictor: Predictor) -> Mapping[str, Any] | None:
    """The ``laws`` section of the model file's metadata, or None (a file from before)."""
    mix = predictor.metadata.get(LAW_MIX_KEY)
    return mix if isinstance(mix, Mapping) else None


def law_models(predictor: Predictor) -> dict[str, Predictor]:
    """The model's law networks (``hc``, ``sls``; not ``kv``, the main network) as predictors
    sharing the file's path, cached on ``predictor``.

    Raises:
        InputDataError: a law network that is malformed, or whose scores or check points are
            wrong (65).
    """
    cached = predictor._cache.get("law_models")
    if cached is not None:
        return dict(cached)
    mix = law_mix(predictor)
    out: dict[str, Predictor] = {}
    for law, entry in dict((mix or {}).get("models") or {}).items():
        out[law] = _law_predictor(predictor, str(law), entry)
    predictor._cache["law_models"] = out
    return dict(out)


def _law_predictor(base: Predictor, law: str, entry: Any) -> Predictor:
    path = base.path
    bad = f"the model's {law} network is malformed"
    if law not in KNOWN_LAWS or law == "kv" or not isinstance(entry, Mapping):
        raise InputDataError(f"the model states a network for an unknown law {law!r}", path=path)
    try:
        features = tuple(str(c) for c in entry["features"])
        weights = tuple(np.asarray(w, dtype=np.float64) for w in entry["weights"])
        biases = tuple(np.asarray(b, dtype=np.float64) for b in entry["biases"])
        mean = np.asarray(entry["scaler_mean"], dtype=np.float64)
        scale = np.asarray(entry["scaler_scale"], dtype=np.float64)
        ranges = {str(k): (float(v[0]), float(v[1])) for k, v in entry["training_range"].items()}
        scores = np.asarray(entry.get("conformal_scores") or [], dtype=np.float64)
        check = entry["check_points"]
        Z = np.asarray(check["groups"], dtype=np.float64)
        expected = np.asarray(check["log_ratio"], dtype=np.float64)
        activation = str(entry["activation"])
        shift = float(entry["zeta_shift"])
    except (KeyError, TypeError, ValueError, IndexError):
        raise InputDataError(bad, path=path) from None
    n_in = len(features)
    known = (law_features(law), *EARLIER_LAW_FEATURES.get(law, ()))
    shapes_ok = features in known and mean.shape == scale.shape == (n_in,)
    width = n_in
    for w, b in zip(weights, biases, strict=False):
        shapes_ok &= w.ndim == 2 and w.shape[0] == width and b.shape == (w.shape[1],)
        width = w.shape[1] if w.ndim == 2 else -1
    finite = all(np.all(np.isfinite(a)) for a in (*weights, *biases, mean, scale))
    ranges_ok = all(math.isfinite(lo) and lo <= hi < math.inf for lo, hi in ranges.values())
    if not (shapes_ok and width == 1 and len(weights) == len(biases) and finite and ranges_ok):
        raise InputDataError(bad, path=path)
    if not np.all(scale > 0) or activation != base.activation:
        raise InputDataError(bad, path=path)
    problem = scores_problem(scores, entry) if scores.size else None
    if problem is not None:
        raise InputDataError(f"not a usable lifting-force model ({law}): {problem}", path=path)
    pred = dataclasses.replace(
        base,
        metadata=dict(entry),
        mean=mean,
        scale=scale,
        weights=weights,
        biases=biases,
        zeta_shift=shift,
        ranges=ranges,
        scores=np.sort(scores) if scores.size else None,
        correction=None,
        _cache={},
    )
    if (
        Z.ndim != 2
        or Z.shape[1:] != (n_in,)
        or not np.allclose(pred._network(Z), expected, rtol=1e-9, atol=1e-12)
    ):
        raise InputDataError(
            f"the model's {law} network does not reproduce its stored predictions", path=path
        )
    return pred


def _law_rows(
    net: Predictor,
    law: str,
    W: np.ndarray,
    D: np.ndarray,
    lam: np.ndarray,
    f_w: np.ndarray,
    params: Mapping[str, np.ndarray],
) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """(L_f, [n, 2] unknown (a law parameter, the shape), the parameters used) of rows of
    ``law``; a NaN parameter the network uses takes the value of the law's training range with
    the largest L_f (a grid of that range)."""
    names = network_parameters(net.metadata["features"])
    used = {k: np.array(params[k], dtype=np.float64) for k in names}
    unknown_law = np.zeros(W.size, dtype=bool)
    unknown_shape = np.zeros(W.size, dtype=bool)
    for k in names:
        if k in SHAPE_PARAMETERS:
            unknown_shape |= ~np.isfinite(used[k])
        else:
            unknown_law |= ~np.isfinite(used[k])
    if law == "hc":
        unknown_law |= ~np.isfinite(lam)
    unknown = unknown_law | unknown_shape
    grids = [np.linspace(*net.ranges.get(k, (np.nan, np.nan)), _PARAMETER_GRID) for k in names]
    for i in np.flatnonzero(unknown):
        cand = np.array(
            [
                [c[j] if not math.isfinite(used[k][i]) else used[k][i] for j, k in enumerate(names)]
                for c in itertools.product(*grids)
            ]
        )
        cand = np.unique(cand, axis=0)
        m = cand.shape[0]
        p = {k: cand[:, j] for j, k in enumerate(names)}
        lam_i = np.full(m, 0.0 if not math.isfinite(lam[i]) else lam[i])
        lift_i = _lift(net, law, np.full(m, W[i]), np.full(m, D[i]), lam_i, np.full(m, f_w[i]), p)
        best = int(np.argmax(lift_i))
        for k in names:
            used[k][i] = p[k][best]
    lam_used = np.where(np.isfinite(lam), lam, 0.0)
    flags = np.column_stack([unknown_law, unknown_shape])
    return _lift(net, law, W, D, lam_used, f_w, used), flags, used


def _lift(
    net: Predictor,
    law: str,
    W: np.ndarray,
    D: np.ndarray,
    lam: np.ndarray,
    f_w: np.ndarray,
    params: Mapping[str, np.ndarray],
) -> np.ndarray:
    if law == "sls":  # λ = k2 τ, fixed by the law's parameters
        omega = np.sqrt(D * 100.0 / (W / 9.80665))
        lam = sls_damping_ns_per_cm(
            D, omega, params["arm_stiffness_ratio"], params["relaxation_time_omega_n"]
        )
    mu = W / (2.0 * f_w)  # F_w = W / (2 μ)
    Z = law_groups(law, W, D, lam, mu, params, net.zeta_shift, net.metadata["features"])
    return np.asarray(np.exp(net._network(Z)) * f_w)


def _outside(net: Predictor, values: Mapping[str, np.ndarray], i: int) -> list[str]:
    parts = []
    for name, arr in values.items():
        bounds = net.ranges.get(name)
        v = float(arr[i])
        if bounds is not None and math.isfinite(v) and not bounds[0] <= v <= bounds[1]:
            parts.append(f"{name} = {v:g} not in [{bounds[0]:g}, {bounds[1]:g}]")
    return parts


def predict_laws(
    predictor: Predictor,
    inputs: Mapping[str, Any],
    laws: np.ndarray,
    *,
    coverage: float | None = None,
    names: Sequence[str] | None = None,
) -> LawPrediction:
    """Predict rows of any law (module doc); ``inputs`` as for ``predict_many`` plus the law
    columns (:data:`~deformctl.grip.laws.LAW_PARAMETER_COLUMNS`) where the rows have them,
    ``laws`` ``[n]`` from :func:`~deformctl.grip.laws.read_laws`.

    Raises:
        InputDataError: a row of another law than Kelvin–Voigt and a model file without a law
            mix (one line, exit 65); as ``predict_many`` for a bad input.
    """
    n = len(laws)
    labels = [str(x) for x in (names if names is not None else [f"row {i}" for i in range(n)])]
    mix = law_mix(predictor)
    others = [i for i in range(n) if laws[i] not in ("kv", "")]
    if mix is None and others:
        shown = ", ".join(labels[i] for i in others[:5])
        raise InputDataError(
            f"the model file states no law mix (it knows Kelvin–Voigt objects only) and cannot "
            f"predict the {laws[others[0]]} row(s) {shown}; use a model trained with "
            "`train --laws COEFFICIENTS`"
        )
    base = predictor.predict_many(
        inputs["weight_n"],
        inputs["deformability_n_per_cm"],
        inputs["damping_ns_per_cm"],
        inputs.get("friction_mu"),
        coverage=coverage,
        max_safe_force_n=inputs.get("max_safe_force_n"),
        names=labels,
    )
    trained = tuple((mix or {}).get("trained_laws") or ("kv",))
    nets = law_models(predictor)
    W = np.broadcast_to(np.asarray(inputs["weight_n"], dtype=np.float64).reshape(-1), (n,))
    D = np.broadcast_to(np.asarray(inputs["deformability_n_per_cm"], dtype=np.float64), (n,))
    lam = np.broadcast_to(np.asarray(inputs["damping_ns_per_cm"], dtype=np.float64), (n,))
    f_w = base.f_w_n
    lift = base.lift_force_n.copy()
    upper = base.lift_force_upper_n.copy()
    outside = base.outside_training_range.copy()
    guaranteed = base.bound_guaranteed.copy()
    law_used = np.array(["kv"] * n, dtype=object)
    law_assumed = np.zeros(n, dtype=bool)
    params_assumed = np.zeros(n, dtype=bool)
    shape_assumed = np.zeros(n, dtype=bool)
    replaced: dict[int, list[str]] = {}
    notes: dict[int, list[str]] = {}
    # every law's prediction of the rows it can predict: (lift, upper, outside parts, assumed)
    per_law: dict[str, dict[int, tuple[float, float, list[str], tuple[bool, bool]]]] = {}
    for law, net in nets.items():
        rows = [i for i in range(n) if laws[i] in (law, "")]
        if not rows:
            continue
        cols = LAW_PARAMETER_COLUMNS[law]
        if laws[rows[0]] == "" and any(c not in inputs for c in cols):
            rows = [i for i in rows if laws[i] == law]
        if not rows:
            continue
        missing = [c for c in cols if c not in inputs and c not in OPTIONAL_PARAMETER_COLUMNS]
        if missing:
            raise InputDataError(
                f"the table has no column {missing[0]!r} for its {law} rows "
                f"({', '.join(labels[i] for i in rows[:5])})"
            )
        idx = np.asarray(rows)
        raw = {
            c: np.broadcast_to(np.asarray(inputs.get(c, np.nan), dtype=np.float64), (n,))[idx]
            for c in cols
        }
        params = law_parameter_values(law, raw, W[idx], D[idx])
        blank = laws[idx] == ""
        if blank.any():  # an unknown law is this law only where the row has its parameters
            material = [k for k in LAW_PARAMETERS[law] if k not in SHAPE_PARAMETERS]
            has = np.all([np.isfinite(params[k]) for k in material], axis=0)
            keep = ~blank | has
            idx = idx[keep]
            params = {k: v[keep] for k, v in params.items()}
        if not idx.size:
            continue
        law_lift, assumed, _used = _law_rows(net, law, W[idx], D[idx], lam[idx], f_w[idx], params)
        q = None if coverage is None else net.margin(coverage)
        law_upper = np.full(idx.size, np.nan) if q is None else net._upper(law_lift, f_w[idx], q)
        checked = {
            "weight_n": W[idx],
            "deformability_n_per_cm": D[idx],
            "friction_mu": np.broadcast_to(
                np.asarray(inputs.get("friction_mu", np.nan), dtype=np.float64), (n,)
            )[idx],
            **params,
        }
        entry: dict[int, tuple[float, float, list[str], tuple[bool, bool]]] = {}
        for j, i in enumerate(idx.tolist()):
            parts = _outside(net, checked, j)
            entry[i] = (
                float(law_lift[j]),
                float(upper[i] if q is None else law_upper[j]),
                parts,
                (bool(assumed[j, 0]), bool(assumed[j, 1])),
            )
        per_law[law] = entry
    for i in range(n):
        law = str(laws[i])
        if law in per_law and i in per_law[law]:
            lf, up, parts, (was_assumed, no_shape) = per_law[law][i]
            lift[i], law_used[i] = lf, law
            params_assumed[i], shape_assumed[i] = was_assumed, no_shape
            upper[i] = up if coverage is not None else np.nan
            outside[i] = bool(parts)
            replaced[i] = []
            if parts:
                replaced[i].append(
                    f"{labels[i]}: outside the {law} training range: {'; '.join(parts)}"
                )
            if was_assumed:
                replaced[i].append(
                    f"{labels[i]}: a {law} parameter is unknown (damping not identifiable); "
                    f"predicted at the value of the model's {law} range with the largest L_f "
                    "(damping_assumed = true)"
                )
            if no_shape:
                replaced[i].append(
                    f"{labels[i]}: the {law} network needs the object's size (size_x_cm, "
                    "size_y_cm, size_z_cm; x squeezed, z up) and the row has none; predicted at "
                    f"the shape of the model's {law} range with the largest L_f "
                    "(shape_assumed = true, bound_guaranteed = false)"
                )
            guaranteed[i] = coverage is not None and not parts and not was_assumed
            guaranteed[i] &= not no_shape
        elif law == "":
            law_assumed[i] = True
            options = {"kv": (float(lift[i]), float(upper[i]))}
            for other, entry in per_law.items():
                if i in entry:
                    options[other] = (entry[i][0], entry[i][1])
            key = 1 if coverage is not None else 0
            chosen = max(options, key=lambda k: (options[k][key], options[k][0]))
            law_used[i] = chosen
            if chosen != "kv":
                lift[i], upper[i] = options[chosen]
                replaced[i] = []
                params_assumed[i], shape_assumed[i] = per_law[chosen][i][3]
                outside[i] = bool(per_law[chosen][i][2])
            guaranteed[i] = False
            notes.setdefault(i, []).append(
                f"{labels[i]}: the material law is unknown (characterize could not tell); "
                f"predicted as {chosen}, the most cautious of {', '.join(sorted(options))} "
                "(law_assumed = true, bound_guaranteed = false)"
            )
        elif law != "kv" or "kv" not in trained:
            guaranteed[i] = False
            notes.setdefault(i, []).append(
                f"{labels[i]}: the row's law is {law} but the model was trained on "
                f"{', '.join(trained)} objects only; predicted by the Kelvin–Voigt network "
                "from its D and λ (bound_guaranteed = false)"
            )
    warnings = _merge_warnings(base.warnings, labels, replaced, notes)
    safe = base.max_safe_force_n
    window_ok = base.window_ok.copy()
    odd = base.prediction_implausible
    odd = np.zeros(n, dtype=bool) if odd is None else odd.copy()
    for i, law in ((i, str(law_used[i])) for i in replaced):
        targets = target_ratio_range(nets[law].metadata)
        window_ok[i], line = _window(labels[i], lift[i], upper[i], safe[i])
        odd[i] = bool(implausible(lift[i : i + 1], f_w[i : i + 1], targets)[0])
        warnings += [line] if line else []
        warnings += [implausible_line(labels[i], lift[i], f_w[i], targets)] if odd[i] else []
    est = dataclasses.replace(
        base,
        lift_force_n=lift,
        lift_force_upper_n=upper,
        outside_training_range=outside,
        bound_guaranteed=guaranteed if coverage is not None else np.zeros(n, dtype=bool),
        window_ok=window_ok,
        warnings=warnings,
        prediction_implausible=odd,
    )
    return LawPrediction(est, law_used, law_assumed, params_assumed, shape_assumed)


def _merge_warnings(
    lines: Sequence[str],
    labels: Sequence[str],
    replaced: Mapping[int, list[str]],
    notes: Mapping[int, list[str]],
) -> list[str]:
    """The base warnings without the lines of rows another network predicted (replaced by
    theirs), then the law notes."""
    gone = {f"{labels[i]}:" for i in replaced}
    out = [t for t in lines if not any(t.startswith(g) for g in gone)]
    for i in sorted(replaced):
        out += replaced[i]
    for i in sorted(notes):
        out += notes[i]
    return out
