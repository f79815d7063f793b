"""Model files that pass the type allow-list but are structurally wrong.

Each is refused on load with one line (exit 65) before anything predicts.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import skops.io as sio
from sklearn.neural_network import MLPRegressor
from sklearn.preprocessing import StandardScaler
from typer.testing import CliRunner

from deformctl.artifacts.model import MODEL_FORMAT, load_model
from deformctl.cli import app
from deformctl.errors import InputDataError
from deformctl.model import TrainOptions
from deformctl.train import ScaledTargetRegressor, TrainResult, train_model
from tests._helpers.models import _table

runner = CliRunner()
DATA = Path(__file__).parents[1] / "data"


@pytest.fixture(scope="module")
def trained() -> TrainResult:
    return train_model(_table(), TrainOptions(train_size=20, seed=1, restarts=1))


def _steps(m: ScaledTargetRegressor) -> list[tuple[str, object]]:
    return m.regressor_.steps  # type: ignore[no-any-return]


def _scaler_for_regressor(m: ScaledTargetRegressor) -> None:
    _steps(m)[1] = ("mlp", _steps(m)[0][1])


def _unfitted_mlp(m: ScaledTargetRegressor) -> None:
    _steps(m)[1] = ("mlp", MLPRegressor(hidden_layer_sizes=(2,)))


def _unfitted_scaler(m: ScaledTargetRegressor) -> None:
    _steps(m)[0] = ("scale", StandardScaler())


def _nan_weight(m: ScaledTargetRegressor) -> None:
    mlp = _steps(m)[1][1]
    mlp.coefs_[0][0, 0] = np.nan  # type: ignore[attr-defined]


def _broken_chain(m: ScaledTargetRegressor) -> None:
    mlp = _steps(m)[1][1]
    mlp.coefs_[0] = mlp.coefs_[0][:, :1]  # type: ignore[attr-defined]


def _two_features(m: ScaledTargetRegressor) -> None:
    m.n_features_in_ = 2


def _scale_index(m: ScaledTargetRegressor) -> None:
    m.scale_index = 7


def _one_step(m: ScaledTargetRegressor) -> None:
    del _steps(m)[0]


def _two_outputs(m: ScaledTargetRegressor) -> None:
    mlp = _steps(m)[1][1]
    mlp.coefs_[-1] = np.hstack([mlp.coefs_[-1], mlp.coefs_[-1]])  # type: ignore[attr-defined]
    mlp.intercepts_[-1] = np.zeros(2)  # type: ignore[attr-defined]


BREAKS: dict[str, tuple[Callable[[ScaledTargetRegressor], None], str]] = {
    "regressor replaced by a scaler": (_scaler_for_regressor, "not an MLPRegressor"),
    "unfitted MLP": (_unfitted_mlp, "not fitted"),
    "unfitted scaler": (_unfitted_scaler, "scaler's mean_"),
    "NaN weight": (_nan_weight, "non-finite"),
    "layers that do not chain": (_broken_chain, "layer 0's biases has shape"),
    "two features": (_two_features, "expected 3"),
    "scaler index out of range": (_scale_index, "scale_index 7 is out of range"),
    "one step": (_one_step, r"not \(StandardScaler, MLPRegressor\)"),
    "two outputs": (_two_outputs, "2 outputs"),
}


def _broken(trained: TrainResult, case: str, path: Path) -> Path:
    model = copy.deepcopy(trained.model)
    BREAKS[case][0](model)
    sio.dump({"format": MODEL_FORMAT, "metadata_json": "{}", "model": model}, path)
    return path


@pytest.mark.parametrize("case", list(BREAKS))
def test_a_structurally_wrong_model_is_refused_on_load(
    case: str, trained: TrainResult, tmp_path: Path
) -> None:
    path = _broken(trained, case, tmp_path / "m.skops")
    with pytest.raises(InputDataError, match=BREAKS[case][1]) as info:
        load_model(path)
    assert info.value.exit_code == 65
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("case", ["unfitted MLP", "scaler index out of range"])
def test_predict_on_a_wrong_model_is_one_line(
    case: str, trained: TrainResult, tmp_path: Path
) -> None:
    path = _broken(trained, case, tmp_path / "m.skops")
    out = tmp_path / "p.parquet"
    result = runner.invoke(
        app, ["predict", str(path), str(DATA / "index_table.parquet"), "-o", str(out)]
    )
    assert result.exit_code == 65, result.output
    assert result.stderr.startswith(f"error: {path}: not a usable lifting-force model")
    assert result.stderr.count("\n") == 1
    assert not out.exists()


def test_a_good_model_still_loads(trained: TrainResult, tmp_path: Path) -> None:
    path = tmp_path / "m.skops"
    sio.dump({"format": MODEL_FORMAT, "metadata_json": "{}", "model": trained.model}, path)
    model, _ = load_model(path)
    assert model.n_features_in_ == 3
