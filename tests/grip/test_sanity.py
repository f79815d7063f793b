"""A model is checked, not trusted; every prediction is a lifting force.

A model whose weights are finite but absurd (the output layer's bias raised by 690, so it
predicts about 10^299 x F_w, its stored check points computed from the same weights) passes every
structural check; it is refused on loading because its prediction at its own training points is
not within [1, 10] x F_w by a factor 2. The bundled grip model and a freshly trained one load and
predict without a flag. Predictions below F_w or above 10 x F_w are flagged
``prediction_implausible`` with a warning; a prediction that is not a positive force is never
printed.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.artifacts.model import save_model
from deformctl.cli import app
from deformctl.errors import InputDataError
from deformctl.grip.fast import Predictor
from deformctl.grip.sanity import implausible, implausible_line
from deformctl.model import TrainOptions
from deformctl.predict import predict_objects
from deformctl.train import model_metadata, train_model

from ._synthetic import grip_index

runner = CliRunner()
PREDICT = ["--weight-n", "2.9", "--deformability-n-per-cm", "30", "--damping-ns-per-cm", "0.47"]


@pytest.fixture(scope="module")
def models(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    out = tmp_path_factory.mktemp("sanity")
    result = train_model(
        grip_index(60, seed=3, noise=0.01), TrainOptions(train_size=40, seed=0, restarts=1)
    )
    save_model(out / "good.skops", result.model, metadata=model_metadata(result))
    mlp = result.model.regressor_.steps[-1][1]
    mlp.intercepts_[-1] = mlp.intercepts_[-1] + 690.0  # log(L_f / F_w) + 690: finite weights
    save_model(out / "absurd.skops", result.model, metadata=model_metadata(result))
    return {"good": out / "good.skops", "absurd": out / "absurd.skops"}


def test_a_model_with_absurd_weights_is_refused_on_loading(models: dict[str, Path]) -> None:
    with pytest.raises(InputDataError, match="not a usable lifting-force model: it predicts L_f"):
        Predictor.load(models["absurd"])
    for command in (["predict", str(models["absurd"]), *PREDICT, "--friction-mu", "0.5"],
                    ["inspect", str(models["absurd"])]):  # fmt: skip
        res = runner.invoke(app, command)
        assert res.exit_code == 65, (command, res.stderr)
        lines = res.stderr.splitlines()
        assert len(lines) == 1, res.stderr
        assert lines[0].startswith(f"error: {models['absurd']}: not a usable lifting-force model")
        assert "x F_w at a stored training point" in lines[0]
        assert res.stdout == ""


@pytest.mark.parametrize("name", ["good", "bundled"])
def test_good_models_load_and_predict_without_a_flag(models: dict[str, Path], name: str) -> None:
    path = str(models["good"]) if name == "good" else "grip"
    res = runner.invoke(app, ["predict", path, *PREDICT, "--friction-mu", "0.5"])
    assert res.exit_code == 0, res.stderr
    assert "implausible" not in res.stderr
    table = pd.read_csv(io.StringIO(res.stdout))
    assert "prediction_implausible" not in table.columns
    ratio = table["predicted_lift_force_n"][0] / table["f_w_n"][0]
    assert 1.0 <= ratio <= 10.0


def test_implausible_fires_outside_f_w_to_ten_f_w_and_is_silent_inside() -> None:
    f_w = np.full(6, 2.0)
    lift = np.array([2.0, 19.9, 1.9, 20.1, np.nan, -1.0])
    assert implausible(lift, f_w).tolist() == [False, False, True, True, True, True]
    assert implausible(np.array([3.0, -3.0]), np.array([np.nan, np.nan])).tolist() == [False, True]
    assert implausible_line("A", 3.5e301, 2.0) == (
        "A: predicted L_f 3.5e+301 N is implausible: outside [F_w, 10 x F_w] = [2, 20] N"
    )


def test_predictions_below_f_w_are_flagged_and_non_forces_refused(
    models: dict[str, Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    predictor = Predictor.load(models["good"])
    inputs = {
        "weight_n": np.array([2.9, 2.9]), "deformability_n_per_cm": np.array([30.0, 30.0]),
        "damping_ns_per_cm": np.array([0.47, 0.47]), "friction_mu": np.array([0.5, 0.5]),
    }  # fmt: skip
    good = predict_objects(predictor, inputs, names=["A", "B"])
    assert good.prediction_implausible is not None
    assert not good.prediction_implausible.any()
    monkeypatch.setattr(Predictor, "_lift_force", lambda self, X: np.array([1.0, 2.9]))  # F_w = 2.9
    low = predict_objects(predictor, inputs, names=["A", "B"])
    assert low.prediction_implausible.tolist() == [True, False]  # type: ignore[union-attr]
    assert "A: predicted L_f 1 N is implausible: outside [F_w, 10 x F_w]" in low.warnings[-1]
    monkeypatch.setattr(Predictor, "_lift_force", lambda self, X: np.array([np.inf, -2.0]))
    with pytest.raises(InputDataError, match=r"the model predicts inf N for A, B: not a force"):
        predict_objects(predictor, inputs, names=["A", "B"])
