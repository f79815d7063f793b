"""One loader: ``inspect``, ``predict``, ``lift --start-model`` and ``adapt`` accept or refuse the
same model files.

A hostile run found 22 tampered model files that ``inspect`` passed (it checked the stored
scikit-learn estimator) while ``predict`` and ``lift`` refused them (they use the numpy copy in
the metadata), and the other way round. Every command now goes through
:meth:`deformctl.grip.fast.Predictor.load`, which also checks that the estimator and the numpy
export are the same network (:mod:`deformctl.grip.modelfile`). Each file below, damaged in one
copy, the other or the metadata, gets one verdict from all four.
"""

from __future__ import annotations

import copy
import json
import math
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.adapt import adapt_model, model_file_bytes
from deformctl.artifacts.model import MODEL_FORMAT, load_model, sio
from deformctl.cli import app
from deformctl.errors import DeformctlError
from deformctl.grip.fast import Predictor, read_model_metadata, resolve_model_path
from deformctl.lift.seeded import load_start_model

cli = CliRunner()
BUNDLED = resolve_model_path("grip")


def _estimator(change: Callable[[Any], None]) -> Callable[[Path], Path]:
    """A copy whose scikit-learn estimator is changed (the metadata untouched)."""

    def write(dst: Path) -> Path:
        model, meta = load_model(BUNDLED)
        model = copy.deepcopy(model)
        change(model)
        payload = {"format": MODEL_FORMAT, "metadata_json": json.dumps(meta), "model": model}
        sio.dump(payload, dst)
        return dst

    return write


def _metadata(change: Callable[[dict[str, Any]], None]) -> Callable[[Path], Path]:
    """A copy whose metadata (numpy export, ranges, check points) is changed."""

    def write(dst: Path) -> Path:
        meta = copy.deepcopy(read_model_metadata(BUNDLED))
        change(meta)
        dst.write_bytes(model_file_bytes(str(BUNDLED), meta))
        return dst

    return write


def _mlp(m: Any) -> Any:
    return m.regressor_[-1]


def _set(path: str, value: Any) -> Callable[[dict[str, Any]], None]:
    def change(meta: dict[str, Any]) -> None:
        *keys, last = path.split(".")
        node: Any = meta
        for key in keys:
            node = node[int(key)] if isinstance(node, list) else node[key]
        if isinstance(node, list):
            node[int(last)] = value
        else:
            node[last] = value

    return change


def _scale_export_layer(meta: dict[str, Any]) -> None:
    exp = meta["numpy_model"]
    exp["weights"][0] = (np.asarray(exp["weights"][0]) * 1.001).tolist()


FILES: dict[str, Callable[[Path], Path]] = {
    "untouched": lambda dst: dst.write_bytes(BUNDLED.read_bytes()) and dst,  # type: ignore[func-returns-value]
    # the estimator changed, the numpy export not
    "estimator weight nan": _estimator(lambda m: _mlp(m).coefs_[0].__setitem__((0, 0), np.nan)),
    "estimator weight x1.001": _estimator(lambda m: _mlp(m).coefs_[1].__imul__(1.001)),
    "estimator weights x1e300": _estimator(lambda m: _mlp(m).coefs_[0].__imul__(1e300)),
    "estimator bias changed": _estimator(lambda m: _mlp(m).intercepts_[-1].__iadd__(0.5)),
    "estimator activation relu": _estimator(lambda m: setattr(_mlp(m), "activation", "relu")),
    "estimator out activation": _estimator(lambda m: setattr(_mlp(m), "out_activation_", "relu")),
    "estimator scaler scale": _estimator(lambda m: m.regressor_[0].scale_.__imul__(2.0)),
    "estimator scaler mean": _estimator(lambda m: m.regressor_[0].mean_.__iadd__(1.0)),
    "estimator zeta shift": _estimator(lambda m: setattr(m, "zeta_shift", 0.5)),
    "estimator feature_min nan": _estimator(lambda m: m.feature_min_.__setitem__(0, np.nan)),
    "estimator group_max inf": _estimator(lambda m: m.group_max_.__setitem__(1, np.inf)),
    "estimator n_layers": _estimator(lambda m: setattr(_mlp(m), "n_layers_", 7)),
    "estimator n_features": _estimator(lambda m: setattr(m, "n_features_in_", 3)),
    # the numpy export changed, the estimator not
    "export weight x1.001": _metadata(_scale_export_layer),
    "export activation": _metadata(_set("numpy_model.activation", "relu")),
    "export zeta shift": _metadata(_set("numpy_model.zeta_shift", 0.5)),
    "export scaler mean": _metadata(_set("numpy_model.scaler_mean.0", 3.0)),
    # the rest of the metadata
    "check point moved": _metadata(_set("check_points.lift_force_n.0", 1.0)),
    "training range nan": _metadata(_set("training_range.weight_n.1", math.nan)),
    "target range reversed": _metadata(_set("target_range.lift_ratio_f_w", [2.0, 1.0])),
    "score x100": _metadata(_set("conformal_scores.0", 100.0)),
    "n_calibration": _metadata(_set("n_calibration", 3)),
    # not read to predict: accepted by all four (inspect shows no provenance)
    "provenance not an object": _metadata(_set("provenance", "abc")),
}
ACCEPTED = {"untouched", "provenance not an object"}


def _index(path: Path) -> Path:
    """An index table of 12 rig rows near the grip model's predictions."""
    rng = np.random.default_rng(0)
    grip = Predictor.load("grip")
    n = 12
    W, D = rng.uniform(1, 20, n), rng.uniform(10, 40, n)
    lam, mu = rng.uniform(0.5, 5, n), rng.uniform(0.3, 0.8, n)
    lift = 1.05 * grip.predict_many(W, D, lam, mu).lift_force_n
    frame = pd.DataFrame({
        "object_id": [f"R{i}" for i in range(n)], "weight_n": W, "deformability_n_per_cm": D,
        "damping_ns_per_cm": lam, "friction_mu": mu, "f_w_n": W / (2 * mu), "lift_force_n": lift,
        "source": "rig", "converged": True})  # fmt: skip
    frame.to_parquet(path)
    return path


def _verdicts(model: Path, index: Path, tmp: Path) -> dict[str, bool]:
    args = ["--weight-n", "2.9", "--deformability-n-per-cm", "30", "--damping-ns-per-cm",
            "0.47", "--friction-mu", "0.5"]  # fmt: skip
    verdict = {
        "inspect": cli.invoke(app, ["inspect", str(model)]).exit_code,
        "predict": cli.invoke(app, ["predict", str(model), *args]).exit_code,
    }
    for name, call in (
        ("lift --start-model", lambda: load_start_model(str(model), margin=1.005)),
        ("adapt", lambda: adapt_model(str(model), pd.read_parquet(index))),
    ):
        try:
            call()
            verdict[name] = 0
        except DeformctlError as err:
            verdict[name] = err.exit_code
    for name, code in verdict.items():
        assert code in (0, 65), (name, code)
    return {name: code == 0 for name, code in verdict.items()}


@pytest.fixture(scope="module")
def index(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _index(tmp_path_factory.mktemp("index") / "rig.parquet")


@pytest.mark.parametrize("kind", list(FILES))
def test_every_command_gives_the_same_verdict(kind: str, index: Path, tmp_path: Path) -> None:
    model = FILES[kind](tmp_path / "model.skops")
    verdicts = _verdicts(model, index, tmp_path)
    assert len(set(verdicts.values())) == 1, verdicts
    assert all(verdicts.values()) == (kind in ACCEPTED), verdicts


def test_the_estimator_is_read_without_pickle(tmp_path: Path) -> None:
    # an estimator array member replaced by a pickled object array: refused, never unpickled
    model = tmp_path / "model.skops"
    model.write_bytes(BUNDLED.read_bytes())
    with zipfile.ZipFile(BUNDLED) as src:
        members = [n for n in src.namelist() if n.endswith(".npy")]
        data = {n: src.read(n) for n in src.namelist()}
    import io

    buf = io.BytesIO()
    np.save(buf, np.array([{"a": 1}], dtype=object), allow_pickle=True)
    data[members[0]] = buf.getvalue()
    with zipfile.ZipFile(model, "w") as dst:
        for name, blob in data.items():
            dst.writestr(name, blob)
    res = cli.invoke(app, ["predict", str(model), "--weight-n", "2.9",
                           "--deformability-n-per-cm", "30", "--damping-ns-per-cm", "0.47",
                           "--friction-mu", "0.5"])  # fmt: skip
    assert res.exit_code == 65
    assert res.stderr.count("\n") == 1
    assert cli.invoke(app, ["inspect", str(model)]).exit_code == 65
