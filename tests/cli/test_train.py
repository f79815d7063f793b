"""``deformctl train`` and ``deformctl inspect`` on model files.

The index table is the synthetic one of ``examples/synthetic_index.py`` (closed-form L_f of the
paper's population), 30 objects, 20 for training. The metrics are checked against the per-object
predictions the command reports, recomputed here with numpy and scikit-learn's metric functions;
the training range against the min/max of the training rows named in the split.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import skops.io as sio
from sklearn.metrics import mean_absolute_error, r2_score
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import FunctionTransformer
from typer.testing import CliRunner

from deformctl.artifacts import sha256_file, write_table
from deformctl.artifacts.model import MODEL_FORMAT, load_model
from deformctl.cli import app
from deformctl.train import FEATURES
from tests._helpers.cli import N_OBJECTS, _error, write_index

runner = CliRunner()
TRAIN_SIZE = 20
SEED = 3


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> dict[str, object]:
    """One ``train`` run: its directory, index table, CliRunner result and metrics JSON."""
    d = tmp_path_factory.mktemp("train")
    index = write_index(d / "index.parquet")
    args = ["train", str(d / "index.parquet"), "-o", str(d / "model.skops")]
    args += ["--train-size", str(TRAIN_SIZE), "--seed", str(SEED), "--metrics", str(d / "m.json")]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.stderr
    return {
        "dir": d,
        "index": index,
        "result": result,
        "metrics": json.loads((d / "m.json").read_text()),
    }


def test_writes_model_and_metrics_only(trained: dict[str, object]) -> None:
    d = trained["dir"]
    assert isinstance(d, Path)
    assert sorted(os.listdir(d)) == ["index.parquet", "m.json", "model.skops"]
    result = trained["result"]
    last = result.stderr.splitlines()[-1]  # type: ignore[attr-defined]
    assert last.startswith("train: 30 object(s) done, 0 flagged, 0 failed in "), last
    assert last.endswith(f" s -> {d / 'model.skops'}, {d / 'm.json'}"), last


def test_seed_split_and_metrics_recorded(trained: dict[str, object]) -> None:
    m = trained["metrics"]
    index = trained["index"]
    assert isinstance(m, dict)
    assert isinstance(index, pd.DataFrame)
    assert m["seed"] == SEED
    assert m["hyperparameters"]["hidden"] == [2]
    assert m["features"] == list(FEATURES)
    assert (m["n_train"], m["n_test"]) == (TRAIN_SIZE, N_OBJECTS - TRAIN_SIZE)
    train_ids, test_ids = m["split"]["train"], m["split"]["test"]
    assert sorted(train_ids + test_ids) == sorted(index["object_id"])
    rows = index.set_index("object_id")
    for feat in FEATURES:
        assert m["training_range"][feat] == [
            rows.loc[train_ids, feat].min(),
            rows.loc[train_ids, feat].max(),
        ]

    _, meta = load_model(Path(str(trained["dir"])) / "model.skops")
    assert meta["seed"] == SEED
    assert meta["split"] == m["split"]
    assert meta["training_range"] == m["training_range"]
    assert meta["model"] == m["model"]
    assert meta["provenance"]["inputs"] == {
        str(Path(str(trained["dir"])) / "index.parquet"): sha256_file(
            Path(str(trained["dir"])) / "index.parquet"
        )
    }


def test_metrics_agree_with_reported_predictions(trained: dict[str, object]) -> None:
    m = trained["metrics"]
    assert isinstance(m, dict)
    preds = pd.DataFrame(m["predictions"])
    for split in ("train", "test"):
        part = preds[preds["split"] == split]
        assert list(part["object_id"]) == m["split"][split]
        y, p = part["lift_force_n"].to_numpy(), part["predicted_lift_force_n"].to_numpy()
        rel = np.abs(p - y) / y
        got = m["model"][split]
        assert got["max_rel_error"] == pytest.approx(rel.max(), rel=1e-12)
        assert got["median_rel_error"] == pytest.approx(np.median(rel), rel=1e-12)
        assert got["mae_n"] == pytest.approx(mean_absolute_error(y, p), rel=1e-12)
        assert got["r2"] == pytest.approx(r2_score(y, p), rel=1e-12)
        fw = part["f_w_n"].to_numpy()
        assert m["baseline_f_w"][split]["mae_n"] == pytest.approx(
            mean_absolute_error(y, fw), rel=1e-12
        )
    # The synthetic L_f is smooth in (W, D, λ): the 3-2-1 network must beat both baselines.
    # Across the OpenBLAS kernels (make golden-spread's 5): max 2.49-2.60 %, MAE 0.61-0.67 N
    # against the baselines' 6.78 and 20.17 N.
    assert m["model"]["test"]["max_rel_error"] < 0.10
    assert m["model"]["test"]["mae_n"] < m["baseline_nearest"]["test"]["mae_n"]
    assert m["model"]["test"]["mae_n"] < m["baseline_f_w"]["test"]["mae_n"]


def test_prints_the_metrics_table(trained: dict[str, object]) -> None:
    m = trained["metrics"]
    assert isinstance(m, dict)
    out = trained["result"].stdout  # type: ignore[attr-defined]
    for head in ("predictor", "max rel err", "median rel err", "MAE (N)", "R²"):
        assert head in out
    assert f"hidden 2, seed {SEED}, {TRAIN_SIZE} train / {N_OBJECTS - TRAIN_SIZE} test" in out
    for key, label in (
        ("model", "model"),
        ("baseline_nearest", "nearest entry"),
        ("baseline_f_w", "F_w alone"),
    ):
        for split in ("train", "test"):
            e = m[key][split]
            line = next(ln for ln in out.splitlines() if f" {label} " in ln and f" {split} " in ln)
            assert f"{100 * e['max_rel_error']:.2f} %" in line
            assert f"{100 * e['median_rel_error']:.2f} %" in line
            assert f"{e['mae_n']:.3f}" in line
            assert f"{e['r2']:.4f}" in line


def test_same_seed_gives_identical_predictions(trained: dict[str, object], tmp_path: Path) -> None:
    d = Path(str(trained["dir"]))
    args = ["train", str(d / "index.parquet"), "-o", str(tmp_path / "again.skops")]
    args += ["--train-size", str(TRAIN_SIZE), "--seed", str(SEED), "--metrics", "-"]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.stderr
    again = json.loads(result.stdout)  # --metrics - puts the JSON on stdout, the table on stderr
    assert "median rel err" in result.stderr
    first = trained["metrics"]
    assert isinstance(first, dict)
    assert again["predictions"] == first["predictions"]
    assert again["split"] == first["split"]
    model_a, _ = load_model(d / "model.skops")
    model_b, _ = load_model(tmp_path / "again.skops")
    X = pd.DataFrame(np.array([[30.0, 35.0, 2.0], [55.0, 48.0, 12.0]]), columns=list(FEATURES))
    np.testing.assert_array_equal(model_a.predict(X), model_b.predict(X))


def _listing(path: Path) -> list[str]:
    return sorted(os.listdir(path))


def test_too_few_rows_for_train_size(tmp_path: Path) -> None:
    write_index(tmp_path / "i.parquet", n=12)
    result = runner.invoke(
        app,
        [
            "train",
            str(tmp_path / "i.parquet"),
            "-o",
            str(tmp_path / "m.skops"),
            "--metrics",
            str(tmp_path / "m.json"),
        ],
    )
    assert _error(result, 65) == (
        "error: the index table has 12 rows; a training set of 40 needs at least 41 "
        "(40 train + at least 1 test)"
    )
    assert _listing(tmp_path) == ["i.parquet"]


def test_nan_feature_is_refused(tmp_path: Path) -> None:
    index = write_index(tmp_path / "i.parquet", n=12)
    index.loc[4, "damping_ns_per_cm"] = np.nan
    index.to_parquet(tmp_path / "nan.parquet")  # another tool's table: no deformctl metadata
    result = runner.invoke(
        app,
        [
            "train",
            str(tmp_path / "nan.parquet"),
            "-o",
            str(tmp_path / "m.skops"),
            "--train-size",
            "8",
        ],
    )
    msg = _error(result, 65)
    assert msg.startswith(f"error: {tmp_path / 'nan.parquet'}: field 'damping_ns_per_cm'")
    assert "P04" in msg
    assert _listing(tmp_path) == ["i.parquet", "nan.parquet"]


def test_constant_feature_is_refused(tmp_path: Path) -> None:
    index = write_index(tmp_path / "i.parquet", n=12)
    index["damping_ns_per_cm"] = 0.0
    write_table(index, tmp_path / "i.parquet", "index_table", provenance=None, force=True)
    result = runner.invoke(
        app,
        [
            "train",
            str(tmp_path / "i.parquet"),
            "-o",
            str(tmp_path / "m.skops"),
            "--train-size",
            "8",
        ],
    )
    assert _error(result, 65) == (
        "error: feature damping_ns_per_cm is constant (0) over the index table; "
        "the model cannot learn its effect"
    )
    assert _listing(tmp_path) == ["i.parquet"]


def test_missing_input_and_bad_options(tmp_path: Path) -> None:
    out = str(tmp_path / "m.skops")
    result = runner.invoke(app, ["train", str(tmp_path / "no.parquet"), "-o", out])
    assert _error(result, 66) == f"error: {tmp_path / 'no.parquet'}: no such file"
    for hidden, message in (("0", ">= 1"), ("2,x", "must be integers like 2 or 8,4; got '2,x'")):
        result = runner.invoke(app, ["train", "i.parquet", "-o", out, "--hidden", hidden])
        assert message in _error(result, 2)
    result = runner.invoke(app, ["train", "i.parquet", "-o", out, "--metrics", out])
    assert _error(result, 2) == f"error: -o and --metrics name the same file: {out}"
    result = runner.invoke(app, ["train", "i.parquet", "-o", "-"])
    assert "cannot be stdout" in _error(result, 2)
    assert _listing(tmp_path) == []


def test_existing_outputs_need_force(tmp_path: Path) -> None:
    write_index(tmp_path / "i.parquet", n=12)
    (tmp_path / "m.skops").write_bytes(b"old model")
    (tmp_path / "m.json").write_text("old")
    base = ["train", str(tmp_path / "i.parquet"), "--train-size", "8"]
    result = runner.invoke(app, [*base, "-o", str(tmp_path / "m.skops")])
    assert (
        _error(result, 1)
        == f"error: {tmp_path / 'm.skops'}: exists already, not overwriting (use --force)"
    )
    result = runner.invoke(
        app, [*base, "-o", str(tmp_path / "new.skops"), "--metrics", str(tmp_path / "m.json")]
    )
    assert (
        _error(result, 1)
        == f"error: {tmp_path / 'm.json'}: exists already, not overwriting (use --force)"
    )
    assert _listing(tmp_path) == ["i.parquet", "m.json", "m.skops"]
    assert (tmp_path / "m.skops").read_bytes() == b"old model"
    assert (tmp_path / "m.json").read_text() == "old"


# --- inspect on model files ---------------------------------------------------------------------


def test_inspect_model_json_and_text(trained: dict[str, object]) -> None:
    path = Path(str(trained["dir"])) / "model.skops"
    m = trained["metrics"]
    assert isinstance(m, dict)
    result = runner.invoke(app, ["inspect", str(path), "--json"])
    assert result.exit_code == 0, result.stderr
    info = json.loads(result.stdout)
    assert (info["format"], info["kind"]) == ("skops", "model")
    assert info["schema"] == {"name": "deformctl-lift-force-model", "version": 2}
    assert info["features"] == list(FEATURES)
    assert info["seed"] == SEED
    assert info["training_range"] == m["training_range"]
    assert info["metrics"]["model"]["test"] == m["model"]["test"]
    assert info["hyperparameters"]["hidden"] == [2]
    assert info["tool_version"] == m["provenance"]["tool_version"]
    assert info["provenance"]["seed"] == SEED
    text = runner.invoke(app, ["inspect", str(path)])
    assert text.exit_code == 0, text.stderr
    assert "kind: model" in text.stdout
    assert f"seed: {SEED}" in text.stdout
    lo, hi = m["training_range"]["weight_n"]
    assert f"weight_n                 {lo:.6g} .. {hi:.6g}" in text.stdout
    stdin = runner.invoke(app, ["inspect", "-", "--json"], input=path.read_bytes())
    assert stdin.exit_code == 0, stdin.stderr
    assert json.loads(stdin.stdout)["training_range"] == m["training_range"]


def test_inspect_refuses_unexpected_type_and_truncation(
    trained: dict[str, object], tmp_path: Path
) -> None:
    evil = tmp_path / "evil.skops"
    sio.dump(
        {
            "format": MODEL_FORMAT,
            "metadata_json": "{}",
            "model": make_pipeline(FunctionTransformer(func=os.system)),
        },
        evil,
    )
    result = runner.invoke(app, ["inspect", str(evil)])
    msg = _error(result, 65)
    assert msg.startswith(f"error: {evil}: refusing to load: unexpected type(s) in the model file:")
    assert f"{os.system.__module__}.system" in msg
    result = runner.invoke(app, ["inspect", "-"], input=evil.read_bytes())
    assert _error(result, 65).startswith("error: <stdin>: refusing to load: unexpected type(s)")

    good = (Path(str(trained["dir"])) / "model.skops").read_bytes()
    (tmp_path / "cut.skops").write_bytes(good[: len(good) // 2])
    result = runner.invoke(app, ["inspect", str(tmp_path / "cut.skops")])
    assert _error(result, 65) == (
        f"error: {tmp_path / 'cut.skops'}: not a skops model file (truncated or not a zip archive)"
    )
