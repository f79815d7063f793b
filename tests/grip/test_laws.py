"""The grip model per material law (``train --laws``, ``predict`` of rows that state their law):
a synthetic population whose L_f follows a known law per material (tests/grip/_synthetic.py),
the bound per law on held-out rows, and every bad input of a law as one line or a flag."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner, Result

from deformctl.artifacts import read_table, write_table
from deformctl.cli import app
from deformctl.grip.fast import Predictor
from deformctl.grip.laws import KNOWN_LAWS
from deformctl.predict import predict_objects_with_laws
from tests.grip._synthetic import LAW_COLS, law_index
from tests.grip._synthetic import train_cli as _train

runner = CliRunner()


def _error(result: Result, code: int) -> str:
    assert result.exit_code == code, (result.exit_code, result.stdout, result.stderr)
    assert result.stderr.startswith("error: "), result.stderr
    assert result.stderr.count("\n") == 1, result.stderr
    return result.stderr.strip()


@pytest.fixture(scope="module")
def setup(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("laws")
    mixed = _train(d, law_index(360, seed=3, noise=0.01), "mixed")
    kv_only = law_index(120, seed=4, noise=0.01, laws="kv=1")
    kv_model = _train(d, kv_only, "kvonly")
    old = _train(d, kv_only, "old", laws=False)
    fresh = law_index(600, seed=11, noise=0.01, prefix="T")  # a seed not used in training
    write_table(fresh, d / "fresh.parquet", "index_table", provenance=None)
    return {"dir": d, "mixed": mixed, "kv": kv_model, "old": old, "fresh": d / "fresh.parquet"}


def _predict(model: Path, table: pd.DataFrame, coverage: float | None = 0.9):  # type: ignore[no-untyped-def]
    p = Predictor.load(model)
    inputs = {c: table[c].to_numpy(dtype=object if c == "model" else float)
              for c in table.columns if c not in ("object_id", "lift_force_n", "f_w_n",
                                                   "converged")}  # fmt: skip
    return predict_objects_with_laws(
        p, inputs, coverage=coverage, names=table["object_id"].tolist()
    )


def test_metadata_states_the_mix_and_every_range(setup: dict[str, Path]) -> None:
    meta = Predictor.load(setup["mixed"]).metadata["laws"]
    assert meta["trained_laws"] == list(KNOWN_LAWS)
    assert set(meta["mix"]) == set(KNOWN_LAWS)
    assert abs(sum(m["fraction"] for m in meta["mix"].values()) - 1) < 1e-12
    assert meta["ranges"]["hc"]["stiffness_exponent"][0] >= 1.0
    assert meta["ranges"]["hc"]["stiffness_exponent"][1] <= 3.0
    assert 0.25 <= meta["ranges"]["sls"]["arm_stiffness_ratio"][0] < 1.0
    assert set(meta["ranges"]["sls"]) >= {"arm_stiffness_ratio", "relaxation_time_omega_n"}
    result = runner.invoke(app, ["inspect", str(setup["mixed"])])
    assert result.exit_code == 0, result.stderr
    assert "stiffness_exponent" in result.stdout
    assert "arm_stiffness_ratio" in result.stdout
    assert "material law mix: " in result.stdout
    assert "hc network" in result.stdout
    assert "kv training range" in result.stdout
    assert "sls training range" in result.stdout


def test_kv_rows_are_the_main_network_exactly(setup: dict[str, Path]) -> None:
    fresh = read_table(setup["fresh"])
    kv = fresh[fresh["model"] == "kv"]
    p = Predictor.load(setup["mixed"])
    got = _predict(setup["mixed"], kv).estimates
    plain = p.predict_many(kv["weight_n"], kv["deformability_n_per_cm"],
                           kv["damping_ns_per_cm"], kv["friction_mu"], coverage=0.9)  # fmt: skip
    np.testing.assert_array_equal(got.lift_force_n, plain.lift_force_n)
    np.testing.assert_array_equal(got.lift_force_upper_n, plain.lift_force_upper_n)


def test_per_law_error_and_coverage_on_fresh_objects(setup: dict[str, Path]) -> None:
    """Group-conditional: P = 0.9 coverage holds within each law on ~200 fresh objects."""
    fresh = read_table(setup["fresh"])
    out = _predict(setup["mixed"], fresh)
    est, y = out.estimates, fresh["lift_force_n"].to_numpy()
    for law in KNOWN_LAWS:
        sel = (fresh["model"] == law).to_numpy() & ~est.outside_training_range
        assert sel.sum() > 120
        assert np.all(out.law_used[sel] == law)
        rel = np.abs(est.lift_force_n[sel] - y[sel]) / y[sel]
        assert np.median(rel) < 0.03, (law, np.median(rel))
        covered = np.mean(y[sel] <= est.lift_force_upper_n[sel])
        assert covered >= 0.82, (law, covered)
    # the KV network alone misses the stiffening objects' law: the law networks are the fix
    hc = (fresh["model"] == "hc").to_numpy()
    kv_only = _predict(setup["kv"], fresh[hc]).estimates
    assert np.median(kv_only.lift_force_n / y[hc]) < 0.93


def test_unknown_law_value_exits_65_naming_column_and_laws(setup: dict[str, Path]) -> None:
    fresh = read_table(setup["fresh"]).head(3).assign(model=["kv", "zener9", "hc"])
    path = setup["dir"] / "bad-law.parquet"
    write_table(fresh, path, "index_table", provenance=None)
    out = setup["dir"] / "bad.parquet"
    line = _error(runner.invoke(app, ["predict", str(setup["mixed"]), str(path), "-o", str(out)]),
                  65)  # fmt: skip
    assert "'model'" in line
    assert "'zener9'" in line
    assert "kv, hc, sls" in line
    assert "T" in line
    assert not out.exists()


def test_law_parameter_outside_range_warns_and_drops_the_guarantee(setup: dict[str, Path]) -> None:
    fresh = read_table(setup["fresh"])
    row = fresh[fresh["model"] == "hc"].head(1).assign(hc_exponent=3.4)
    path = setup["dir"] / "steep.parquet"
    write_table(row, path, "index_table", provenance=None)
    result = runner.invoke(app, ["predict", str(setup["mixed"]), str(path), "--coverage", "0.9"])
    assert result.exit_code == 0, result.stderr
    assert "stiffness_exponent = 3.4 not in [1" in result.stderr
    assert "outside the hc training range" in result.stderr
    line = result.stdout.splitlines()[1]
    assert ",False," in line
    assert line.count("hc") >= 1
    sls = fresh[fresh["model"] == "sls"].head(1)
    sls = sls.assign(sls_arm_stiffness_n_per_cm=sls["sls_stiffness_n_per_cm"] * 20)
    est = _predict(setup["mixed"], sls).estimates
    assert not est.bound_guaranteed[0]
    assert np.isfinite(est.lift_force_n[0])
    assert any("arm_stiffness_ratio = 20 not in [0.2" in w for w in est.warnings)


def test_other_law_row_on_a_one_law_model_warns(setup: dict[str, Path]) -> None:
    fresh = read_table(setup["fresh"])
    rows = fresh[fresh["model"] != "kv"].head(2)
    out = _predict(setup["kv"], rows)
    assert not out.estimates.bound_guaranteed.any()
    assert np.isfinite(out.estimates.lift_force_n).all()
    assert sum("trained on kv objects only" in w for w in out.estimates.warnings) == 2


def test_model_without_law_mix_keeps_kv_and_refuses_other_laws(setup: dict[str, Path]) -> None:
    fresh = read_table(setup["fresh"])
    kv = fresh[fresh["model"] == "kv"].head(3)
    est = _predict(setup["old"], kv).estimates
    assert est.bound_guaranteed.all()
    path = setup["dir"] / "hc-rows.parquet"
    write_table(fresh[fresh["model"] == "hc"].head(2), path, "index_table", provenance=None)
    line = _error(runner.invoke(app, ["predict", str(setup["old"]), str(path)]), 65)
    assert "no law mix" in line
    assert "hc" in line


def test_unknown_law_predicts_the_most_cautious_and_flags_it(setup: dict[str, Path]) -> None:
    fresh = read_table(setup["fresh"])
    row = fresh[fresh["model"] == "hc"].head(1)
    known = _predict(setup["mixed"], row).estimates
    as_kv = _predict(setup["mixed"], row.assign(model="kv")).estimates
    blank = _predict(setup["mixed"], row.assign(model=None))
    assert blank.law_assumed[0]
    assert not blank.estimates.bound_guaranteed[0]
    top = max(known.lift_force_upper_n[0], as_kv.lift_force_upper_n[0])
    assert blank.estimates.lift_force_upper_n[0] == pytest.approx(top, rel=1e-12)
    assert any("law is unknown" in w and "law_assumed = true" in w
               for w in blank.estimates.warnings)  # fmt: skip


def test_unknown_sls_damping_takes_the_most_cautious_parameters(setup: dict[str, Path]) -> None:
    fresh = read_table(setup["fresh"])
    row = fresh[fresh["model"] == "sls"].head(1)
    nan = row.assign(sls_arm_stiffness_n_per_cm=np.nan, sls_relaxation_time_s=np.nan)
    out = _predict(setup["mixed"], nan)
    assert out.parameters_assumed[0]
    assert not out.estimates.bound_guaranteed[0]
    assert out.estimates.lift_force_n[0] >= _predict(setup["mixed"], row).estimates.lift_force_n[0]


def test_training_drops_unidentified_law_rows_and_refuses_unknown_laws(tmp_path: Path) -> None:
    from deformctl.errors import InputDataError
    from deformctl.model import TrainOptions
    from deformctl.train import train_with_laws

    index = law_index(200, seed=5, noise=0.01)
    sls = index.index[index["model"] == "sls"][:3]
    index.loc[sls, "sls_arm_stiffness_n_per_cm"] = np.nan
    options = TrainOptions(train_size=20, calibration_size=20, seed=0)
    _, section, _ = train_with_laws(index.drop(columns=LAW_COLS), index, options)
    dropped = section["models"]["sls"]["dropped_unidentified"]
    assert dropped == sorted(index.loc[sls, "object_id"].tolist())
    used = {i for ids in section["models"]["sls"]["split"].values() for i in ids}
    assert not set(dropped) & used
    bad = index.assign(model=np.where(index["model"] == "hc", "zener9", index["model"]))
    with pytest.raises(InputDataError, match="'model' is 'zener9'"):
        train_with_laws(index.drop(columns=LAW_COLS), bad, options)


def test_the_recognised_laws_are_every_law_characterize_fits() -> None:
    from deformctl.characterize.laws import PARAMETERS
    from deformctl.grip.laws import recognised_laws

    assert sorted(recognised_laws()) == sorted(PARAMETERS)


def test_an_hc_row_without_its_size_is_predicted_at_the_most_cautious_shape(
    setup: dict[str, Path],
) -> None:
    fresh = read_table(setup["fresh"])
    rows = fresh[fresh["model"] == "hc"].head(3)
    known = _predict(setup["mixed"], rows)
    assert known.estimates.bound_guaranteed.all()
    assert not known.shape_assumed.any()
    blind = _predict(setup["mixed"], rows.drop(columns=["size_x_cm", "size_y_cm", "size_z_cm"]))
    assert blind.shape_assumed.all()
    assert not blind.parameters_assumed.any()
    assert not blind.estimates.bound_guaranteed.any()
    # the largest L_f over the training shapes (a grid): not below the row's own shape's
    assert np.all(blind.estimates.lift_force_n >= 0.99 * known.estimates.lift_force_n)
    lines = [w for w in blind.estimates.warnings if "shape_assumed = true" in w]
    assert len(lines) == 3
    assert all("size_x_cm" in w for w in lines)
    # the CLI states the flag as a column
    path = setup["dir"] / "no-size.parquet"
    write_table(rows.drop(columns=["size_x_cm", "size_y_cm", "size_z_cm"]), path, "index_table",
                provenance=None)  # fmt: skip
    result = runner.invoke(app, ["predict", str(setup["mixed"]), str(path), "--coverage", "0.9"])
    assert result.exit_code == 0, result.stderr
    header = result.stdout.splitlines()[0].split(",")
    assert "shape_assumed" in header
    col = header.index("shape_assumed")
    assert [r.split(",")[col] for r in result.stdout.splitlines()[1:4]] == ["True"] * 3


def test_an_hc_network_from_before_the_shape_inputs_is_still_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from deformctl.grip import laws

    four = laws.LAW_FEATURES["hc"][:4]
    assert four in laws.EARLIER_LAW_FEATURES["hc"]
    with monkeypatch.context() as m:
        m.setitem(laws.LAW_FEATURES, "hc", four)
        old = _train(tmp_path, law_index(330, seed=6, noise=0.01), "fourinputs")
    entry = Predictor.load(old).metadata["laws"]["models"]["hc"]
    assert tuple(entry["features"]) == four
    fresh = law_index(60, seed=12, noise=0.0, prefix="T")
    hc = fresh[fresh["model"] == "hc"].drop(columns=["size_x_cm", "size_y_cm", "size_z_cm"])
    out = _predict(old, hc)
    assert not out.shape_assumed.any()  # the old network needs no size
    assert np.all(np.isfinite(out.estimates.lift_force_n))
    rel = np.abs(out.estimates.lift_force_n / hc["lift_force_n"].to_numpy() - 1)
    assert np.median(rel) < 0.05


def test_law_train_size_caps_each_law_and_leaves_kelvin_voigt_alone() -> None:
    from deformctl.errors import InputDataError, UsageError
    from deformctl.grip.lawtrain import law_lines
    from deformctl.model import TrainOptions
    from deformctl.train import train_with_laws

    index = law_index(240, seed=5, noise=0.01)
    counts = index["model"].value_counts()
    base = TrainOptions(train_size=30, calibration_size=20, seed=0)
    capped = TrainOptions(train_size=30, calibration_size=20, seed=0, law_train_size=1000)
    kv_a, plain, _ = train_with_laws(index.drop(columns=LAW_COLS), index, base)
    kv_b, section, report = train_with_laws(index.drop(columns=LAW_COLS), index, capped)
    lines = law_lines(report)
    assert len(lines) == 2
    assert all("0 test rows (tested on fresh objects" in line for line in lines)
    for law in ("hc", "sls"):
        assert plain["models"][law]["n_train"] == 30
        assert section["models"][law]["n_train"] == counts[law] - 20
        assert section["models"][law]["n_test"] == 0
    assert kv_a.training_range == kv_b.training_range
    with pytest.raises(UsageError, match="--law-train-size must be an integer >= 2, got 1"):
        TrainOptions(law_train_size=1)
    no_size = index.drop(columns=["size_x_cm"])
    with pytest.raises(InputDataError, match="hc rows with every parameter known"):
        train_with_laws(index.drop(columns=LAW_COLS), no_size, base)
