"""Model files: round trip, atomic/no-overwrite writes, and refusal of anything unexpected."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import skops.io as sio
from sklearn.linear_model import LinearRegression
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import FunctionTransformer

from deformctl.artifacts.model import (
    ALLOWED_TYPES,
    MODEL_FORMAT,
    inspect_types,
    load_model,
    save_model,
)
from deformctl.errors import InputDataError, MissingInputError, OutputExistsError, UsageError
from deformctl.model import TrainOptions
from deformctl.train import FEATURES, TrainResult, predict, train_model
from tests._helpers.models import _metadata, _table

LOADED_EVIL: list[str] = []


class Evil:
    """A custom class that records being rebuilt (skops would call ``__setstate__``)."""

    def __setstate__(self, state: dict[str, object]) -> None:
        LOADED_EVIL.append("rebuilt")
        self.__dict__.update(state)


@pytest.fixture(scope="module")
def trained() -> TrainResult:
    return train_model(_table(), TrainOptions(train_size=20, seed=1, restarts=1))


def test_round_trip_model_and_metadata(trained: TrainResult, tmp_path: Path) -> None:
    path = save_model(tmp_path / "model.skops", trained.model, metadata=_metadata(trained))
    assert sorted(os.listdir(tmp_path)) == ["model.skops"]  # no temp file left behind
    model, meta = load_model(path)
    features = _table()[list(FEATURES)]
    np.testing.assert_array_equal(model.predict(features), trained.model.predict(features))
    np.testing.assert_array_equal(
        predict(model, features).frame["predicted_lift_force_n"],
        predict(trained.model, features).frame["predicted_lift_force_n"],
    )
    assert meta["seed"] == 1
    assert meta["features"] == list(FEATURES)
    assert meta["training_range"] == json.loads(json.dumps(trained.metrics["training_range"]))
    assert (
        meta["metrics"]["test"]["max_rel_error"]
        == trained.metrics["model"]["test"]["max_rel_error"]
    )
    assert meta["format"] == MODEL_FORMAT
    assert meta["tool_version"]
    types, _ = inspect_types(path)
    assert types <= ALLOWED_TYPES
    assert "deformctl.model.ScaledTargetRegressor" in types


def test_a_file_naming_the_class_where_it_was_first_defined_still_loads(
    trained: TrainResult, tmp_path: Path
) -> None:
    """Files written before the estimator moved to ``deformctl.model`` name it
    ``deformctl.train.ScaledTargetRegressor`` (still re-exported there): they load as before."""
    import zipfile

    new = tmp_path / "new.skops"
    save_model(new, trained.model, metadata={"seed": 1})
    old = tmp_path / "old.skops"
    with zipfile.ZipFile(new) as src, zipfile.ZipFile(old, "w") as dst:
        for info in src.infolist():
            data = src.read(info)
            if info.filename == "schema.json":
                assert b'"deformctl.model"' in data
                data = data.replace(b'"deformctl.model"', b'"deformctl.train"')
            dst.writestr(info, data)
    types, _ = inspect_types(old)
    assert "deformctl.train.ScaledTargetRegressor" in types
    model, meta = load_model(old)
    x = pd.DataFrame([[30.0, 40.0, 5.0]], columns=list(FEATURES))
    assert meta["seed"] == 1
    assert model.predict(x).tolist() == trained.model.predict(x).tolist()


def test_existing_file_needs_force(trained: TrainResult, tmp_path: Path) -> None:
    path = tmp_path / "model.skops"
    path.write_bytes(b"old")
    with pytest.raises(OutputExistsError) as exc:
        save_model(path, trained.model, metadata={})
    assert str(exc.value) == f"{path}: exists already, not overwriting (use --force)"
    assert path.read_bytes() == b"old"
    save_model(path, trained.model, metadata={}, force=True)
    assert load_model(path)[1]["format"] == MODEL_FORMAT
    assert sorted(os.listdir(tmp_path)) == ["model.skops"]


def test_save_refuses_bad_model_or_metadata_and_leaves_nothing(
    trained: TrainResult, tmp_path: Path
) -> None:
    with pytest.raises(UsageError, match="not a lifting-force model: LinearRegression"):
        save_model(tmp_path / "m.skops", LinearRegression(), metadata={})  # type: ignore[arg-type]
    with pytest.raises(UsageError, match="not JSON-serialisable"):
        save_model(tmp_path / "m.skops", trained.model, metadata={"x": object()})
    with pytest.raises(UsageError, match="does not exist"):
        save_model(tmp_path / "nope" / "m.skops", trained.model, metadata={})
    assert os.listdir(tmp_path) == []


def _crafted(tmp_path: Path, model: object, name: str = "evil.skops") -> Path:
    path = tmp_path / name
    sio.dump({"format": MODEL_FORMAT, "metadata_json": "{}", "model": model}, path)
    return path


def test_function_reference_is_refused_and_named(tmp_path: Path) -> None:
    path = _crafted(tmp_path, make_pipeline(FunctionTransformer(func=os.system)))
    with pytest.raises(InputDataError) as exc:
        load_model(path)
    msg = str(exc.value)
    assert exc.value.exit_code == 65
    assert "\n" not in msg
    assert msg.startswith(f"{path}: refusing to load: unexpected type(s)")
    assert f"{os.system.__module__}.system" in msg
    assert "sklearn.preprocessing._function_transformer.FunctionTransformer" in msg


def test_custom_class_is_refused_without_being_rebuilt(tmp_path: Path) -> None:
    evil = Evil()
    evil.payload = "x"  # type: ignore[attr-defined]
    path = _crafted(tmp_path, evil)
    LOADED_EVIL.clear()
    with pytest.raises(InputDataError, match=rf"unexpected type\(s\).*{__name__}\.Evil"):
        load_model(path)
    assert LOADED_EVIL == []


def test_types_skops_trusts_by_default_are_still_refused(tmp_path: Path) -> None:
    """skops trusts scikit-learn's estimators by default; a model file may hold only ours.

    skops builds that default list when it is imported: in a process that imported it before
    deformctl did (checked in a fresh interpreter), it trusts ``LinearRegression``; deformctl's
    own import gives it only the model's estimators. The loader refuses the file either way."""
    path = _crafted(tmp_path, LinearRegression())
    with pytest.raises(InputDataError, match=r"sklearn\.linear_model\._base\.LinearRegression"):
        load_model(path)
    code = (
        "import sys, skops.io as sio\n"
        "from deformctl.artifacts.model import load_model\n"
        "from deformctl.errors import InputDataError\n"
        "assert sio.get_untrusted_types(file=sys.argv[1]) == [], 'skops does not trust it'\n"
        "try:\n"
        "    load_model(sys.argv[1])\n"
        "except InputDataError as err:\n"
        "    print(err)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code, str(path)], capture_output=True, text=True, check=True
    )
    assert "sklearn.linear_model._base.LinearRegression" in out.stdout


def test_wrong_format_tag_is_refused(trained: TrainResult, tmp_path: Path) -> None:
    path = tmp_path / "other.skops"
    sio.dump({"format": "something-else", "metadata_json": "{}", "model": trained.model}, path)
    with pytest.raises(InputDataError, match="not a deformctl model file"):
        load_model(path)


@pytest.mark.parametrize("keep", [0.5, 0.9])
def test_truncated_file_is_refused(trained: TrainResult, tmp_path: Path, keep: float) -> None:
    good = save_model(tmp_path / "good.skops", trained.model, metadata={})
    data = good.read_bytes()
    bad = tmp_path / "bad.skops"
    bad.write_bytes(data[: int(len(data) * keep)])
    with pytest.raises(InputDataError) as exc:
        load_model(bad)
    assert exc.value.exit_code == 65
    assert str(exc.value) == f"{bad}: not a skops model file (truncated or not a zip archive)"


def test_garbage_and_missing_files(tmp_path: Path) -> None:
    garbage = tmp_path / "g.skops"
    garbage.write_text("not a zip")
    with pytest.raises(InputDataError, match="truncated or not a zip archive"):
        load_model(garbage)
    with pytest.raises(MissingInputError) as exc:
        load_model(tmp_path / "missing.skops")
    assert exc.value.exit_code == 66


def test_skops_is_imported_without_changing_scikit_learn() -> None:
    """The model module imports skops with a short estimator list (its import's cost) and puts
    scikit-learn's discovery back: afterwards ``all_estimators`` lists every estimator again."""
    import sklearn.utils
    from sklearn.utils import discovery

    import deformctl.artifacts.model as model_module

    assert model_module.sio.__name__ == "skops.io"
    assert sklearn.utils.all_estimators is discovery.all_estimators
    assert len(sklearn.utils.all_estimators()) > 100
