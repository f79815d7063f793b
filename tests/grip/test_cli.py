"""``train`` and ``predict`` for the grip model through the CLI: the bound, μ, the window, and
every bad input as one line with its exit code and nothing written."""

from __future__ import annotations

import io
import json
import os
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner, Result

from deformctl.artifacts import read_table, write_catalog, write_table
from deformctl.cli import app
from deformctl.grip.fast import NO_SCORES_MESSAGE
from deformctl.squeeze.rupture import SAFE_FORCE_MARGIN
from tests.grip._synthetic import grip_index

runner = CliRunner()
OBJECT = ["--weight-n", "2.9", "--deformability-n-per-cm", "30", "--damping-ns-per-cm", "0.47"]


def _error(result: Result, code: int) -> str:
    assert result.exit_code == code, (result.exit_code, result.stdout, result.stderr)
    assert result.stderr.startswith("error: "), result.stderr
    assert result.stderr.count("\n") == 1, result.stderr
    return result.stderr.strip()


@pytest.fixture(scope="module")
def setup(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("grip")
    index = grip_index(150, seed=8, noise=0.01)
    write_table(index, d / "index.parquet", "index_table", provenance=None)
    ratio = index["lift_force_n"] / index["f_w_n"]  # kept: an L_f below F_w is refused
    single = index.assign(
        friction_mu=0.5, f_w_n=index["weight_n"], lift_force_n=ratio * index["weight_n"]
    )
    write_table(single, d / "single.parquet", "index_table", provenance=None)
    args = ["--train-size", "80", "--calibration-size", "40", "--seed", "0"]
    result = runner.invoke(
        app,
        ["train", str(d / "index.parquet"), "-o", str(d / "grip.skops"), *args,
         "--note", "population=grip", "--note", "sim_preset=paper",
         "--metrics", str(d / "m.json")],
    )  # fmt: skip
    assert result.exit_code == 0, result.stderr
    d.joinpath("train.out").write_text(result.stdout)
    result = runner.invoke(
        app,
        ["train", str(d / "single.parquet"), "-o", str(d / "paper.skops"), "--train-size", "80"],
    )
    assert result.exit_code == 0, result.stderr
    return {"dir": d, "index": d / "index.parquet", "model": d / "grip.skops",
            "paper": d / "paper.skops", "metrics": d / "m.json"}  # fmt: skip


def test_train_prints_and_records_the_bound_on_its_test_rows(setup: dict[str, Path]) -> None:
    out = setup["dir"].joinpath("train.out").read_text()
    assert "lifting-force model (grip: weight_n, deformability_n_per_cm, damping_ns_per_cm" in out
    assert "80 train / 40 calibration / 30 test" in out
    lines = [line for line in out.splitlines() if line.startswith("upper bound P = ")]
    assert [line.split(":")[0] for line in lines] == ["upper bound P = 0.9", "upper bound P = 0.95"]
    metrics = json.loads(setup["metrics"].read_text())
    assert metrics["notes"] == {"population": "grip", "sim_preset": "paper"}
    for p in ("0.9", "0.95"):
        entry = metrics["conformal"][p]
        assert f"coverage {entry['coverage']:.3f}" in out
        assert f"mean margin (upper / L_f - 1) {entry['mean_margin']:.2%}" in out


def test_predict_one_object_with_its_bound(setup: dict[str, Path]) -> None:
    result = runner.invoke(
        app, ["predict", str(setup["model"]), *OBJECT, "--friction-mu", "0.5", "--coverage", "0.9"]
    )
    assert result.exit_code == 0, result.stderr
    assert result.stderr == ""
    csv = pd.read_csv(io.StringIO(result.stdout))
    assert list(csv.columns) == [
        "weight_n", "deformability_n_per_cm", "damping_ns_per_cm", "friction_mu", "f_w_n",
        "predicted_lift_force_n", "lift_force_upper_n", "coverage", "bound_guaranteed",
        "outside_training_range",
    ]  # fmt: skip
    row = csv.iloc[0]
    assert row["f_w_n"] == pytest.approx(2.9)
    assert row["lift_force_upper_n"] > row["predicted_lift_force_n"] > row["f_w_n"]
    assert bool(row["bound_guaranteed"])
    assert not bool(row["outside_training_range"])
    # μ only through F_w: at μ 1.0 the force halves
    twice = runner.invoke(app, ["predict", str(setup["model"]), *OBJECT, "--friction-mu", "1"])
    half = pd.read_csv(io.StringIO(twice.stdout))["predicted_lift_force_n"][0]
    assert half == pytest.approx(row["predicted_lift_force_n"] / 2, rel=1e-5)


#: μ's one rule, as every command prints it (deformctl.quantities.FRICTION_MU).
MU_RULE = "error: --friction-mu must be a number in [0.01, 3], got "


@pytest.mark.parametrize(
    ("extra", "code", "line"),
    [
        ([], 2, "error: the model needs each object's friction: give --friction-mu MU for one "
                "object, or a friction_mu column (in the table or a --catalog)"),
        # μ's one rule, as every command prints it (deformctl.quantities.FRICTION_MU)
        (["--friction-mu", "0"], 2, MU_RULE + "0"),
        (["--friction-mu", "-0.5"], 2, MU_RULE + "-0.5"),
        (["--friction-mu", "3.5"], 2, MU_RULE + "3.5"),
        (["--friction-mu", "nan"], 2, MU_RULE + "nan"),
        (["--friction-mu", "inf"], 2, MU_RULE + "inf"),
        (["--friction-mu", "0.5", "--coverage", "0"], 2,
         "error: --coverage must be a number in (0, 1), got 0"),
        (["--friction-mu", "0.5", "--coverage", "1"], 2,
         "error: --coverage must be a number in (0, 1), got 1"),
        (["--friction-mu", "0.5", "--coverage", "1.5"], 2,
         "error: --coverage must be a number in (0, 1), got 1.5"),
        (["--friction-mu", "0.5", "--coverage", "nan"], 2,
         "error: --coverage must be a number in (0, 1), got nan"),
    ],
)  # fmt: skip
def test_bad_flags_exit_2_with_one_line_and_write_nothing(
    setup: dict[str, Path], tmp_path: Path, extra: list[str], code: int, line: str
) -> None:
    out = tmp_path / "p.parquet"
    result = runner.invoke(app, ["predict", str(setup["model"]), *OBJECT, *extra, "-o", str(out)])
    assert _error(result, code) == line
    assert os.listdir(tmp_path) == []


def test_nan_in_any_feature_flag(setup: dict[str, Path]) -> None:
    args = [*OBJECT, "--friction-mu", "0.5"]
    args[args.index("--damping-ns-per-cm") + 1] = "inf"
    result = runner.invoke(app, ["predict", str(setup["model"]), *args])
    assert _error(result, 2) == (
        "error: --damping-ns-per-cm must be a number in [0, 10000] N·s/cm, got inf"
    )


def test_a_model_without_scores_asked_for_a_bound(setup: dict[str, Path], tmp_path: Path) -> None:
    out = tmp_path / "p.parquet"
    result = runner.invoke(
        app, ["predict", str(setup["paper"]), *OBJECT, "--coverage", "0.9", "-o", str(out)]
    )
    assert _error(result, 65) == f"error: {setup['paper']}: {NO_SCORES_MESSAGE}"
    assert os.listdir(tmp_path) == []


def test_a_table_without_mu_for_a_mu_aware_model(setup: dict[str, Path], tmp_path: Path) -> None:
    table = read_table(setup["index"], "index_table").drop(columns=["friction_mu"])
    path = tmp_path / "coefficients.parquet"
    write_table(
        table[["object_id", "deformability_n_per_cm", "damping_ns_per_cm"]].assign(
            weight_n=table["weight_n"]
        ),
        path,
        "coefficients",
        provenance=None,
    )
    result = runner.invoke(app, ["predict", str(setup["model"]), str(path)])
    assert _error(result, 2) == (
        "error: the model needs each object's friction: give --friction-mu MU for one object, "
        "or a friction_mu column (in the table or a --catalog)"
    )


def test_bad_mu_in_a_table_exits_65_naming_the_rows(setup: dict[str, Path], tmp_path: Path) -> None:
    table = read_table(setup["index"], "index_table")
    # (μ <= 0 cannot be written: the index table's schema refuses it on both sides)
    for value, line in (
        (12.0, "friction_mu must be a number in [0.01, 3]; it is 12 for P003"),
        (float("nan"), "friction_mu is NaN or not a finite number for P003"),
    ):
        bad = table.copy()
        bad.loc[3, "friction_mu"] = value
        path = tmp_path / "bad.parquet"
        write_table(bad, path, "index_table", provenance=None, force=True)
        out = tmp_path / "p.parquet"
        result = runner.invoke(app, ["predict", str(setup["model"]), str(path), "-o", str(out)])
        assert _error(result, 65) == f"error: {path}: {line}"
        assert not out.exists()


def test_coefficients_with_a_rupture_force_get_the_window(
    setup: dict[str, Path], tmp_path: Path
) -> None:
    table = read_table(setup["index"], "index_table").iloc[:3]
    coefficients = table[["object_id", "deformability_n_per_cm", "damping_ns_per_cm"]].copy()
    # P000 ruptured far above its force, P001 just above its L_f (below its bound), P002 never
    coefficients["rupture_force_n"] = [1000.0, 1.002 * table["lift_force_n"].iloc[1], float("nan")]
    write_table(coefficients, tmp_path / "c.parquet", "coefficients", provenance=None)
    catalog = pd.DataFrame(
        {
            "object_id": table["object_id"], "size_x_cm": 15.0, "size_y_cm": 15.0,
            "size_z_cm": 10.0, "weight_n": table["weight_n"], "friction_mu": table["friction_mu"],
        }
    )  # fmt: skip
    write_catalog(catalog, tmp_path / "objects.csv")
    result = runner.invoke(
        app,
        ["predict", str(setup["model"]), str(tmp_path / "c.parquet"), "--catalog",
         str(tmp_path / "objects.csv"), "--coverage", "0.95"],
    )  # fmt: skip
    assert result.exit_code == 0, result.stderr
    csv = pd.read_csv(io.StringIO(result.stdout))
    # true only with a known safe force above the bound; unknown (empty) without one
    assert csv["window_ok"].tolist()[:2] == [True, False]
    assert np.isnan(csv["window_ok"].iloc[2])
    assert csv["max_safe_force_n"].isna().tolist() == [False, False, True]
    assert csv["max_safe_force_n"].iloc[0] == pytest.approx(1000.0 * (1 - SAFE_FORCE_MARGIN))
    lines = result.stderr.splitlines()
    assert len(lines) == 2
    assert lines[0].startswith("warning: P001: no safe grip: its ")
    assert lines[0].endswith("(window_ok = false)")
    assert lines[1].startswith("warning: P002: no safe force known")


def test_bundled_name_and_model_metadata(setup: dict[str, Path]) -> None:
    with zipfile.ZipFile(setup["model"]) as z:
        schema = json.loads(z.read("schema.json"))
    meta = json.loads(json.loads(schema["content"]["metadata_json"]["content"]))
    assert meta["form"] == "grip"
    assert len(meta["conformal_scores"]) == 40
    assert meta["numpy_model"]["form"] == "grip"
    assert meta["notes"]["sim_preset"] == "paper"


def test_lift_starts_from_the_grip_model_with_the_catalogs_mu(
    setup: dict[str, Path], tmp_path: Path
) -> None:
    """``lift --start-model`` with a μ-aware model: the start is the model's L_f at the catalog's
    μ (threshold rig: lifts from 17 N)."""
    import shlex
    import sys

    from deformctl.grip.fast import Predictor

    table = read_table(setup["index"], "index_table").iloc[:2]
    catalog = pd.DataFrame(
        {
            "object_id": table["object_id"], "size_x_cm": 15.0, "size_y_cm": 15.0,
            "size_z_cm": 10.0, "weight_n": table["weight_n"], "friction_mu": table["friction_mu"],
            "deformability_n_per_cm": table["deformability_n_per_cm"],
            "damping_ns_per_cm": table["damping_ns_per_cm"],
        }
    )  # fmt: skip
    write_catalog(catalog, tmp_path / "objects.csv")
    rig = shlex.join(
        [sys.executable, str(Path(__file__).parents[1] / "rigs" / "threshold_rig.py"), "17"]
    )
    out = tmp_path / "lift.parquet"
    result = runner.invoke(
        app,
        ["lift", "rig", str(tmp_path / "objects.csv"), "--command", rig, "--start-model",
         str(setup["model"]), "-o", str(out)],
    )  # fmt: skip
    assert result.exit_code == 0, result.stderr
    lifted = read_table(out, "lift_results").set_index("object_id")
    assert set(lifted["start_source"]) == {"model"}
    predictor = Predictor.load(setup["model"])
    for oid, row in table.set_index("object_id").iterrows():
        want = predictor.predict(
            row["weight_n"], row["deformability_n_per_cm"], row["damping_ns_per_cm"],
            row["friction_mu"],
        ).lift_force_n  # fmt: skip
        assert lifted.loc[oid, "predicted_lift_force_n"] == pytest.approx(want, rel=1e-12)
