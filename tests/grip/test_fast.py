"""The numpy predictor: the same numbers as scikit-learn, its checks, flags and warnings."""

from __future__ import annotations

import json
import math
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from deformctl.artifacts.model import load_model, load_predictor, save_model
from deformctl.errors import InputDataError, UsageError
from deformctl.grip.fast import (
    NO_SCORES_MESSAGE,
    UNRECORDED_MU_WARNING,
    NoNumpyExportError,
    Predictor,
    resolve_model_path,
)
from deformctl.grip.groups import GRIP_FEATURES
from deformctl.model import TrainOptions
from deformctl.train import model_metadata, train_model
from tests.grip._synthetic import grip_index


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A grip model with 30 calibration scores, a paper-form model trained at μ = 0.5."""
    out = tmp_path_factory.mktemp("models")
    table = grip_index(140, seed=5, noise=0.01)
    grip = train_model(table, TrainOptions(train_size=90, calibration_size=30, seed=1, restarts=1))
    save_model(out / "grip.skops", grip.model, metadata=model_metadata(grip))
    ratio = table["lift_force_n"] / table["f_w_n"]  # kept: an L_f below F_w is refused
    single = table.assign(
        friction_mu=0.5, f_w_n=table["weight_n"], lift_force_n=ratio * table["weight_n"]
    )
    paper = train_model(single, TrainOptions(train_size=90, seed=1, restarts=1))
    save_model(out / "paper.skops", paper.model, metadata=model_metadata(paper))
    return {"grip": out / "grip.skops", "paper": out / "paper.skops"}


def _rewrite_metadata(src: Path, dst: Path, change: dict[str, object]) -> None:
    """Copy a model file with its metadata changed (keys set to None are removed)."""
    with zipfile.ZipFile(src) as z_in, zipfile.ZipFile(dst, "w") as z_out:
        for info in z_in.infolist():
            data = z_in.read(info)
            if info.filename == "schema.json":
                schema = json.loads(data)
                node = schema["content"]["metadata_json"]
                meta = json.loads(json.loads(node["content"]))
                for key, value in change.items():
                    if value is None:
                        meta.pop(key, None)
                    else:
                        meta[key] = value
                node["content"] = json.dumps(json.dumps(meta))
                data = json.dumps(schema).encode()
            z_out.writestr(info, data)


def test_the_same_numbers_as_scikit_learn(files: dict[str, Path]) -> None:
    rng = np.random.default_rng(0)
    X = np.column_stack(
        [
            rng.uniform(0.5, 80, 500),
            rng.uniform(5, 60, 500),
            rng.uniform(0, 15, 500),
            rng.uniform(0.2, 1, 500),
        ]
    )
    for name, cols in (("grip", 4), ("paper", 3)):
        model, meta = load_model(files[name])
        sk = model.predict(pd.DataFrame(X[:, :cols], columns=meta["features"]))
        predictor = Predictor.load(files[name])
        mu = X[:, 3] if name == "grip" else None
        fast = predictor.predict_many(X[:, 0], X[:, 1], X[:, 2], mu).lift_force_n
        np.testing.assert_allclose(fast, sk, rtol=1e-13, atol=0)
        one = predictor.predict(*X[7, :3], *(X[7, 3:] if name == "grip" else ()))
        assert one.lift_force_n == pytest.approx(sk[7], rel=1e-13)


def test_scalar_and_batch_agree_on_every_field(files: dict[str, Path]) -> None:
    p = Predictor.load(files["grip"])
    args = (2.9, 30.0, 0.47, 0.5)
    one = p.predict(*args, coverage=0.9, max_safe_force_n=4.0, name="C")
    many = p.predict_many(*([a] for a in args), coverage=0.9, max_safe_force_n=[4.0], names=["C"])
    assert one.lift_force_n == pytest.approx(many.lift_force_n[0], rel=1e-14)
    assert one.lift_force_upper_n == pytest.approx(many.lift_force_upper_n[0], rel=1e-14)
    assert one.f_w_n == many.f_w_n[0] == 2.9
    assert one.window_ok == bool(many.window_ok[0])
    assert one.outside_training_range == bool(many.outside_training_range[0])
    assert list(one.warnings) == many.warnings


@pytest.mark.parametrize(
    ("args", "line"),
    [
        ((2.0, 10.0, 0.5, 0.0), "friction_mu must be a number in [0.01, 3]; it is 0 for A"),
        ((2.0, 10.0, 0.5, 3.5), "friction_mu must be a number in [0.01, 3]; it is 3.5 for A"),
        ((2.0, 10.0, 0.5, math.nan), "friction_mu is NaN or not a finite number for A"),
        ((math.inf, 10.0, 0.5, 0.5), "weight_n is NaN or not a finite number for A"),
        (
            (2.0, -1.0, 0.5, 0.5),
            "deformability_n_per_cm must be a number in [0.01, 100000] N/cm; it is -1 for A",
        ),
        (
            (2.0, 10.0, -0.2, 0.5),
            "damping_ns_per_cm must be a number in [0, 10000] N·s/cm (a fitted -0.05 counts as 0); "
            "it is -0.2 for A",
        ),
    ],
)
def test_bad_inputs_are_refused_naming_the_input_and_the_object(
    files: dict[str, Path], args: tuple[float, ...], line: str
) -> None:
    p = Predictor.load(files["grip"])
    with pytest.raises(InputDataError) as err:
        p.predict(*args, name="A")
    assert err.value.message == line
    with pytest.raises(InputDataError) as err:
        p.predict_many(*([a, 1.0] for a in args), names=["A", "B"])
    assert err.value.message == line


def test_a_mu_aware_model_needs_mu_and_a_coverage_must_be_in_the_open_unit_interval(
    files: dict[str, Path],
) -> None:
    p = Predictor.load(files["grip"])
    with pytest.raises(UsageError, match="needs each object's friction_mu"):
        p.predict(2.0, 10.0, 0.5)
    for bad in (0.0, 1.0, 1.5, -0.1, math.nan):
        with pytest.raises(UsageError, match="--coverage must be a number in"):
            p.predict(2.0, 10.0, 0.5, 0.5, coverage=bad)


def test_a_bound_needs_calibration_scores_enough_for_p(files: dict[str, Path]) -> None:
    with pytest.raises(InputDataError) as err:
        Predictor.load(files["paper"]).predict(30.0, 40.0, 1.0, coverage=0.9)
    assert err.value.message == NO_SCORES_MESSAGE
    assert "deformctl train --calibration-size N" in NO_SCORES_MESSAGE
    with pytest.raises(InputDataError, match=r"--coverage 0\.99 needs at least 99 calibration"):
        Predictor.load(files["grip"]).predict(2.0, 10.0, 0.5, 0.5, coverage=0.99)


def test_outside_the_training_range_flags_and_warns_inside_is_silent(
    files: dict[str, Path],
) -> None:
    p = Predictor.load(files["grip"])
    inside = p.predict(5.0, 20.0, 0.5, 0.5, coverage=0.9, name="in")
    assert not inside.outside_training_range
    assert inside.bound_guaranteed
    assert inside.warnings == ()
    out = p.predict(300.0, 20.0, 0.5, 0.5, coverage=0.9, name="heavy")
    assert out.outside_training_range
    assert not out.bound_guaranteed
    assert math.isfinite(out.lift_force_upper_n)
    assert len(out.warnings) == 1
    assert out.warnings[0].startswith("heavy: outside the training range: weight_n = 300 not in")


def test_the_force_window(files: dict[str, Path]) -> None:
    p = Predictor.load(files["grip"])
    free = p.predict(5.0, 20.0, 0.5, 0.5, coverage=0.9)
    fine = p.predict(5.0, 20.0, 0.5, 0.5, coverage=0.9, max_safe_force_n=100.0, name="X")
    assert fine.window_ok
    assert fine.warnings == ()
    assert fine.max_safe_force_n == 100.0
    # a safe force between L_f and its bound: the bound decides
    between = 0.5 * (free.lift_force_n + free.lift_force_upper_n)
    est = p.predict(5.0, 20.0, 0.5, 0.5, coverage=0.9, max_safe_force_n=between, name="X")
    assert not est.window_ok
    assert est.warnings == (
        f"X: no safe grip: its upper bound {free.lift_force_upper_n:.4g} N exceeds its safe "
        f"force {between:.4g} N (window_ok = false)",
    )
    # without a bound, L_f itself decides
    assert p.predict(5.0, 20.0, 0.5, 0.5, max_safe_force_n=between).window_ok
    low = p.predict(5.0, 20.0, 0.5, 0.5, max_safe_force_n=1.0, name="X")
    assert not low.window_ok
    assert "its lifting force" in low.warnings[0]
    # no safe force known: the window is unknown (None), never true, and a warning says so
    nan = p.predict(5.0, 20.0, 0.5, 0.5, max_safe_force_n=math.nan, name="Y")
    assert nan.window_ok is None
    assert len(nan.warnings) == 1
    assert nan.warnings[0].startswith("Y: no safe force known")
    assert nan.warnings[0].endswith("(window_ok = null)")
    many = p.predict_many([5.0] * 3, 20.0, 0.5, 0.5, max_safe_force_n=[100.0, 1.0, math.nan])
    assert many.window_ok.tolist() == [True, False, None]
    assert [w.split(":")[0] for w in many.warnings] == ["row 1", "row 2"]
    # not asked about a safe force at all: unknown, without a warning
    free_many = p.predict_many([5.0], 20.0, 0.5, 0.5)
    assert free.window_ok is None
    assert free.warnings == ()
    assert free_many.window_ok.tolist() == [None]


def test_a_single_mu_model_asked_about_another_mu(files: dict[str, Path]) -> None:
    p = Predictor.load(files["paper"])
    assert not p.needs_friction
    assert p.training_friction_mu == 0.5
    at = p.predict(30.0, 40.0, 1.0, 0.5, name="A")
    none = p.predict(30.0, 40.0, 1.0, name="A")
    assert at.warnings == none.warnings == ()
    assert not at.outside_training_range
    assert at.lift_force_n == none.lift_force_n
    assert none.f_w_n == 30.0
    other = p.predict(30.0, 40.0, 1.0, 1.0, name="A")
    assert other.outside_training_range
    assert other.lift_force_n == pytest.approx(at.lift_force_n / 2)  # scaled by F_w
    assert other.warnings == (
        "A: the model was trained at friction_mu = 0.5 only; friction_mu = 1 is outside its "
        "range, its prediction is scaled by F_w (L_f ∝ 1/μ)",
    )


def test_a_model_file_without_export_or_with_a_tampered_one(
    files: dict[str, Path], tmp_path: Path
) -> None:
    old = tmp_path / "old.skops"
    _rewrite_metadata(
        files["paper"],
        old,
        {"numpy_model": None, "check_points": None, "training_friction_mu": None},
    )
    with pytest.raises(NoNumpyExportError):
        Predictor.load(old)
    through_skops = load_predictor(old)  # the estimator, exported on the fly
    fast = Predictor.load(files["paper"])
    assert through_skops.predict(30.0, 40.0, 1.0).lift_force_n == pytest.approx(
        fast.predict(30.0, 40.0, 1.0).lift_force_n, rel=1e-14
    )
    est = through_skops.predict_many([30.0], [40.0], [1.0], [0.5])
    assert est.warnings == [UNRECORDED_MU_WARNING]
    assert not est.outside_training_range[0]

    meta = Predictor.load(files["grip"]).metadata
    export = dict(meta["numpy_model"])
    export["biases"] = [[b + 1e-6 for b in layer] for layer in export["biases"]]
    tampered = tmp_path / "tampered.skops"
    _rewrite_metadata(files["grip"], tampered, {"numpy_model": export})
    with pytest.raises(InputDataError, match="does not reproduce its stored predictions"):
        Predictor.load(tampered)


def test_bundled_names_resolve_to_the_package_data() -> None:
    path = resolve_model_path("grip")
    assert path.name == "grip.skops"
    assert path.parent.name == "models"
    assert resolve_model_path("./grip") == Path("./grip")
    assert resolve_model_path("grip.skops") == Path("grip.skops")


def test_features_are_the_grip_models(files: dict[str, Path]) -> None:
    assert Predictor.load(files["grip"]).features == GRIP_FEATURES
