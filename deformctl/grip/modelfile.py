"""One validation of a model file, numpy only: the estimator and its numpy export must agree.

A model file holds the network twice: the scikit-learn estimator (skops' ``.npy`` members and
``schema.json``) and its numpy export in the metadata (``numpy_model``), which ``predict``,
``lift --start-model`` and ``adapt`` evaluate without importing scikit-learn. ``inspect`` loads
the estimator. Checking only one copy let a file pass one command and be refused by another,
so every command that reads a model file (:meth:`deformctl.grip.fast.Predictor.load`, which
:func:`deformctl.artifacts.model.load_model` calls too) runs :func:`file_problem`:

* every type and loader ``schema.json`` names is in :data:`ALLOWED_TYPES` /
  :data:`ALLOWED_LOADERS` (read as JSON; nothing is imported or built);
* the estimator's arrays, read with ``numpy.load(allow_pickle=False)``, are the export's
  bit for bit (the scaler's mean and scale, every layer's weights and biases), and its
  activation, ζ shift or scale index, features, layer count and training range agree.

So a change to either copy refuses the file everywhere with the same line (exit 65).
"""

from __future__ import annotations

import io
import zipfile
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from deformctl import jsonsafe
from deformctl.errors import InputDataError, MissingInputError

__all__ = [
    "ALLOWED_LOADERS",
    "ALLOWED_TYPES",
    "MODEL_FORMATS",
    "file_problem",
    "read_model_metadata",
    "walk_types",
]

#: Every type a model file may contain, as ``module.Class`` (the form skops reports).
ALLOWED_TYPES: frozenset[str] = frozenset(
    {
        "builtins.dict",
        "builtins.list",
        "builtins.tuple",
        "builtins.str",
        "builtins.int",
        "builtins.float",
        "builtins.bool",
        "builtins.NoneType",
        "numpy.ndarray",
        "numpy.float64",
        "numpy.int64",
        "numpy.random.mtrand.RandomState",
        "sklearn.pipeline.Pipeline",
        "sklearn.preprocessing._data.StandardScaler",
        "sklearn.neural_network._multilayer_perceptron.MLPRegressor",
        "deformctl.model.ScaledTargetRegressor",
        "deformctl.train.ScaledTargetRegressor",  # files written before the class moved
        "deformctl.grip.model.GripForceRegressor",
    }
)

#: The skops node loaders a model file may use (no functions, methods, operators, partials).
ALLOWED_LOADERS: frozenset[str] = frozenset(
    {
        "DictNode",
        "ListNode",
        "TupleNode",
        "JsonNode",
        "TypeNode",
        "NdArrayNode",
        "ObjectNode",
        "RandomStateNode",
    }
)

#: The model formats the numpy predictor reads (``deformctl.artifacts.model.READABLE_FORMATS``).
MODEL_FORMATS = ("deformctl-lift-force-model/1", "deformctl-lift-force-model/2")
#: The largest ``schema.json`` a model file may have.
MAX_SCHEMA_BYTES = 64 * 1024 * 1024
#: The largest ``.npy`` member read (a model's arrays are a few kB).
MAX_ARRAY_BYTES = 16 * 1024 * 1024


def walk_types(node: Any) -> Iterator[tuple[str, str | None]]:
    """Yield ``(module.Class, loader)`` for every typed node of a skops ``schema.json`` tree."""
    stack = [node]
    while stack:
        item = stack.pop()
        if isinstance(item, dict):
            if "__class__" in item or "__module__" in item:
                loader = item.get("__loader__")
                yield (
                    f"{item.get('__module__')}.{item.get('__class__')}",
                    loader if isinstance(loader, str) else str(loader),
                )
            stack.extend(item.values())
        elif isinstance(item, list):
            stack.extend(item)


def _array_nodes(node: Any) -> Iterator[dict[str, Any]]:
    """Every numpy array node of a ``schema.json`` tree."""
    stack = [node]
    while stack:
        item = stack.pop()
        if isinstance(item, dict):
            if item.get("__loader__") == "NdArrayNode" and item.get("type") == "numpy":
                yield item
            stack.extend(item.values())
        elif isinstance(item, list):
            stack.extend(item)


def _type_problem(schema: Any) -> str | None:
    types, loaders = set(), set()
    for type_name, loader in walk_types(schema):
        types.add(type_name)
        if loader is not None and loader != "None":
            loaders.add(loader)
    bad = sorted(types - ALLOWED_TYPES) + [f"loader {x}" for x in sorted(loaders - ALLOWED_LOADERS)]
    if bad:
        return f"refusing to load: unexpected type(s) in the model file: {', '.join(bad)}"
    return None


class _Reader:
    """Reads the estimator's nodes out of an open archive (KeyError/TypeError/ValueError on
    anything malformed)."""

    def __init__(self, archive: zipfile.ZipFile) -> None:
        self.archive = archive

    @staticmethod
    def state(node: Any) -> Mapping[str, Any]:
        """An ObjectNode's attribute dict."""
        if node.get("__loader__") != "ObjectNode":
            raise TypeError("not an object")
        inner = node["content"]
        state = inner.get("content", inner)
        if not isinstance(state, dict):
            raise TypeError("no state")
        return state

    @staticmethod
    def value(node: Any) -> Any:
        """A JsonNode's value."""
        if node.get("__loader__") != "JsonNode":
            raise TypeError("not a value")
        return jsonsafe.loads(node["content"], allow_nan=True)

    def array(self, node: Any) -> np.ndarray:
        """An NdArrayNode's array, read without pickle."""
        if node.get("__loader__") != "NdArrayNode" or node.get("type") != "numpy":
            raise TypeError("not an array")
        info = self.archive.getinfo(str(node["file"]))
        if info.file_size > MAX_ARRAY_BYTES:
            raise ValueError("an array too large for a model")
        return np.asarray(np.load(io.BytesIO(self.archive.read(info)), allow_pickle=False))

    def names(self, node: Any) -> list[str]:
        """An array of strings (skops stores it as a list of JSON values)."""
        if node.get("__loader__") != "NdArrayNode" or node.get("type") != "json":
            raise TypeError("not an array of names")
        return [str(self.value(item)) for item in node["content"]]

    def arrays(self, node: Any) -> list[np.ndarray]:
        """A ListNode of arrays."""
        if node.get("__loader__") != "ListNode":
            raise TypeError("not a list")
        return [self.array(item) for item in node["content"]]


def _same(a: Any, b: Any) -> bool:
    x, y = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return x.shape == y.shape and bool(np.array_equal(x, y))


def _estimator_problem(reader: _Reader, schema: Any, export: Mapping[str, Any]) -> str | None:
    model = reader.state(schema["content"]["model"])
    form = export.get("form")
    features = [str(c) for c in export.get("features") or []]
    names = model.get("feature_names_in_")
    if names is not None and reader.names(names) != features:
        return "the estimator's features are not the numpy export's"
    if reader.value(model["n_features_in_"]) != len(features):
        return "the estimator's feature count is not the numpy export's"
    for key in ("feature_min_", "feature_max_"):
        values = reader.array(model[key])
        if values.shape != (len(features),) or not np.all(np.isfinite(values)):
            return f"the estimator's {key} is not {len(features)} finite numbers"
    if form == "grip":
        shift = reader.value(model["zeta_shift"])
        if not (isinstance(shift, int | float) and shift == export.get("zeta_shift")):
            return "the estimator's zeta_shift is not the numpy export's"
        for key in ("group_min_", "group_max_"):
            values = reader.array(model[key])
            if values.shape != (2,) or not np.all(np.isfinite(values)):
                return f"the estimator's {key} is not 2 finite numbers"
    elif reader.value(model["scale_index"]) != export.get("scale_index"):
        return "the estimator's scale_index is not the numpy export's"
    pipe = reader.state(model["regressor_"])
    steps = pipe["steps"]["content"]
    scaler = reader.state(steps[0]["content"][1])
    mlp = reader.state(steps[1]["content"][1])
    if not (
        _same(reader.array(scaler["mean_"]), export["scaler_mean"])
        and _same(reader.array(scaler["scale_"]), export["scaler_scale"])
    ):
        return "the estimator's scaler is not the numpy export's"
    coefs, intercepts = reader.arrays(mlp["coefs_"]), reader.arrays(mlp["intercepts_"])
    weights, biases = list(export["weights"]), list(export["biases"])
    if len(coefs) != len(weights) or len(intercepts) != len(biases):
        return "the estimator's layers are not the numpy export's"
    for w, v in zip(coefs + intercepts, weights + biases, strict=True):
        if not _same(w, v):
            return "the estimator's weights are not the numpy export's"
    if reader.value(mlp["activation"]) != export.get("activation"):
        return "the estimator's activation is not the numpy export's"
    if reader.value(mlp["out_activation_"]) != "identity":
        return "the estimator's output activation is not a regressor's"
    if reader.value(mlp["n_layers_"]) != len(coefs) + 1 or reader.value(mlp["n_outputs_"]) != 1:
        return "the estimator's layer count does not match its weights"
    return None


def file_problem(path: str | Path, export: Mapping[str, Any]) -> str | None:
    """What makes a model file unusable beyond its metadata (module doc), or None.

    Args:
        path: the model file (a zip archive whose ``schema.json`` was read already).
        export: its metadata's ``numpy_model``.
    """
    try:
        with zipfile.ZipFile(path) as archive:
            schema = jsonsafe.loads(archive.read("schema.json"))
            problem = _type_problem(schema)
            if problem is not None:
                return problem
            reader = _Reader(archive)
            for node in _array_nodes(schema):  # every array readable as skops reads it
                reader.array(node)
            return _estimator_problem(reader, schema, export)
    except (KeyError, TypeError, ValueError, IndexError, AttributeError, OSError, EOFError,
            zipfile.BadZipFile) as err:  # fmt: skip
        what = type(err).__name__
        return f"its scikit-learn estimator cannot be read as the numpy export's ({what})"


def read_model_metadata(path: str | Path) -> dict[str, Any]:
    """A model file's metadata dict, read as JSON from the archive's ``schema.json``.

    Raises:
        MissingInputError: no such file (66).
        InputDataError: not a deformctl model file (65).
    """
    p = Path(path)
    if not p.is_file():
        raise MissingInputError("model file not found", path=p)
    try:
        with zipfile.ZipFile(p) as archive:
            info = archive.getinfo("schema.json")
            if info.file_size > MAX_SCHEMA_BYTES:
                raise InputDataError(
                    f"schema.json is {info.file_size} bytes, more than a model file holds", path=p
                )
            schema = jsonsafe.loads(archive.read(info))
        node = schema["content"]["metadata_json"]
        fmt = jsonsafe.loads(schema["content"]["format"]["content"])
        if node.get("__loader__") != "JsonNode" or node.get("__class__") != "str":
            raise TypeError("metadata_json is not a string")
        text = jsonsafe.loads(node["content"])
        if not isinstance(text, str):
            raise TypeError("metadata_json is not a string")
    except InputDataError:
        raise
    except zipfile.BadZipFile:
        raise InputDataError(
            "not a skops model file (truncated or not a zip archive)", path=p
        ) from None
    except (KeyError, TypeError, ValueError, AttributeError, OSError, EOFError) as err:
        raise InputDataError(f"not a deformctl model file ({type(err).__name__})", path=p) from None
    if fmt not in MODEL_FORMATS:
        raise InputDataError(
            f"not a deformctl model file (expected format {MODEL_FORMATS[-1]})", path=p
        )
    try:
        metadata = jsonsafe.loads(text, allow_nan=True)
    except ValueError as err:
        raise InputDataError(
            f"the model file's metadata is not usable JSON ({err})", path=p
        ) from None
    if not isinstance(metadata, dict):
        raise InputDataError("the model file's metadata is not a JSON object", path=p)
    return metadata
