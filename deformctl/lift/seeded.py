"""Where a seeded lifting-force search starts: a trained model's or an index table's L_f.

On a real rig every lift attempt costs a grip, a lift, a check and a reset. The search
:func:`deformctl.lift.search.find_min_lift_force_seeded` starts at a predicted L_f instead of at
F_w; this module makes the predictions (``lift --start-model`` / ``--start-table``):

* :func:`load_start_model`: a model file from ``train`` or a bundled model such as ``grip``,
  evaluated by the numpy predictor (:class:`deformctl.grip.fast.Predictor`; a model file without
  a numpy export is loaded through the skops allow-list); the model must take
  :data:`deformctl.train.FEATURES` or, a grip model, those and ``friction_mu`` (taken from the
  catalog's F_w), else the file is refused (exit 65). An object outside the
  model's training range is not predicted from: its search falls back to ``refine`` from F_w,
  with one warning line naming the object and the feature(s).
* :func:`load_start_table`: an index table from ``table``: the nearest entry (in standardized
  units, :mod:`deformctl.table`), or with ``k`` an inverse-distance weighted mean of the ``k``
  nearest. The table predicts the entry's *ratio* L_f / F_w times this object's F_w (when the
  table carries ``f_w_n``): entries have other weights and friction, and F_w = W / (2 μ) carries
  those exactly. Its "training range" is the range of its entries' attributes.

The features are the model's, (W, D, λ): W from the catalog row; D and λ, for each object, from
the first of

1. a coefficients table (``--coefficients``, from ``characterize``): what the model and the
   table were built from, and what a rig user has after squeezing the objects;
2. the catalog's own ``deformability_n_per_cm`` and ``damping_ns_per_cm`` columns (measured
   values a user keeps in the object list);
3. with the simulator only (``use_material``), the catalog's material values, the simulator's
   ground truth for D and λ (what ``characterize`` recovers from a simulated squeeze).

An object with none of them, or with a D or λ that is not a finite number (``characterize``
leaves λ NaN when it cannot identify it), is refused naming the object (exit 65).

Example:
    >>> import pandas as pd
    >>> index = pd.DataFrame({"object_id": ["A", "B"], "weight_n": [20.0, 40.0],
    ...     "deformability_n_per_cm": [30.0, 50.0], "damping_ns_per_cm": [0.0, 10.0],
    ...     "lift_force_n": [30.0, 50.0], "f_w_n": [20.0, 40.0]})
    >>> seed = StartSeed.from_index_table(index)
    >>> features = pd.DataFrame({"object_id": ["C"], "weight_n": [38.0],
    ...     "deformability_n_per_cm": [49.0], "damping_ns_per_cm": [9.0]})
    >>> start = seed.estimate(features, f_w_n=[38.0])["C"]
    >>> round(start.predicted_lift_force_n, 6), start.in_range  # B's ratio 1.25 x F_w
    (47.5, True)
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import pandas as pd

from deformctl.catalog import CatalogObject
from deformctl.errors import InputDataError
from deformctl.quantities import START_INTERPOLATE
from deformctl.reprs import short_repr

__all__ = [
    "FEATURE_COLUMNS",
    "StartEstimate",
    "StartSeed",
    "load_start_model",
    "load_start_table",
    "object_features",
]

#: The features a start is predicted from, in order (``deformctl.train.FEATURES``, the index
#: table's ``LOOKUP_KEYS``); restated so that importing this module does not import sklearn.
FEATURE_COLUMNS: tuple[str, str, str] = ("weight_n", "deformability_n_per_cm", "damping_ns_per_cm")
_D, _LAMBDA = FEATURE_COLUMNS[1], FEATURE_COLUMNS[2]

StartSource = Literal["model", "table"]
#: ``predict(features, f_w_n) -> (predicted L_f [n], outside the range [n], warning per row or
#: None, upper bound at :data:`START_BOUND_COVERAGE` [n], NaN when the source has none)``
Predictor = Callable[
    [pd.DataFrame, np.ndarray],
    tuple[np.ndarray, np.ndarray, list[str | None], np.ndarray],
]
#: The coverage of the bound a model's start records in the lift log (with the prediction).
START_BOUND_COVERAGE = 0.9


@dataclass(frozen=True)
class StartEstimate:
    """The predicted L_f of one object, and whether the search may start from it.

    Attributes:
        object_id: the object.
        predicted_lift_force_n: the prediction, N.
        in_range: True when the object's features lie inside the model's training range (the
            table's attribute range); False: the search falls back to F_w.
        source: ``"model"`` or ``"table"``.
        warning: one line (no ``warning:`` prefix) naming the object and the feature(s) outside
            the range, when ``in_range`` is False.
        lift_force_upper_n: the model's split-conformal upper bound on L_f at
            :data:`START_BOUND_COVERAGE`, N (NaN for a table, or a model without enough
            calibration scores).
    """

    __repr__ = short_repr

    object_id: str
    predicted_lift_force_n: float
    in_range: bool
    source: StartSource
    warning: str | None = None
    lift_force_upper_n: float = math.nan

    def record(self) -> dict[str, Any]:
        """The start as the lift log stores it with the object (JSON values)."""
        return {
            "source": self.source,
            "predicted_lift_force_n": self.predicted_lift_force_n,
            "lift_force_upper_n": _finite(self.lift_force_upper_n),
            "coverage": START_BOUND_COVERAGE if _finite(self.lift_force_upper_n) else None,
            "in_training_range": self.in_range,
        }


def _finite(value: Any) -> float | None:
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return number if math.isfinite(number) else None


def object_features(
    objects: Sequence[CatalogObject],
    *,
    coefficients: pd.DataFrame | None = None,
    use_material: bool = False,
    coefficients_path: str | None = None,
    path: str | None = None,
) -> pd.DataFrame:
    """(W, D, λ) per object, in the order given, from the sources of the module docstring.

    Args:
        objects: the catalog objects to lift.
        coefficients: a coefficients table (``object_id``, ``deformability_n_per_cm``,
            ``damping_ns_per_cm``), or None.
        use_material: fall back to the catalog's material values (the simulator's ground truth).
        coefficients_path, path: the coefficients' and the catalog's file names, for messages.

    Returns:
        ``object_id`` and :data:`FEATURE_COLUMNS`, one row per object, plus ``feature_source``
        (``"coefficients"``, ``"catalog"`` or ``"material"``).

    Raises:
        InputDataError: an object without D and λ, or with one that is not a finite number
            (naming the object and where it looked; exit 65).
    """
    by_id: dict[str, Mapping[str, Any]] = {}
    if coefficients is not None:
        by_id = {str(r["object_id"]): r for r in coefficients.to_dict("records")}
    rows = []
    for obj in objects:
        oid = obj.object_id
        found: tuple[Any, Any, str] | None = None
        if oid in by_id:
            found = (by_id[oid].get(_D), by_id[oid].get(_LAMBDA), "coefficients")
        elif _finite(obj.get(_D)) is not None or _finite(obj.get(_LAMBDA)) is not None:
            found = (obj.get(_D), obj.get(_LAMBDA), "catalog")
        elif use_material and obj.has_material:
            found = (obj.material_stiffness_n_per_cm, obj.material_damping_ns_per_cm, "material")
        if found is None:
            where = [f"not in {coefficients_path or 'the coefficients'}"] if by_id else []
            where.append(f"the catalog has no {_D} / {_LAMBDA}")
            hint = "pass --coefficients COEFFICIENTS.parquet (from characterize)"
            raise InputDataError(
                f"object {oid!r}: no D and λ to predict its start from ({'; '.join(where)}); "
                f"{hint}",
                path=coefficients_path if by_id else path,
            )
        d, lam, source = found
        if _finite(d) is None or _finite(lam) is None:
            bad = _D if _finite(d) is None else _LAMBDA
            raise InputDataError(
                f"object {oid!r}: {bad} from the {source} is not a finite number ({d!r}, {lam!r})"
                f"; a start needs both D and λ (leave the object out with --objects)",
                path=coefficients_path if source == "coefficients" else path,
            )
        rows.append(
            {
                "object_id": oid,
                FEATURE_COLUMNS[0]: float(obj.weight_n),
                _D: float(d),
                _LAMBDA: float(lam),
                "feature_source": source,
            }
        )
    return pd.DataFrame(rows, columns=["object_id", *FEATURE_COLUMNS, "feature_source"])


@dataclass(frozen=True)
class StartSeed:
    """A source of start forces: a model or an index table, and the search's start margin.

    Attributes:
        source: ``"model"`` or ``"table"``.
        predictor: see :data:`Predictor`.
        margin: the first attempt is at the prediction times this (>= 1).
        settings: JSON-serialisable facts for the outputs' provenance (file, margin, ...).
        coefficients: a coefficients table with the objects' measured D and λ, or None (see
            :func:`object_features`).
        coefficients_path: its file name, for messages.
        inputs: the files the seed was read from (hashed into the outputs' provenance).
    """

    __repr__ = short_repr

    source: StartSource
    predictor: Predictor
    margin: float = 1.0
    settings: Mapping[str, Any] = field(default_factory=dict)
    coefficients: pd.DataFrame | None = field(default=None, repr=False)
    coefficients_path: str | None = None
    inputs: tuple[str, ...] = ()

    def starts(
        self,
        objects: Sequence[CatalogObject],
        *,
        use_material: bool = False,
        path: str | None = None,
    ) -> dict[str, StartEstimate]:
        """The start of each object: its features (:func:`object_features`), then :meth:`estimate`.

        Raises:
            InputDataError: an object without D and λ (exit 65).
        """
        features = object_features(
            objects,
            coefficients=self.coefficients,
            use_material=use_material,
            coefficients_path=self.coefficients_path,
            path=path,
        )
        return self.estimate(features, f_w_n=[obj.f_w_n() for obj in objects])

    def estimate(
        self, features: pd.DataFrame, *, f_w_n: Sequence[float] | np.ndarray
    ) -> dict[str, StartEstimate]:
        """The start of every row of ``features`` (``object_id`` and :data:`FEATURE_COLUMNS`).

        Args:
            features: from :func:`object_features`.
            f_w_n: ``[n]`` F_w of the rows, N (the table scales its entries' ratio by it).

        Returns:
            object_id -> :class:`StartEstimate`, in the rows' order.
        """
        predicted, outside, warnings, upper = self.predictor(
            features, np.asarray(f_w_n, dtype=np.float64)
        )
        out: dict[str, StartEstimate] = {}
        for i, oid in enumerate(features["object_id"].astype(str)):
            p = float(predicted[i])
            fallback = bool(outside[i]) or not (math.isfinite(p) and p > 0)
            warning = None
            if fallback:
                why = warnings[i] or f"predicted L_f {p!r} N is not a positive number"
                warning = f"object {oid!r}: {why}; starting at F_w (refine)"
            out[oid] = StartEstimate(oid, p, not fallback, self.source, warning, float(upper[i]))
        return out

    @classmethod
    def from_model(
        cls, model: Any, *, margin: float = 1.0, settings: Mapping[str, Any] | None = None
    ) -> StartSeed:
        """A seed from a lifting-force model: a :class:`deformctl.grip.fast.Predictor` (any
        model file, :func:`load_start_model`) or a fitted estimator from
        :func:`deformctl.train.train_model`.

        A μ-aware model (the grip model) gets each object's μ from its F_w (μ = W / (2 F_w)).
        """
        from deformctl.grip.fast import Predictor as FastPredictor

        if not isinstance(model, FastPredictor):
            from deformctl.grip.export import export_model

            train_range = {
                c: [float(lo), float(hi)]
                for c, lo, hi in zip(
                    model.feature_names_in_, model.feature_min_, model.feature_max_, strict=True
                )
            }
            model = FastPredictor.from_export(
                export_model(model), {"training_range": train_range}, "model", check_points=False
            )
        fast: FastPredictor = model
        coverage: float | None = START_BOUND_COVERAGE
        try:
            fast.margin(START_BOUND_COVERAGE)
        except InputDataError:  # no (or too few) calibration scores: no bound to record
            coverage = None

        def predictor(
            features: pd.DataFrame, f_w_n: np.ndarray
        ) -> tuple[np.ndarray, np.ndarray, list[str | None], np.ndarray]:
            ids = features["object_id"].astype(str).tolist()
            w = features[FEATURE_COLUMNS[0]].to_numpy(dtype=np.float64)
            mu = w / (2.0 * f_w_n) if fast.needs_friction else None
            est = fast.predict_many(
                w,
                features[_D].to_numpy(dtype=np.float64),
                features[_LAMBDA].to_numpy(dtype=np.float64),
                mu,
                names=ids,
                coverage=coverage,
            )
            notes: dict[str, str] = {}
            for line in est.warnings:  # "ID: outside the training range: ..."
                oid, _, rest = line.partition(": ")
                notes[oid] = rest.replace("the training range", "the model's training range", 1)
            return (
                est.lift_force_n,
                est.outside_training_range,
                [notes.get(i) for i in ids],
                est.lift_force_upper_n,
            )

        return cls("model", predictor, float(margin), dict(settings or {}))

    @classmethod
    def from_index_table(
        cls,
        table: pd.DataFrame,
        *,
        k: int | None = None,
        margin: float = 1.0,
        settings: Mapping[str, Any] | None = None,
    ) -> StartSeed:
        """A seed from an index table: its nearest entry, or with ``k`` the IDW of ``k`` nearest.

        The estimate is the entry's ``lift_force_n / f_w_n`` times the object's F_w when the
        table has ``f_w_n`` for every entry, else the entry's ``lift_force_n``.

        Raises:
            UsageError: ``k < 1``.
            SchemaError / InputDataError: see :func:`deformctl.table.validate_index_table`.
        """
        from deformctl.table import standardized_distances, validate_index_table

        START_INTERPOLATE.check_optional(k)
        validate_index_table(table)
        keys = table[list(FEATURE_COLUMNS)].to_numpy(dtype=np.float64)
        lo, hi = keys.min(axis=0), keys.max(axis=0)
        forces = table["lift_force_n"].to_numpy(dtype=np.float64)
        f_w = (
            table["f_w_n"].to_numpy(dtype=np.float64)
            if "f_w_n" in table.columns
            else np.full(len(table), np.nan)
        )
        use_ratio = bool(np.all(np.isfinite(f_w) & (f_w > 0)))

        def predictor(
            features: pd.DataFrame, f_w_n: np.ndarray
        ) -> tuple[np.ndarray, np.ndarray, list[str | None], np.ndarray]:
            q = features[list(FEATURE_COLUMNS)].to_numpy(dtype=np.float64)
            dist = standardized_distances(table, q) if len(q) else np.empty((0, len(table)))
            values = forces / f_w if use_ratio else forces
            predicted = np.empty(len(q))
            for i, row in enumerate(dist):
                order = np.argsort(row, kind="stable")[: (k or 1)]
                d = row[order]
                w = (d == 0).astype(float) if (d == 0).any() else 1.0 / d**2
                predicted[i] = float(np.dot(w / w.sum(), values[order]))
            if use_ratio:
                predicted = predicted * f_w_n
            outside = (q < lo) | (q > hi)
            notes: list[str | None] = []
            for i in range(len(q)):
                parts = [
                    f"{col} = {q[i, j]:g} not in [{lo[j]:g}, {hi[j]:g}]"
                    for j, col in enumerate(FEATURE_COLUMNS)
                    if outside[i, j]
                ]
                notes.append(
                    f"outside the index table's range: {'; '.join(parts)}" if parts else None
                )
            return predicted, outside.any(axis=1), notes, np.full(len(q), np.nan)

        info = {"interpolate_k": k, "ratio_to_f_w": use_ratio, **dict(settings or {})}
        return cls("table", predictor, float(margin), info)


def _coefficients(path: str | None) -> pd.DataFrame | None:
    if path is None:
        return None
    from deformctl.artifacts import read_table

    return read_table(path, "coefficients")


def load_start_model(path: str, *, margin: float, coefficients: str | None = None) -> StartSeed:
    """:meth:`StartSeed.from_model` from a model file (or a bundled name such as ``grip``).

    Args:
        path: the model file (``train -o``) or a bundled model's name.
        margin: the start margin (>= 1).
        coefficients: a coefficients table with the objects' D and λ, or None.

    Raises:
        UsageError: ``margin`` < 1 (exit 2).
        MissingInputError: no such file (exit 66).
        InputDataError: not a model file, a type outside the allow-list, or a model whose
            features are neither :data:`FEATURE_COLUMNS` nor the grip model's (exit 65); see
            also :func:`_coefficients`.
    """
    from deformctl.grip.fast import NoNumpyExportError, resolve_model_path
    from deformctl.grip.fast import Predictor as FastPredictor
    from deformctl.grip.groups import GRIP_FEATURES
    from deformctl.lift.search import validate_start_margin

    validate_start_margin(margin)
    try:
        predictor = FastPredictor.load(path)
    except NoNumpyExportError:  # a model file from before the numpy export (format 1)
        from deformctl.artifacts.model import load_predictor

        predictor = load_predictor(resolve_model_path(path))
    if predictor.features not in (FEATURE_COLUMNS, GRIP_FEATURES):
        raise InputDataError(
            f"the model takes {list(predictor.features)}, not the features a start is predicted "
            f"from ({', '.join(FEATURE_COLUMNS)}, and friction_mu for a grip model)",
            path=path,
        )
    coefficients_table = _coefficients(coefficients)
    settings = {"model": path, "margin": float(margin), "coefficients": coefficients}
    seed = StartSeed.from_model(predictor, margin=margin, settings=settings)
    return dataclasses.replace(
        seed,
        coefficients=coefficients_table,
        coefficients_path=coefficients,
        inputs=(str(predictor.path), *([coefficients] if coefficients else [])),
    )


def load_start_table(
    path: str, *, margin: float, k: int | None = None, coefficients: str | None = None
) -> StartSeed:
    """:meth:`StartSeed.from_index_table` from an index table file.

    Args:
        path: the index table (``table -o``).
        margin: the start margin (>= 1).
        k: interpolate the ``k`` nearest entries (None: the nearest entry).
        coefficients: a coefficients table with the objects' D and λ, or None.

    Raises:
        UsageError: ``margin`` < 1 or ``k`` < 1 (exit 2).
        MissingInputError: no such file (exit 66).
        SchemaError, InputDataError: not an index table, or unusable (exit 65).
    """
    from deformctl.artifacts import read_table
    from deformctl.errors import error_context
    from deformctl.lift.search import validate_start_margin

    validate_start_margin(margin)
    START_INTERPOLATE.check_optional(k)
    table = read_table(path, "index_table")
    coefficients_table = _coefficients(coefficients)
    settings = {"table": path, "margin": float(margin), "coefficients": coefficients}
    with error_context(path):
        seed = StartSeed.from_index_table(table, k=k, margin=margin, settings=settings)
    return dataclasses.replace(
        seed,
        coefficients=coefficients_table,
        coefficients_path=coefficients,
        inputs=(path, *([coefficients] if coefficients else [])),
    )
