"""The lifting-force predictor a robot calls: numpy only, microseconds per object.

:class:`Predictor` reads a model file's numpy export (:mod:`deformctl.grip.export`, stored in the
file's metadata by ``train``) straight from the skops archive with :mod:`zipfile` and
:mod:`json` -- it never builds a Python object from the file, and never imports scikit-learn,
skops or pandas -- and evaluates the network with the same numpy operations scikit-learn uses.
``deformctl predict`` uses it for every model file that has an export.

Example (the bundled grip model)::

    from deformctl.grip.fast import Predictor

    grip = Predictor.load("grip")            # once: about a millisecond
    est = grip.predict(weight_n=2.9, deformability_n_per_cm=30.0,
                       damping_ns_per_cm=0.47, friction_mu=0.5, coverage=0.9)
    est.lift_force_n, est.lift_force_upper_n, est.warnings

One call validates its inputs (finite; W, D > 0; λ >= 0; 0.01 <= μ <= 3), predicts L_f, the upper
bound at a coverage P when asked (:mod:`deformctl.grip.conformal`: ``L_f (1 + q_P)`` with the
model's stored calibration scores), flags inputs outside the training ranges
(``outside_training_range``; the bound is then not guaranteed, ``bound_guaranteed = False``) and,
given the object's safe force (a rupture or yield force), says whether a grip window exists
(``window_ok``: true only when the safe force is known and L_f and the bound lie at or below it;
None, with a warning, when the safe force given is NaN; None without one when none is given).
Every flag comes with a warning line naming the object and the cause.

A model trained at one friction coefficient (the paper's network) has no μ input. Asked about
another μ, its prediction is rescaled by F_w (L_f ∝ 1/μ, as the simulator shows: docs/explanation/
model.md), flagged ``outside_training_range`` and warned about; asked without μ, it predicts at
its training μ.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib.resources import files
from pathlib import Path
from typing import Any

import numpy as np

from deformctl.errors import InputDataError, UsageError
from deformctl.grip.activations import _activation, _activation_scalar
from deformctl.grip.conformal import (
    conformal_margin,
    conformal_min_scores,
    conformal_rank,
    min_coverage,
)
from deformctl.grip.groups import GRIP_FEATURES, ZETA_SHIFT
from deformctl.grip.inputs import (  # their home; re-exported for predict and the tests
    INPUT_RULES,
    MAX_FRICTION_MU,
    input_problem,
    input_problems,
    input_rule,
)
from deformctl.grip.modelfile import (  # read_model_metadata: re-exported, its old home
    file_problem,
    read_model_metadata,
)
from deformctl.grip.sanity import (
    SCORE_HIGH,
    bound_problem,
    implausible,
    implausible_line,
    output_problem,
    scores_problem,
    target_ratio_range,
)
from deformctl.physics import rigid_grip_force_n
from deformctl.quantities import (
    COVERAGE,
    FRICTION_MU,
)
from deformctl.reprs import short_repr
from deformctl.units import GRAVITY_M_S2

__all__ = [
    "BUNDLED_MODELS",
    "INPUT_RULES",
    "MAX_FRICTION_MU",
    "NEEDS_FRICTION_MESSAGE",
    "NO_SCORES_MESSAGE",
    "UNRECORDED_MU_WARNING",
    "Estimate",
    "Estimates",
    "NoNumpyExportError",
    "Predictor",
    "input_problem",
    "input_problems",
    "input_rule",
    "read_model_metadata",
    "resolve_model_path",
]

#: Model names ``predict`` (and :meth:`Predictor.load`) resolve to a file shipped with deformctl.
BUNDLED_MODELS: tuple[str, ...] = ("grip",)

#: Two friction coefficients this close (relative) are the same μ.
_SAME_MU_RTOL = 1e-6
_ACTIVATIONS = ("tanh", "relu", "logistic", "identity")
#: What a μ-aware model without μ says (the CLI names the flag and the column).
NEEDS_FRICTION_MESSAGE = (
    "the model needs each object's friction_mu: give --friction-mu MU or a friction_mu column"
)
#: What a single-μ model without a record of its μ (model format 1) says, once, when given μ.
UNRECORDED_MU_WARNING = (
    "the model has no friction input and does not record the μ it was trained at (model format "
    "1): friction_mu is not used and not checked; retrain it to have it checked"
)
#: What a model without calibration scores says when asked for a bound.
NO_SCORES_MESSAGE = (
    "the model file has no conformal calibration scores, so it has no upper bound: they are "
    "written by `deformctl train --calibration-size N` from model format "
    "deformctl-lift-force-model/2 on"
)


class NoNumpyExportError(InputDataError):
    """The model file has no numpy export (written before it existed): load it with skops."""


def resolve_model_path(model: str | Path) -> Path:
    """The file behind a model argument: a bundled name (:data:`BUNDLED_MODELS`) or a path.

    A bare name such as ``grip`` (no directory, no suffix) means the bundled model; a file of
    that name in the working directory is reached as ``./grip``.
    """
    text = str(model)
    if text in BUNDLED_MODELS:
        return Path(str(files("deformctl.datasets").joinpath("models", f"{text}.skops")))
    return Path(text)


def _float_array(value: Any, shape: tuple[int, ...] | None, what: str, path: Path) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputDataError(f"the numpy export's {what} is not numeric", path=path) from None
    if (shape is not None and arr.shape != shape) or not np.all(np.isfinite(arr)):
        raise InputDataError(
            f"the numpy export's {what} has shape {arr.shape} or non-finite values", path=path
        )
    return arr


@dataclass(frozen=True)
class Estimates:
    """Predictions for ``n`` objects (arrays ``[n]``).

    Attributes:
        names: object ids (or ``row i``).
        lift_force_n: predicted L_f, N.
        f_w_n: F_w = W / (2 μ), N (NaN for a single-μ model asked without μ).
        lift_force_upper_n: the upper bound at ``coverage`` (NaN when no coverage was asked).
        coverage: P, or None.
        outside_training_range: an input (or a group: ω_n, ζ, F_w / D) outside the training
            rows' range, or a μ other than a single-μ model's.
        bound_guaranteed: the bound holds with probability >= P (inside the range, finite);
            all False when no coverage was asked.
        max_safe_force_n: the object's safe force, N (NaN when unknown).
        window_ok: True when the safe force is known and L_f and the bound lie at or below it,
            False when either exceeds it, None when no safe force is known (object array).
        warnings: one line per cause and object (no ``warning:`` prefix).
    """

    __repr__ = short_repr

    names: np.ndarray
    lift_force_n: np.ndarray
    f_w_n: np.ndarray
    lift_force_upper_n: np.ndarray
    coverage: float | None
    outside_training_range: np.ndarray
    bound_guaranteed: np.ndarray
    max_safe_force_n: np.ndarray
    window_ok: np.ndarray
    warnings: list[str] = field(default_factory=list)
    prediction_implausible: np.ndarray | None = None  # deformctl.grip.sanity.implausible


@dataclass(frozen=True)
class Estimate:
    """One object's prediction (the fields of :class:`Estimates` as scalars)."""

    __repr__ = short_repr

    lift_force_n: float
    f_w_n: float
    lift_force_upper_n: float
    coverage: float | None
    outside_training_range: bool
    bound_guaranteed: bool
    max_safe_force_n: float
    window_ok: bool | None
    warnings: tuple[str, ...] = ()
    prediction_implausible: bool = False


@dataclass(frozen=True)
class Predictor:
    """A model file's network as numpy arrays, with its ranges and calibration scores.

    Build it with :meth:`load`. Attributes mirror the export (:mod:`deformctl.grip.export`) and
    the metadata ``train`` wrote: ``features`` (the model's inputs), ``ranges`` (name ->
    (min, max) over the training rows, inputs and groups), ``training_friction_mu`` (a single-μ
    model's μ, else None) and ``scores`` (the calibration scores, sorted, or None).
    """

    __repr__ = short_repr

    path: Path
    metadata: Mapping[str, Any]
    form: str
    features: tuple[str, ...]
    activation: str
    mean: np.ndarray
    scale: np.ndarray
    weights: tuple[np.ndarray, ...]
    biases: tuple[np.ndarray, ...]
    zeta_shift: float
    scale_index: int | None
    ranges: Mapping[str, tuple[float, float]]
    training_friction_mu: float | None
    scores: np.ndarray | None
    #: ``adapt``'s ``[c0, c_j]``: log(L_f / F_w) += c0 + Σ c_j x_j, x the scaled network inputs
    correction: np.ndarray | None = None
    #: what is worked out once per predictor: the margins per coverage, the plain-float layers
    _cache: dict[Any, Any] = field(default_factory=dict, repr=False, compare=False)

    @classmethod
    def load(cls, model: str | Path = "grip") -> Predictor:
        """Load a model file (or a bundled name such as ``"grip"``) for numpy evaluation.

        Raises:
            MissingInputError: no such file (66).
            NoNumpyExportError: the file has no numpy export (an older ``train``; 65).
            InputDataError: not a deformctl model file, or an export that is malformed or does
                not reproduce the model's stored check predictions (65).
        """
        path = resolve_model_path(model)
        meta = read_model_metadata(path)
        exp = meta.get("numpy_model")
        if not isinstance(exp, dict):
            raise NoNumpyExportError("the model file has no numpy export", path=path)
        predictor = cls.from_export(exp, meta, path)
        problem = file_problem(path, exp)  # the estimator agrees with the export (one loader)
        if problem is not None:
            raise InputDataError(f"not a usable lifting-force model: {problem}", path=path)
        return predictor

    @classmethod
    def from_export(
        cls,
        exp: Mapping[str, Any],
        meta: Mapping[str, Any],
        path: str | Path,
        *,
        check_points: bool = True,
    ) -> Predictor:
        """A predictor from a numpy export (:func:`deformctl.grip.export.export_model`) and the
        model file's metadata.

        Args:
            check_points: refuse an export that does not reproduce the metadata's stored check
                points (False for an export just made from the estimator itself).

        Raises:
            InputDataError: a malformed export (65).
        """
        path = Path(path)
        try:
            form = str(exp["form"])
            features = tuple(str(c) for c in exp["features"])
            activation = str(exp["activation"])
            raw_w, raw_b = list(exp["weights"]), list(exp["biases"])
            ranges = {
                str(k): (float(v[0]), float(v[1]))
                for k, v in dict(meta.get("training_range") or {}).items()
            }
            mu = meta.get("training_friction_mu")
            mu = None if mu is None else float(mu)
            shift = float(exp.get("zeta_shift", ZETA_SHIFT))
        except (KeyError, TypeError, ValueError, IndexError):
            raise InputDataError("the model's numpy export is malformed", path=path) from None
        bad = [
            k for k, (lo, hi) in ranges.items() if not (math.isfinite(lo) and lo <= hi < math.inf)
        ]
        if bad:
            raise InputDataError(f"the model's training range of {bad[0]} is not finite", path=path)
        if form not in ("grip", "paper") or activation not in _ACTIVATIONS:
            raise InputDataError(f"the numpy export's form {form!r} is unknown", path=path)
        if form == "grip" and features != GRIP_FEATURES:
            raise InputDataError(f"the grip model's features are {list(features)}", path=path)
        if form == "paper" and not set(features) <= set(INPUT_RULES):
            raise InputDataError(f"the model's features are {list(features)}", path=path)
        n_in = 2 if form == "grip" else len(features)
        if len(raw_w) != len(raw_b) or not raw_w:
            raise InputDataError("the numpy export's layers do not match", path=path)
        weights, biases, width = [], [], n_in
        for i, (w, b) in enumerate(zip(raw_w, raw_b, strict=True)):
            wa = _float_array(w, None, f"layer {i} weights", path)
            if wa.ndim != 2 or wa.shape[0] != width:
                raise InputDataError(
                    f"the numpy export's layer {i} has shape {wa.shape}", path=path
                )
            weights.append(wa)
            biases.append(_float_array(b, (wa.shape[1],), f"layer {i} biases", path))
            width = wa.shape[1]
        if width != 1:
            raise InputDataError("the numpy export's network has more than one output", path=path)
        mean = _float_array(exp.get("scaler_mean"), (n_in,), "scaler mean", path)
        scale = _float_array(exp.get("scaler_scale"), (n_in,), "scaler scale", path)
        if not np.all(scale > 0) or not (math.isfinite(shift) and shift > 0):
            raise InputDataError("the numpy export's scaler or ζ shift is not > 0", path=path)
        scale_index = exp.get("scale_index")
        if (
            form == "paper"
            and scale_index is not None
            and not (isinstance(scale_index, int) and 0 <= scale_index < len(features))
        ):
            raise InputDataError("the numpy export's scale_index is out of range", path=path)
        try:
            target_ratio_range(meta)  # read on every prediction (grip.sanity)
        except (TypeError, ValueError):
            raise InputDataError("the model's target range is malformed", path=path) from None
        if mu is not None:  # μ's one rule, as a value read from a file
            FRICTION_MU.check_data(mu, where="the model's training objects", path=path)
        corr = exp.get("correction")
        corr = None if corr is None else _float_array(corr, (n_in + 1,), "correction", path)
        raw_scores = meta.get("conformal_scores")
        scores = None
        if raw_scores is not None:
            try:
                stored = np.asarray(raw_scores, dtype=np.float64).ravel()
            except (TypeError, ValueError):
                what = "the model's calibration scores are not numbers"
                raise InputDataError(what, path=path) from None
            problem = scores_problem(stored, meta)  # the one check of a bound's scores
            if problem is not None:
                raise InputDataError(f"not a usable lifting-force model: {problem}", path=path)
            scores = np.sort(stored)
        predictor = cls(
            path=path,
            metadata=meta,
            form=form,
            features=features,
            activation=activation,
            mean=mean,
            scale=scale,
            weights=tuple(weights),
            biases=tuple(biases),
            zeta_shift=shift,
            scale_index=scale_index if form == "paper" else None,
            ranges=ranges,
            training_friction_mu=mu,
            scores=scores,
            correction=corr,
        )
        if check_points:
            predictor._check_stored_points()
        problem = output_problem(predictor)  # a lifting force at its own training points?
        if problem is not None:
            raise InputDataError(f"not a usable lifting-force model: {problem}", path=path)
        return predictor

    def _check_stored_points(self) -> None:
        """Refuse an export that does not reproduce the predictions ``train`` stored with it."""
        check = self.metadata.get("check_points")
        if not isinstance(check, dict):
            raise InputDataError("the model file has no check points", path=self.path)
        try:
            X = np.asarray(check["inputs"], dtype=np.float64)
            expected = np.asarray(check["lift_force_n"], dtype=np.float64)
            got = self._lift_force(X)
        except (KeyError, TypeError, ValueError, IndexError):
            raise InputDataError("the model's check points are malformed", path=self.path) from None
        if got.shape != expected.shape or not np.allclose(got, expected, rtol=1e-9, atol=0.0):
            raise InputDataError(
                "the model's numpy export does not reproduce its stored predictions",
                path=self.path,
            )

    @property
    def needs_friction(self) -> bool:
        """True for a μ-aware model (friction_mu is one of its inputs)."""
        return "friction_mu" in self.features

    # -- evaluation ------------------------------------------------------------------------

    def _network_one(self, z: Sequence[float]) -> float:
        """The network on one input row in plain floats: a small network costs less this way
        than numpy's per-call overhead (the same numbers to rounding, tested)."""
        x = [(v - m) / s for v, m, s in zip(z, self._plain[0], self._plain[1], strict=True)]
        scaled = x
        layers = self._plain[2]
        last = len(layers) - 1
        for i, (columns, biases) in enumerate(layers):
            x = [b + sum(map(operator.mul, col, x)) for col, b in zip(columns, biases, strict=True)]
            if i != last:
                x = [_activation_scalar(self.activation, v) for v in x]
        c = [0.0] if self.correction is None else self.correction.tolist()
        return x[0] + c[0] + sum(map(operator.mul, c[1:], scaled))

    @property
    def _plain(
        self,
    ) -> tuple[list[float], list[float], list[tuple[list[list[float]], list[float]]]]:
        """The scaler and the layers as lists (columns of each weight matrix), made once."""
        cached = self._cache.get("plain")
        if cached is None:
            cached = (
                self.mean.tolist(),
                self.scale.tolist(),
                [
                    (w.T.tolist(), b.tolist())
                    for w, b in zip(self.weights, self.biases, strict=True)
                ],
            )
            self._cache["plain"] = cached
        return cached

    def _network(self, Z: np.ndarray) -> np.ndarray:
        """The scaler and the network on ``Z`` ``[n, n_in]``, as scikit-learn computes them."""
        x = scaled = (Z - self.mean) / self.scale
        last = len(self.weights) - 1
        for i, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            x = x @ w
            x += b
            if i != last:
                x = _activation(self.activation, x)
        c = self.correction
        return x[:, 0] if c is None else x[:, 0] + c[0] + scaled @ c[1:]

    def _groups(self, W: np.ndarray, D: np.ndarray, lam: np.ndarray) -> np.ndarray:
        mass = W / GRAVITY_M_S2
        d_si = D * 100.0
        omega = np.sqrt(d_si / mass)
        zeta = np.maximum(lam, 0.0) * 100.0 / (2.0 * np.sqrt(d_si * mass))
        return np.column_stack([np.log10(omega), np.log10(zeta + self.zeta_shift)])

    def _lift_force(self, X: np.ndarray) -> np.ndarray:
        """L_f for ``X`` ``[n, len(features)]`` in the model's feature order (no checks)."""
        if self.form == "grip":
            W, D, lam, mu = X[:, 0], X[:, 1], X[:, 2], X[:, 3]
            return np.exp(self._network(self._groups(W, D, lam))) * rigid_grip_force_n(W, mu)
        out = self._network(X)
        return out * X[:, self.scale_index] if self.scale_index is not None else out

    def margin(self, coverage: float) -> float:
        """The conformal margin q_P of this model's calibration scores (cached per P).

        Raises:
            UsageError: ``coverage`` outside (0, 1) (exit 2).
            InputDataError: the model has no calibration scores, or too few for P (exit 65).
        """
        cached = self._cache.get(("margin", coverage))
        if cached is not None:
            return float(cached)
        p = COVERAGE.check(coverage)  # the one rule of --coverage
        if self.scores is None:
            raise InputDataError(NO_SCORES_MESSAGE, path=self.path)
        n = self.scores.size
        if p < min_coverage(n):
            raise UsageError(
                f"--coverage must be at least 1/(n + 1) = {min_coverage(n):.3g} with the model's "
                f"n = {n} calibration scores, got {p:g} (below it every P gives the same bound)"
            )
        if self._thin(p) is not None:  # an adapted model on few rig rows: their largest score
            return max(float(self.scores[-1]), 0.0)
        if conformal_rank(n, p) > n:
            need = conformal_min_scores(p)
            raise InputDataError(
                f"--coverage {p:g} needs at least {need} calibration scores; the model has {n}",
                path=self.path,
            )
        # a negative margin (a low P) would put the bound below the prediction: never
        q = max(conformal_margin(self.scores, p), 0.0)
        self._cache[("margin", coverage)] = q
        return q

    def _upper(self, lift: Any, f_w: Any, q: float) -> Any:
        """The bound ``max(L_f (1 + q), F_w)`` (grip.sanity), checked: a bound that breaks
        F_w <= L_f <= bound <= (1 + SCORE_HIGH) L_f refuses the file (its scores cannot be
        right).

        Raises:
            InputDataError: such a bound (exit 65).
        """
        with np.errstate(over="ignore", invalid="ignore"):
            upper = np.fmax(np.asarray(lift, dtype=np.float64) * (1.0 + q), f_w)
        row = bound_problem(np.atleast_1d(lift), np.atleast_1d(upper), np.atleast_1d(f_w))
        if row is not None:
            value = float(np.atleast_1d(upper)[row])
            raise InputDataError(
                f"not a usable lifting-force model: its calibration scores give an upper bound of "
                f"{value:.6g} N for a prediction of {float(np.atleast_1d(lift)[row]):.6g} N "
                f"(F_w = {float(np.atleast_1d(f_w)[row]):.6g} N), outside [max(L_f, F_w), "
                f"{1 + SCORE_HIGH:.4g} x L_f]",
                path=self.path,
            )
        return upper

    def _thin(self, p: float | None) -> str | None:
        """The warning of an adapted model asked for a P its n rig rows cannot guarantee."""
        n = 0 if self.scores is None else self.scores.size
        if p is None or "adapted" not in self.metadata or not 0 < n < conformal_rank(n, p):
            return None
        return (f"the bound at P = {p:g} rests on {n} rig rows, fewer than the "
                f"{conformal_min_scores(p)} it needs: it is their largest score, guaranteed at "
                f"n / (n + 1) = {n / (n + 1):.3f} only (bound_guaranteed = false)")  # fmt: skip

    def _checked_values(
        self, W: Any, D: Any, lam: Any, mu: Any, f_w: Any
    ) -> tuple[tuple[str, Any], ...]:
        """(name, value) of everything compared with the training ranges."""
        if self.form != "grip":
            given = {"weight_n": W, "deformability_n_per_cm": D, "damping_ns_per_cm": lam}
            return tuple((c, given[c]) for c in self.features if c in given)
        mass = W / GRAVITY_M_S2
        return (
            ("weight_n", W),
            ("deformability_n_per_cm", D),
            ("damping_ns_per_cm", _max0(lam)),
            ("friction_mu", mu),
            ("natural_frequency_rad_s", (D * 100.0 / mass) ** 0.5),
            ("damping_ratio", _max0(lam) * 100.0 / (2.0 * (D * 100.0 * mass) ** 0.5)),
            ("compression_at_f_w_cm", f_w / D),
        )

    def _outside_parts(self, checked: tuple[tuple[str, float], ...]) -> list[str]:
        parts = []
        for name, value in checked:
            bounds = self.ranges.get(name)
            if bounds is not None and not bounds[0] <= value <= bounds[1]:
                parts.append(f"{name} = {value:g} not in [{bounds[0]:g}, {bounds[1]:g}]")
        return parts

    def _mu_warning(self, label: str, mu: float) -> str:
        return (
            f"{label}: the model was trained at friction_mu = {self.training_friction_mu:g} "
            f"only; friction_mu = {mu:g} is outside its range, its prediction is scaled by F_w "
            "(L_f ∝ 1/μ)"
        )

    def predict(
        self,
        weight_n: float,
        deformability_n_per_cm: float,
        damping_ns_per_cm: float,
        friction_mu: float | None = None,
        *,
        coverage: float | None = None,
        max_safe_force_n: float | None = None,
        name: str = "object",
    ) -> Estimate:
        """Predict one object (the library call a robot makes; microseconds).

        Same checks, flags and warnings as :meth:`predict_many`, on floats.

        Raises:
            UsageError: a μ-aware model without μ; a coverage outside (0, 1).
            InputDataError: a bad input (the line names the input and ``name``); a coverage
                the model has no (or too few) calibration scores for.
        """
        W, D, lam = float(weight_n), float(deformability_n_per_cm), float(damping_ns_per_cm)
        mu = None if friction_mu is None else float(friction_mu)
        if mu is None and self.needs_friction:
            raise UsageError(NEEDS_FRICTION_MESSAGE)
        q = None if coverage is None else self.margin(coverage)
        for col, value in (
            ("weight_n", W),
            ("deformability_n_per_cm", D),
            ("damping_ns_per_cm", lam),
            *((("friction_mu", mu),) if mu is not None else ()),
        ):
            line = input_problem(col, value, name)
            if line is not None:
                raise InputDataError(line)
        warnings: list[str] = [t for t in [self._thin(coverage)] if t]
        outside = False
        if self.form == "grip":
            assert mu is not None
            mass = W / GRAVITY_M_S2
            d_si = D * 100.0
            zeta = _max0(lam) * 100.0 / (2.0 * math.sqrt(d_si * mass))
            z = (math.log10(math.sqrt(d_si / mass)), math.log10(zeta + self.zeta_shift))
            f_w = rigid_grip_force_n(W, mu)
            lift = math.exp(self._network_one(z)) * f_w
        else:
            lift, f_w = self._paper_scalar(W, D, lam, mu, name, warnings)
            outside = bool(warnings)
        parts = self._outside_parts(self._checked_values(W, D, lam, mu, f_w))
        if parts:
            outside = True
            warnings.append(f"{name}: outside the training range: {'; '.join(parts)}")
        upper = math.nan if q is None else float(self._upper(lift, f_w, q))
        safe = math.nan if max_safe_force_n is None else float(max_safe_force_n)
        window_ok, line = (
            (None, None) if max_safe_force_n is None else _window(name, lift, upper, safe)
        )
        if line:
            warnings.append(line)
        targets = target_ratio_range(self.metadata)
        odd = bool(implausible(np.array([lift]), np.array([f_w]), targets)[0])
        warnings += [implausible_line(name, lift, f_w, targets)] if odd else []
        return Estimate(
            lift_force_n=lift,
            f_w_n=f_w,
            lift_force_upper_n=upper,
            coverage=None if coverage is None else float(coverage),
            outside_training_range=outside,
            bound_guaranteed=q is not None and not outside and self._thin(coverage) is None,
            max_safe_force_n=safe,
            window_ok=window_ok,
            warnings=tuple(warnings),
            prediction_implausible=odd,
        )

    def _paper_scalar(
        self, W: float, D: float, lam: float, mu: float | None, name: str, warnings: list[str]
    ) -> tuple[float, float]:
        """(L_f, F_w) of one object under a single-μ model, and a warning for another μ."""
        given = {"weight_n": W, "deformability_n_per_cm": D, "damping_ns_per_cm": lam}
        lift = float(self._lift_force(np.array([[given[c] for c in self.features]]))[0])
        mu_train = self.training_friction_mu
        if mu is not None and mu_train is None:
            warnings.append(UNRECORDED_MU_WARNING)
        elif mu is not None and mu_train is not None and not _same_mu(mu, mu_train):
            warnings.append(self._mu_warning(name, mu))
            lift *= mu_train / mu
        used = mu if mu is not None else mu_train
        return lift, (rigid_grip_force_n(W, used) if used is not None else math.nan)

    def predict_many(
        self,
        weight_n: Any,
        deformability_n_per_cm: Any,
        damping_ns_per_cm: Any,
        friction_mu: Any = None,
        *,
        coverage: float | None = None,
        max_safe_force_n: Any = None,
        names: Sequence[str] | None = None,
    ) -> Estimates:
        """Predict ``n`` objects (array-likes ``[n]``; μ may be None for a single-μ model).

        Raises:
            UsageError: a μ-aware model without μ; a coverage outside (0, 1).
            InputDataError: an input that is NaN, not finite or out of its range (the line
                names the column and the objects); a coverage the model has no (or too few)
                calibration scores for.
        """
        W = np.atleast_1d(np.asarray(weight_n, dtype=np.float64))
        n = W.shape[0]
        labels = np.asarray(list(names) if names is not None else [f"row {i}" for i in range(n)])
        values = {
            "weight_n": W,
            "deformability_n_per_cm": np.broadcast_to(
                np.asarray(deformability_n_per_cm, dtype=np.float64), (n,)
            ),
            "damping_ns_per_cm": np.broadcast_to(
                np.asarray(damping_ns_per_cm, dtype=np.float64), (n,)
            ),
        }
        if friction_mu is not None:
            values["friction_mu"] = np.broadcast_to(np.asarray(friction_mu, dtype=np.float64), (n,))
        elif self.needs_friction:
            raise UsageError(NEEDS_FRICTION_MESSAGE)
        q = None if coverage is None else self.margin(coverage)
        problems = input_problems(values, labels)
        if problems:
            raise InputDataError(problems[0][1])
        D, lam = values["deformability_n_per_cm"], values["damping_ns_per_cm"]
        mu = values.get("friction_mu")
        warnings: list[str] = [t for t in [self._thin(coverage)] if t]
        outside = np.zeros(n, dtype=bool)
        if self.form == "grip":
            assert mu is not None
            lift = self._lift_force(np.column_stack([W, D, lam, mu]))
            f_w = rigid_grip_force_n(W, mu)
        else:
            lift = self._lift_force(np.column_stack([values[c] for c in self.features]))
            mu_train = self.training_friction_mu
            used = mu if mu is not None else np.full(n, np.nan if mu_train is None else mu_train)
            f_w = rigid_grip_force_n(W, used)
            if mu is not None and mu_train is None:
                warnings.append(UNRECORDED_MU_WARNING)
            elif mu is not None and mu_train is not None:
                other = ~np.isclose(mu, mu_train, rtol=_SAME_MU_RTOL, atol=0.0)
                lift = np.where(other, lift * (mu_train / mu), lift)
                outside |= other
                warnings += [
                    self._mu_warning(str(labels[i]), float(mu[i])) for i in np.flatnonzero(other)
                ]
        checked = self._checked_values(W, D, lam, mu, f_w)
        parts: list[list[str]] = [[] for _ in range(n)]
        for name, arr in checked:
            bounds = self.ranges.get(name)
            if bounds is None:
                continue
            for j in np.flatnonzero((arr < bounds[0]) | (arr > bounds[1])):
                parts[j].append(f"{name} = {arr[j]:g} not in [{bounds[0]:g}, {bounds[1]:g}]")
        for k, row_parts in enumerate(parts):
            if row_parts:
                outside[k] = True
                warnings.append(f"{labels[k]}: outside the training range: {'; '.join(row_parts)}")
        upper = np.full(n, np.nan) if q is None else self._upper(lift, f_w, q)
        safe = (
            np.full(n, np.nan)
            if max_safe_force_n is None
            else np.array(np.broadcast_to(np.asarray(max_safe_force_n, dtype=np.float64), (n,)))
        )
        window_ok = np.full(n, None, dtype=object)
        if max_safe_force_n is not None:
            for i in range(n):
                window_ok[i], line = _window(str(labels[i]), lift[i], upper[i], safe[i])
                if line:
                    warnings.append(line)
        targets = target_ratio_range(self.metadata)
        odd = implausible(lift, f_w, targets)
        warnings += [
            implausible_line(str(labels[i]), lift[i], f_w[i], targets) for i in np.flatnonzero(odd)
        ]
        return Estimates(
            names=labels,
            lift_force_n=lift,
            f_w_n=f_w,
            lift_force_upper_n=upper,
            coverage=None if coverage is None else float(coverage),
            outside_training_range=outside,
            bound_guaranteed=~outside & (self._thin(coverage) is None)
            if q is not None
            else np.zeros(n, dtype=bool),
            max_safe_force_n=safe,
            window_ok=window_ok,
            warnings=warnings,
            prediction_implausible=odd,
        )


def _max0(x: Any) -> Any:
    return np.maximum(x, 0.0) if isinstance(x, np.ndarray) else max(x, 0.0)


def _same_mu(a: float, b: float) -> bool:
    return abs(a - b) <= _SAME_MU_RTOL * abs(b)


def _window(label: str, lift: float, upper: float, safe: float) -> tuple[bool | None, str | None]:
    """(window_ok, warning): unknown (None) without a safe force, false when L_f or the bound
    exceeds it."""
    if not math.isfinite(safe):
        return None, (
            f"{label}: no safe force known (no rupture or yield force measured): whether the "
            "grip crushes it is unknown (window_ok = null)"
        )
    need = max(lift, upper) if math.isfinite(upper) else lift
    if need <= safe:
        return True, None
    what = "its upper bound" if need > lift else "its lifting force"
    return False, (
        f"{label}: no safe grip: {what} {need:.4g} N exceeds its safe force {safe:.4g} N "
        "(window_ok = false)"
    )
