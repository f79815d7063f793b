"""Model files: the lifting-force model and its metadata in one skops file, loaded safely.

A model file is a `skops <https://skops.readthedocs.io>`_ archive (a zip of ``schema.json`` and
``.npy`` arrays; no pickle) holding one dict::

    {"format": MODEL_FORMAT, "metadata_json": "<JSON text>", "model": <estimator>}

The metadata (seed, features, training ranges, metrics summary, tool version, ...) is stored as
JSON *text*, so reading it back is ``json.loads`` and can never build an object.

Loading never trusts the file. Before anything is imported or constructed,
:func:`load_model` reads ``schema.json`` as plain JSON and walks the whole object tree: every
node's type (``module.Class``) must be in :data:`ALLOWED_TYPES` and every node's loader in
:data:`ALLOWED_LOADERS` -- the handful of types the model is made of (builtins containers and
scalars, numpy arrays, ``RandomState``, ``Pipeline``, ``StandardScaler``, ``MLPRegressor`` and
:class:`deformctl.model.ScaledTargetRegressor` (which files written before it moved there name
``deformctl.train.ScaledTargetRegressor``, still re-exported there) or
:class:`deformctl.grip.model.GripForceRegressor`). A file with anything else (a function such as
``os.system``, any other class) is refused with :class:`~deformctl.errors.InputDataError` (exit
65) naming the type(s). Only then is ``skops.io.load`` called, with ``trusted`` set to the types
``skops.io.get_untrusted_types`` reports, after checking that they too are in the allow-list;
``trusted=True`` is never used. A truncated or non-zip file is refused the same way.

Writes are atomic: the archive is written to a temporary file in the target directory and moved
into place with :func:`os.replace`; an existing file is only replaced with ``force=True``.
"""

from __future__ import annotations

import json
import os
import zipfile
from collections.abc import Mapping
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _dist_version
from pathlib import Path
from typing import Any

import numpy as np
import sklearn.utils
from sklearn.neural_network import MLPRegressor
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler

from deformctl import jsonsafe
from deformctl.artifacts.io import atomic_output, note_input
from deformctl.errors import InputDataError, MissingInputError, OutputExistsError, UsageError
from deformctl.grip.groups import GRIP_FEATURES
from deformctl.grip.model import GripForceRegressor
from deformctl.grip.modelfile import ALLOWED_LOADERS, ALLOWED_TYPES, walk_types
from deformctl.model import FEATURES, ScaledTargetRegressor

#: The estimator classes a model file may hold.
LiftForceModel = ScaledTargetRegressor | GripForceRegressor


def _import_skops() -> Any:
    """``skops.io``, imported without scikit-learn's estimator discovery.

    On import, skops builds its *default* trust list from ``sklearn.utils.all_estimators()``,
    which imports every scikit-learn module: 2.4 s of the 2.9 s that ``import skops.io`` took
    here, paid by every ``train`` and ``predict``. This module never relies on that list (a
    model file's types are checked against :data:`ALLOWED_TYPES` and only those are passed to
    ``skops.io.load`` as trusted), so skops is imported while ``all_estimators`` lists only the
    estimators a model file may hold: the import takes 0.5 s. Its default list is then that
    short list, which can only make skops report more types as untrusted, never fewer.
    """
    import sys

    if "skops.io" in sys.modules:
        return sys.modules["skops.io"]
    from sklearn.utils import discovery

    def model_estimators(type_filter: Any = None) -> list[tuple[str, type]]:
        return [(cls.__name__, cls) for cls in (MLPRegressor, Pipeline, StandardScaler)]

    saved = (sklearn.utils.all_estimators, discovery.all_estimators)
    sklearn.utils.all_estimators = model_estimators
    discovery.all_estimators = model_estimators
    try:
        import skops.io
    finally:
        sklearn.utils.all_estimators, discovery.all_estimators = saved
    return skops.io


sio = _import_skops()

#: The hidden-layer activations of scikit-learn's MLP.
ACTIVATIONS = frozenset({"identity", "logistic", "tanh", "relu"})

#: The ``format`` tag of the model files :func:`save_model` writes. Format 2 adds to 1's
#: metadata the model's ``form`` (paper or grip), its numpy export (``numpy_model``), check
#: points and, when trained with calibration rows, the conformal scores; format 1 files still load.
MODEL_FORMAT = "deformctl-lift-force-model/2"
#: Every format :func:`load_model` reads.
READABLE_FORMATS = ("deformctl-lift-force-model/1", MODEL_FORMAT)


def _tool_version() -> str:
    try:
        return _dist_version("deformctl")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree
        return "unknown"


def inspect_types(path: str | os.PathLike[str]) -> tuple[set[str], set[str]]:
    """All types and loaders named in a skops file's ``schema.json``, without loading it.

    Returns:
        ``(types, loaders)``: sets of ``module.Class`` strings and loader names.

    Raises:
        MissingInputError: the file does not exist.
        InputDataError: not a zip archive (e.g. truncated), or no valid ``schema.json``.
    """
    p = Path(path)
    if not p.is_file():
        raise MissingInputError("model file not found", path=p)
    note_input(p)
    try:
        with zipfile.ZipFile(p) as archive:
            schema = jsonsafe.loads(archive.read("schema.json"))
    except zipfile.BadZipFile:
        raise InputDataError(
            "not a skops model file (truncated or not a zip archive)", path=p
        ) from None
    except KeyError:
        raise InputDataError("not a skops model file (no schema.json)", path=p) from None
    except (ValueError, OSError, EOFError) as err:
        raise InputDataError(
            f"unreadable model file ({type(err).__name__}: {err})", path=p
        ) from None
    types: set[str] = set()
    loaders: set[str] = set()
    for type_name, loader in walk_types(schema):
        types.add(type_name)
        if loader is not None and loader != "None":
            loaders.add(loader)
    return types, loaders


def save_model(
    path: str | os.PathLike[str],
    model: LiftForceModel,
    *,
    metadata: Mapping[str, Any],
    force: bool = False,
) -> Path:
    """Write ``model`` and ``metadata`` to a skops file at ``path``, atomically.

    Args:
        path: the output file (conventionally ``*.skops``).
        model: a fitted lifting-force model (:func:`deformctl.train.train_model`).
        metadata: JSON-serialisable facts about the model (seed, features, training ranges,
            metrics summary, ...); ``tool_version`` and ``format`` are added.
        force: replace an existing file.

    Returns:
        The path written.

    Raises:
        OutputExistsError: ``path`` exists and ``force`` is False.
        UsageError: the directory does not exist, ``model`` is not a lifting-force model, the
            metadata is not JSON-serialisable, or the model contains a type that
            :func:`load_model` would refuse.
    """
    out = Path(path)
    if out.exists() and not force:
        raise OutputExistsError(out)
    if not out.parent.is_dir():
        raise UsageError("output directory does not exist", path=out.parent)
    if not isinstance(model, ScaledTargetRegressor | GripForceRegressor):
        raise UsageError(f"not a lifting-force model: {type(model).__name__}")
    meta = {"format": MODEL_FORMAT, "tool_version": _tool_version(), **dict(metadata)}
    try:
        metadata_json = json.dumps(meta, sort_keys=True, allow_nan=True)
    except (TypeError, ValueError) as err:
        raise UsageError(f"model metadata is not JSON-serialisable: {err}") from None
    payload = {"format": MODEL_FORMAT, "metadata_json": metadata_json, "model": model}

    with atomic_output(out, force=force) as tmp:
        sio.dump(payload, tmp)
        types, loaders = inspect_types(tmp)
        bad = sorted(types - ALLOWED_TYPES) + sorted(loaders - ALLOWED_LOADERS)
        if bad:
            raise UsageError(
                f"the model contains types a model file may not hold: {', '.join(bad)}"
            )
    return out


def load_model(path: str | os.PathLike[str]) -> tuple[LiftForceModel, dict[str, Any]]:
    """Load a model file written by :func:`save_model`, trusting only :data:`ALLOWED_TYPES`.

    Returns:
        ``(model, metadata)``.

    Raises:
        MissingInputError: the file does not exist (exit 66).
        InputDataError: the file is truncated / not a skops archive, contains a type or loader
            outside the allow-list (named in the message), or is not a deformctl model file
            (exit 65).
    """
    p = Path(path)
    types, loaders = inspect_types(p)
    unexpected = sorted(types - ALLOWED_TYPES)
    bad_loaders = sorted(loaders - ALLOWED_LOADERS)
    if unexpected or bad_loaders:
        what = ", ".join([*unexpected, *(f"loader {x}" for x in bad_loaders)])
        raise InputDataError(
            f"refusing to load: unexpected type(s) in the model file: {what}", path=p
        )
    try:
        untrusted = sio.get_untrusted_types(file=p)
    except Exception as err:  # an untrusted file may break skops' parser in any way
        raise InputDataError(
            f"unreadable model file ({type(err).__name__}: {err})", path=p
        ) from None
    outside = sorted(set(untrusted) - ALLOWED_TYPES)
    if outside:
        raise InputDataError(
            f"refusing to load: unexpected type(s) in the model file: {', '.join(outside)}", path=p
        )
    try:
        payload = sio.load(p, trusted=sorted(untrusted))
    except Exception as err:  # truncated members, bad arrays, skops' own refusals, ...
        raise InputDataError(
            f"unreadable model file ({type(err).__name__}: {err})", path=p
        ) from None

    if not isinstance(payload, dict) or payload.get("format") not in READABLE_FORMATS:
        raise InputDataError(f"not a deformctl model file (expected format {MODEL_FORMAT})", path=p)
    model = payload.get("model")
    if not isinstance(model, ScaledTargetRegressor | GripForceRegressor):
        raise InputDataError(
            f"the model file holds a {type(model).__name__}, not a lifting-force model", path=p
        )
    raw = payload.get("metadata_json")
    try:
        metadata = jsonsafe.loads(raw, allow_nan=True) if isinstance(raw, str) else None
    except ValueError as err:
        raise InputDataError(
            f"the model file's metadata is not usable JSON ({err})", path=p
        ) from None
    if not isinstance(metadata, dict):
        raise InputDataError("the model file's metadata is not a JSON object", path=p)
    check_structure(model, path=p)
    if isinstance(metadata.get("numpy_model"), dict):  # the one validation predict and lift use
        from deformctl.grip.fast import Predictor

        Predictor.load(p)
    else:  # model format 1: the estimator is all there is
        _predictor(model, metadata, p)  # its output at its own training points (grip.sanity)
    return model, metadata


def _predictor(model: LiftForceModel, metadata: Mapping[str, Any], path: Path) -> Any:
    """The model as a :class:`deformctl.grip.fast.Predictor` (its numpy export), which refuses
    a model whose prediction at its own training points is not a lifting force."""
    from deformctl.grip.export import export_model
    from deformctl.grip.fast import Predictor

    meta = dict(metadata)
    if isinstance(model, ScaledTargetRegressor):
        meta.setdefault(
            "training_range",
            {
                c: [float(lo), float(hi)]
                for c, lo, hi in zip(FEATURES, model.feature_min_, model.feature_max_, strict=True)
            },
        )
    return Predictor.from_export(export_model(model), meta, path, check_points=False)


def _finite_array(value: Any, shape: tuple[int, ...], what: str) -> str | None:
    """None when ``value`` is a finite float array of ``shape``; else what is wrong."""
    if not isinstance(value, np.ndarray) or value.dtype.kind not in "fi":
        return f"{what} is not a numeric array"
    if value.shape != shape:
        return f"{what} has shape {value.shape}, expected {shape}"
    if not np.all(np.isfinite(value)):
        return f"{what} has non-finite values"
    return None


def _is_int(value: Any, expected: int | None = None) -> bool:
    ok = isinstance(value, int | np.integer) and not isinstance(value, bool)
    return ok and (expected is None or int(value) == expected)


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _structure_problem(model: LiftForceModel) -> str | None:
    """What is wrong with a loaded model's structure (None: it can predict)."""
    grip = isinstance(model, GripForceRegressor)
    features = GRIP_FEATURES if grip else FEATURES
    n = len(features)
    attrs = vars(model)
    if not _is_int(attrs.get("n_features_in_"), n):
        return f"the model takes {_short(attrs.get('n_features_in_'))} features, expected {n}"
    names = attrs.get("feature_names_in_")
    if names is not None and not (
        isinstance(names, np.ndarray | list | tuple) and [str(x) for x in names] == list(features)
    ):
        return f"the model's features are {_short(names)}, expected {list(features)}"
    if grip:
        shift = attrs.get("zeta_shift")
        if not (isinstance(shift, float | int) and np.isfinite(shift) and shift > 0):
            return f"zeta_shift {_short(shift)} is not a number > 0"
        for key in ("group_min_", "group_max_"):
            problem = _finite_array(attrs.get(key), (2,), key)
            if problem:
                return problem
    else:
        if "scale_index" not in attrs:
            return "the model has no scale_index"
        index = attrs["scale_index"]
        if index is not None and not (_is_int(index) and 0 <= index < n):
            return f"scale_index {_short(index)} is out of range (0..{n - 1})"
    for key in ("feature_min_", "feature_max_"):
        problem = _finite_array(attrs.get(key), (n,), key)
        if problem:
            return problem
    n = 2 if grip else n  # the network's inputs: the groups (grip) or the features
    pipe = attrs.get("regressor_")
    if not isinstance(pipe, Pipeline):
        return f"the regressor is a {type(pipe).__name__}, not a fitted Pipeline"
    raw_steps = vars(pipe).get("steps")
    steps = (
        [s[1] for s in raw_steps if isinstance(s, tuple) and len(s) == 2]
        if isinstance(raw_steps, list)
        else []
    )
    if len(steps) != 2 or not isinstance(steps[0], StandardScaler):
        return "the pipeline is not (StandardScaler, MLPRegressor)"
    scaler, mlp = steps
    if not isinstance(mlp, MLPRegressor):
        return f"the pipeline's last step is a {type(mlp).__name__}, not an MLPRegressor"
    for key in ("mean_", "scale_"):
        problem = _finite_array(vars(scaler).get(key), (n,), f"the scaler's {key}")
        if problem:
            return problem
    if not np.all(scaler.scale_ > 0):
        return "the scaler's scale_ is not > 0"
    coefs, intercepts = vars(mlp).get("coefs_"), vars(mlp).get("intercepts_")
    if not isinstance(coefs, list) or not isinstance(intercepts, list) or not coefs:
        return "the MLPRegressor is not fitted (no coefs_ / intercepts_)"
    if len(intercepts) != len(coefs) or not _is_int(vars(mlp).get("n_layers_"), len(coefs) + 1):
        return "the MLPRegressor's layers do not match (coefs_, intercepts_, n_layers_)"
    width = n
    for i, (w, b) in enumerate(zip(coefs, intercepts, strict=True)):
        out = w.shape[1] if isinstance(w, np.ndarray) and w.ndim == 2 else -1
        problem = _finite_array(w, (width, out), f"layer {i}'s weights") or _finite_array(
            b, (out,), f"layer {i}'s biases"
        )
        if problem:
            return problem
        width = out
    if width != 1:
        return f"the network has {width} outputs, expected 1"
    activation, out = vars(mlp).get("activation"), vars(mlp).get("out_activation_")
    if not (isinstance(activation, str) and activation in ACTIVATIONS and out == "identity"):
        return f"the network's activations ({_short(activation)}) are not a regressor's"
    if not _is_int(vars(mlp).get("n_outputs_"), 1):
        return "the MLPRegressor is not fitted for one output"
    return None


def check_structure(model: LiftForceModel, *, path: str | os.PathLike[str]) -> None:
    """Refuse a model whose structure cannot predict (the allow-list checks only the types).

    Checks: ``n_features_in_`` is 3 (and the feature names are :data:`~deformctl.model.FEATURES`),
    ``scale_index`` in range, the training range finite; the wrapped regressor is a fitted
    ``Pipeline(StandardScaler, MLPRegressor)``: the scaler's ``mean_`` / ``scale_`` of 3 finite
    values, the network's weights and biases finite and chained 3 → ... → 1, a regressor's
    activations. A grip model (:class:`~deformctl.grip.model.GripForceRegressor`): 4 features
    (:data:`~deformctl.grip.groups.GRIP_FEATURES`), ``zeta_shift`` > 0, finite group ranges, and
    a network on its 2 groups.

    Raises:
        InputDataError: one line naming what is wrong (exit 65).
    """
    try:
        problem = _structure_problem(model)
    except (TypeError, ValueError, AttributeError, IndexError) as err:  # attributes of odd types
        problem = f"malformed attributes ({type(err).__name__}: {err})"
    if problem is not None:
        raise InputDataError(f"not a usable lifting-force model: {problem}", path=path)


def load_predictor(path: str | os.PathLike[str]) -> Any:
    """A :class:`deformctl.grip.fast.Predictor` for a model file without a numpy export (model
    format 1): the estimator is loaded through the allow-list (:func:`load_model`) and exported.

    Raises:
        as :func:`load_model`.
    """
    model, metadata = load_model(path)
    return _predictor(model, metadata, Path(path))
