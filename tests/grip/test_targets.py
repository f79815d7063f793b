"""A prediction far from the model's training targets.

``train`` stores the range of its training rows' L_f / F_w (``target_range.lift_ratio_f_w``); a
prediction more than :data:`~deformctl.grip.sanity.TARGET_FACTOR` (1.5) outside it is flagged
``prediction_implausible`` with a warning line naming the ratio and the range. Known truth: the
synthetic law of :mod:`._synthetic` (its training ratios are computed here and compared); the
bundled model over 20,000 random objects inside its training ranges flags none; the same model
with its stored range narrowed (its file's metadata rewritten) flags exactly the objects whose
ratio lies outside the narrowed band.
"""

from __future__ import annotations

import io
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.adapt import model_file_bytes
from deformctl.cli import app
from deformctl.errors import InputDataError
from deformctl.grip.fast import Predictor
from deformctl.grip.sanity import TARGET_FACTOR, implausible, implausible_line
from deformctl.model import TrainOptions
from deformctl.train import model_metadata, train_model

from ._synthetic import grip_index

runner = CliRunner()
N_RANDOM = 20_000
PREDICT = ["--weight-n", "2.9", "--deformability-n-per-cm", "30", "--damping-ns-per-cm", "0.47",
           "--friction-mu", "0.5"]  # fmt: skip


def _in_range_objects(predictor: Predictor, n: int, seed: int) -> dict[str, np.ndarray]:
    """n objects drawn uniformly (log for W and D) inside the model's stored training ranges."""
    rng = np.random.default_rng(seed)
    r = predictor.ranges

    def log_uniform(name: str) -> np.ndarray:
        lo, hi = r[name]
        return np.exp(rng.uniform(math.log(lo), math.log(hi), n))

    return {
        "weight_n": log_uniform("weight_n"),
        "deformability_n_per_cm": log_uniform("deformability_n_per_cm"),
        "damping_ns_per_cm": rng.uniform(*r["damping_ns_per_cm"], n),
        "friction_mu": rng.uniform(*r["friction_mu"], n),
    }


def _with_targets(tmp_path: Path, low: float, high: float) -> Path:
    """The bundled model's file with its stored target range replaced."""
    meta = dict(Predictor.load("grip").metadata)
    meta["target_range"] = {"lift_ratio_f_w": [low, high]}
    path = tmp_path / f"narrow-{low:g}-{high:g}.skops"
    path.write_bytes(model_file_bytes("grip", meta))
    return path


def test_train_stores_the_training_targets_range() -> None:
    index = grip_index(60, seed=3, noise=0.01)
    result = train_model(index, TrainOptions(train_size=40, seed=0, restarts=1))
    ids = set(result.split.train)
    train = index[index["object_id"].isin(ids)]
    ratio = train["lift_force_n"] / train["f_w_n"]
    meta = model_metadata(result)
    assert meta["target_range"]["lift_ratio_f_w"] == [ratio.min(), ratio.max()]


def test_the_bundled_model_is_silent_over_its_training_range() -> None:
    """20,000 random objects inside the ranges (ω_n, ζ, F_w / D too): no flag, and the
    measured ratios lie inside the stored targets' range."""
    grip = Predictor.load("grip")
    low, high = grip.metadata["target_range"]["lift_ratio_f_w"]
    assert (round(low, 4), round(high, 4)) == (1.1141, 2.0588)  # the training rows' L_f / F_w
    objects = _in_range_objects(grip, N_RANDOM, seed=0)
    est = grip.predict_many(*objects.values())
    inside = ~est.outside_training_range
    assert inside.sum() > 10_000, inside.sum()
    ratio = est.lift_force_n[inside] / est.f_w_n[inside]
    assert est.prediction_implausible is not None
    assert not est.prediction_implausible[inside].any()
    assert not [w for w in est.warnings if "far from the training targets" in w]
    assert low / 1.01 <= ratio.min()  # measured 1.108
    assert ratio.max() <= high * 1.01  # measured 2.023


def test_the_flag_fires_outside_the_band_and_not_inside() -> None:
    f_w = np.full(6, 2.0)
    targets = (1.1, 2.0)  # band 0.733-3.0
    lift = 2.0 * np.array([1.0, 2.99, 3.01, 5.0, 9.9, 1.1])
    assert implausible(lift, f_w, targets).tolist() == [False, False, True, True, True, False]
    assert implausible(lift, f_w).tolist() == [False] * 6  # no stored range: [1, 10] x F_w only
    assert implausible_line("A", 10.0, 2.0, targets) == (
        "A: predicted L_f 10 N = 5 x F_w is implausible: far from the training targets (L_f / "
        f"F_w 1.1-2; flagged outside x/÷ {TARGET_FACTOR:g}: 0.733-3)"
    )
    assert implausible_line("A", 30.0, 2.0, targets).endswith("outside [F_w, 10 x F_w] = [2, 20] N")


def test_predict_flags_what_a_narrowed_model_never_learned(tmp_path: Path) -> None:
    """Targets narrowed to 1.0-1.2 (band 0.667-1.8): the objects whose ratio is above 1.8 are
    flagged through the CLI with the warning line, the others are not."""
    narrow = _with_targets(tmp_path, 1.0, 1.2)
    grip = Predictor.load("grip")
    objects = _in_range_objects(grip, 200, seed=1)
    ratio = grip.predict_many(*objects.values()).lift_force_n / (
        objects["weight_n"] / (2 * objects["friction_mu"])
    )
    table_path = tmp_path / "objects.parquet"
    pd.DataFrame({"object_id": [f"o{i}" for i in range(200)], **objects}).to_parquet(table_path)
    res = runner.invoke(app, ["predict", str(narrow), str(table_path)])
    assert res.exit_code == 0, res.stderr
    table = pd.read_csv(io.StringIO(res.stdout))
    expected = ratio > 1.2 * TARGET_FACTOR
    assert 0 < expected.sum() < 200
    assert table["prediction_implausible"].tolist() == expected.tolist()
    far = [w for w in res.stderr.splitlines() if "far from the training targets" in w]
    assert len(far) == expected.sum()
    assert far[0].startswith("warning: o")
    good = runner.invoke(app, ["predict", "grip", str(table_path)])
    assert good.exit_code == 0
    assert "implausible" not in good.stderr


def test_a_malformed_target_range_refuses_the_model(tmp_path: Path) -> None:
    meta = dict(Predictor.load("grip").metadata)
    meta["target_range"] = {"lift_ratio_f_w": [2.0, -1.0]}
    bad = tmp_path / "bad.skops"
    bad.write_bytes(model_file_bytes("grip", meta))
    with pytest.raises(InputDataError, match="the model's target range is malformed"):
        Predictor.load(bad)
    res = runner.invoke(app, ["predict", str(bad), *PREDICT])
    assert res.exit_code == 65
    assert len(res.stderr.splitlines()) == 1, res.stderr


def test_adapt_widens_the_range_to_its_rig_rows(tmp_path: Path) -> None:
    from deformctl.adapt import adapt_model

    grip = Predictor.load("grip")
    objects = _in_range_objects(grip, 12, seed=4)
    f_w = objects["weight_n"] / (2 * objects["friction_mu"])
    rows = pd.DataFrame({"object_id": [f"R{i}" for i in range(12)], **objects})
    rows["lift_force_n"] = 1.6 * grip.predict_many(*objects.values()).lift_force_n
    rows["f_w_n"], rows["converged"], rows["source"] = f_w, True, "rig"
    result = adapt_model("grip", rows)
    low, high = result.metadata["target_range"]["lift_ratio_f_w"]
    rig = rows["lift_force_n"] / f_w
    base_low, base_high = grip.metadata["target_range"]["lift_ratio_f_w"]
    assert low == pytest.approx(min(base_low, rig.min()))
    assert high == pytest.approx(max(base_high, rig.max()))
    assert high > base_high  # the rig rows (1.6 x the model) reach above the simulated targets
    assert json.dumps(result.metadata["target_range"])  # stored as plain numbers
