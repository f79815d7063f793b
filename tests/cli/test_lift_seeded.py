"""``deformctl lift --start-model / --start-table``: on a scripted rig, and one small --sim run.

The rig is ``tests/rigs/threshold_rig.py`` (lifts iff the grip force >= 17 N), so every object's
true L_f is max(17 N, F_w) and refine's answer on the same rig is known in closed form.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

from deformctl.artifacts import Provenance, read_table, validate_message, write_table
from deformctl.artifacts.model import save_model
from deformctl.lift import DEFAULT_START_MARGIN, DEFAULT_TOLERANCE_REL, find_min_lift_force
from deformctl.model import TrainOptions, make_model
from deformctl.train import train_model
from tests._helpers.lift import (
    HEADER,
    THRESHOLD_N,
    ThresholdRunner,
    listing,
    one_line_error,
    rig,
    run,
)

TOL = DEFAULT_TOLERANCE_REL
PAPER = Path(__file__).resolve().parents[2] / "datasets" / "paper"
# W in [8, 20] N, mu = 0.5 (F_w = W): the model is trained on that range; anvil is outside.
CATALOG = HEADER + "sponge,8,5,4,10,0.5\nbrick,6,6,6,16,0.5\nanvil,5,5,5,40,0.5\n"
COEFFICIENTS = {"sponge": (30.0, 2.0), "brick": (40.0, 5.0), "anvil": (35.0, 3.0)}
REQUEST_KEYS = {
    *("object_id", "attempt_index", "grip_force_n", "weight_n", "friction_mu", "size_cm"),
    "max_force_n",  # the force ceiling
}


def _index_table(n: int = 45, seed: int = 0) -> pd.DataFrame:
    """Objects W 8-20 N, mu 0.5, whose L_f on the threshold rig is max(17 N, F_w = W)."""
    rng = np.random.default_rng(seed)
    w = rng.uniform(8.0, 20.0, n)
    return pd.DataFrame(
        {
            "object_id": [f"t{i:02d}" for i in range(n)],
            "weight_n": w,
            "deformability_n_per_cm": rng.uniform(20.0, 50.0, n),
            "damping_ns_per_cm": rng.uniform(0.0, 10.0, n),
            "lift_force_n": np.maximum(THRESHOLD_N, w),
            "friction_mu": 0.5,
            "f_w_n": w,
            "converged": True,
        }
    )


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("seed")
    index = _index_table()
    paths = {"index": d / "index.parquet", "model": d / "model.skops",
             "coefficients": d / "coefficients.parquet", "other": d / "other.skops"}  # fmt: skip
    write_table(index, paths["index"], "index_table", provenance=None)
    result = train_model(index, TrainOptions(hidden=(4,), train_size=40, restarts=2))
    save_model(paths["model"], result.model, metadata=result.metrics)
    coefficients = pd.DataFrame(
        {
            "object_id": list(COEFFICIENTS),
            "deformability_n_per_cm": [v[0] for v in COEFFICIENTS.values()],
            "damping_ns_per_cm": [v[1] for v in COEFFICIENTS.values()],
        }
    )
    write_table(coefficients, paths["coefficients"], "coefficients", provenance=None)
    # a model for another feature set: (W, D) only
    two = make_model().fit(index[["weight_n", "deformability_n_per_cm"]], index["lift_force_n"])
    save_model(paths["other"], two, metadata={"features": ["weight_n", "deformability_n_per_cm"]})
    return paths


@pytest.fixture
def catalog(tmp_path: Path) -> Path:
    path = tmp_path / "objects.csv"
    path.write_text(CATALOG, encoding="utf-8")
    return path


def _refine(weight_n: float) -> float:
    r = find_min_lift_force(ThresholdRunner(THRESHOLD_N), weight_n=weight_n, friction_mu=0.5)
    return r.lift_force_n


def test_start_model_on_a_rig(catalog: Path, tmp_path: Path, files: dict[str, Path]) -> None:
    out, log, requests = tmp_path / "lift.parquet", tmp_path / "lift.mcap", tmp_path / "req.jsonl"
    result = run("rig", catalog, "--command", rig("threshold_rig.py", THRESHOLD_N, requests),
                 "--start-model", files["model"], "--coefficients", files["coefficients"],
                 "-o", out, "--log", log)  # fmt: skip
    assert result.exit_code == 0, result.stderr
    # anvil (W = 40 N) is outside the training range: one warning line, then refine from F_w
    lines = result.stderr.splitlines()
    assert lines[:1] == [
        "warning: object 'anvil': outside the model's training range: weight_n = 40 not in "
        f"[{_range('weight_n', files)}]; starting at F_w (refine)"
    ]
    # the summary line counts the flagged start (and stays at 0 flagged in the other tests)
    assert len(lines) == 2
    assert lines[1].startswith("lift: 3 object(s) done, 1 flagged, 0 failed in ")
    t = read_table(out, "lift_results").set_index("object_id")
    assert list(t["protocol"]) == ["seeded", "seeded", "refine"]
    assert list(t["start_in_training_range"]) == [True, True, False]
    assert set(t["start_source"]) == {"model"}
    for oid, w in (("sponge", 10.0), ("brick", 16.0)):
        row = t.loc[oid]
        assert row.start_force_n == pytest.approx(
            max(w, row.predicted_lift_force_n * DEFAULT_START_MARGIN)
        )
        assert abs(row.lift_force_n - _refine(w)) <= TOL * _refine(w)  # the same answer
        assert row.bracket_low_n < THRESHOLD_N <= row.bracket_high_n == row.lift_force_n
        assert row.attempts <= 6  # refine: 8 on sponge (4 ramp + 4 bisections)
    assert t.loc["anvil", "start_force_n"] == t.loc["anvil", "f_w_n"] == 40.0
    assert (t.loc["anvil", "attempts"], t.loc["anvil", "lift_force_n"]) == (1, 40.0)
    # the rig protocol is unchanged: the rig sees grip forces, never the prediction
    sent = [json.loads(line) for line in requests.read_text().splitlines()]
    assert len(sent) == t["attempts"].sum()
    for request in sent:
        validate_message("rig_request", request)
        assert set(request) == REQUEST_KEYS
    first = {r["object_id"]: r["grip_force_n"] for r in sent if r["attempt_index"] == 0}
    assert first == pytest.approx(t["start_force_n"].to_dict())
    # the provenance names the seed and hashes its files
    info = json.loads(run_inspect(out))
    start = info["provenance"]["settings"]["start"]
    assert (start["source"], start["margin"]) == ("model", DEFAULT_START_MARGIN)
    assert str(files["model"]) in info["provenance"]["inputs"]


def run_inspect(path: Path) -> str:
    from typer.testing import CliRunner

    from deformctl.cli import app

    return str(CliRunner().invoke(app, ["inspect", str(path), "--json"]).stdout)


def _range(feature: str, files: dict[str, Path]) -> str:
    from deformctl.artifacts.model import load_model

    model, _ = load_model(files["model"])
    j = ["weight_n", "deformability_n_per_cm", "damping_ns_per_cm"].index(feature)
    return f"{model.feature_min_[j]:g}, {model.feature_max_[j]:g}"


def test_start_table_from_catalog_columns(tmp_path: Path, files: dict[str, Path]) -> None:
    # D and lambda kept in the catalog itself; the nearest entry's L_f/F_w times F_w
    cat = tmp_path / "objects.csv"
    cat.write_text(
        HEADER.strip() + ",deformability_n_per_cm,damping_ns_per_cm\n"
        "sponge,8,5,4,10,0.5,30,2\nbrick,6,6,6,16,0.5,40,5\n",
        encoding="utf-8",
    )
    out = tmp_path / "lift.parquet"
    result = run("rig", cat, "--command", rig("threshold_rig.py", THRESHOLD_N), "--start-table",
                 files["index"], "--start-interpolate", 3, "--start-margin", 1.01,
                 "-o", out)  # fmt: skip
    assert result.exit_code == 0, result.stderr
    assert result.stderr.startswith("lift: 2 object(s) done, 0 flagged, 0 failed in ")
    assert len(result.stderr.splitlines()) == 1
    t = read_table(out, "lift_results").set_index("object_id")
    assert set(t["protocol"]) == {"seeded"}
    assert set(t["start_source"]) == {"table"}
    for oid, w in (("sponge", 10.0), ("brick", 16.0)):
        assert abs(t.loc[oid, "lift_force_n"] - _refine(w)) <= TOL * _refine(w)
        assert t.loc[oid, "start_force_n"] == pytest.approx(
            max(w, 1.01 * t.loc[oid, "predicted_lift_force_n"])
        )


def test_a_model_for_another_feature_set_is_refused(
    catalog: Path, tmp_path: Path, files: dict[str, Path]
) -> None:
    out = tmp_path / "lift.parquet"
    result = run("rig", catalog, "--command", rig("threshold_rig.py", THRESHOLD_N), "--start-model",
                 files["other"], "--coefficients", files["coefficients"], "-o", out)  # fmt: skip
    assert result.exit_code == 65
    # the model file's structure check (deformctl.train) refuses it on loading
    assert one_line_error(result) == (
        f"error: {files['other']}: not a usable lifting-force model: the model takes 2 features, "
        "expected 3"
    )
    assert listing(tmp_path) == ["objects.csv"]


@pytest.mark.parametrize(
    ("options", "code", "message"),
    [
        (["--start-model", "m.skops", "--start-table", "i.parquet"], 2,
         "error: give --start-model or --start-table, not both"),
        (["--start-margin", "1.1"], 2, "error: --start-margin needs --start-model or"),
        (["--coefficients", "c.parquet"], 2, "error: --coefficients needs --start-model or"),
        (["--start-interpolate", "2"], 2, "error: --start-interpolate needs --start-table"),
        (["--start-model", "MODEL", "--start-margin", "0.9"], 2,
         "error: --start-margin must be a finite number >= 1, got 0.9"),
        (["--start-model", "MODEL", "--protocol", "paper"], 2,
         "error: --start-model bisects to --tolerance as refine does; drop --protocol paper"),
        (["--start-table", "INDEX", "--start-interpolate", "0"], 2,
         "error: --start-interpolate must be an integer >= 1, got 0"),
        (["--start-model", "nope.skops"], 66, "error: nope.skops: model file not found"),
        (["--start-model", "MODEL"], 65,
         "error: {catalog}: object 'sponge': no D and λ to predict its start from (the catalog "
         "has no deformability_n_per_cm / damping_ns_per_cm); pass --coefficients"),
        (["--start-model", "MODEL", "--coefficients", "INDEX"], 65, "error: {index}: "),
    ],
)  # fmt: skip
def test_bad_start_options(
    catalog: Path,
    tmp_path: Path,
    files: dict[str, Path],
    options: list[str],
    code: int,
    message: str,
) -> None:
    subst = {"MODEL": files["model"], "INDEX": files["index"]}
    args = [subst.get(o, o) for o in options]
    requests = tmp_path / "req.jsonl"
    result = run("rig", catalog, "--command", rig("threshold_rig.py", THRESHOLD_N, requests), "-o",
                 tmp_path / "lift.parquet", *args)  # fmt: skip
    assert result.exit_code == code, result.stderr
    assert one_line_error(result).startswith(message.format(catalog=catalog, index=files["index"]))
    assert listing(tmp_path) == ["objects.csv"]  # nothing written, the rig never ran


def test_seeded_sim_run_agrees_with_refine_in_fewer_attempts(tmp_path: Path) -> None:
    # Object A of Table I in the simulator: refine, an index table of that one answer, seeded.
    cat = PAPER / "objects.csv"
    refine, seeded = tmp_path / "refine.parquet", tmp_path / "seeded.parquet"
    result = run("sim", cat, "--objects", "A", "-o", refine)
    assert result.exit_code == 0, result.stderr
    ref = read_table(refine, "lift_results").iloc[0]
    obj = pd.read_csv(cat).set_index("object_id").loc["A"]
    coefficients = pd.DataFrame(
        {
            "object_id": ["A"],
            "deformability_n_per_cm": [obj.material_stiffness_n_per_cm],
            "damping_ns_per_cm": [obj.material_damping_ns_per_cm],
        }
    )
    write_table(coefficients, tmp_path / "c.parquet", "coefficients",
                provenance=Provenance.from_invocation([]))  # fmt: skip
    assert run_table(tmp_path / "c.parquet", refine, tmp_path / "index.parquet") == 0
    result = run("sim", cat, "--objects", "A", "--start-table", tmp_path / "index.parquet",
                 "-o", seeded)  # fmt: skip
    assert result.exit_code == 0, result.stderr
    row = read_table(seeded, "lift_results").iloc[0]
    assert (row.protocol, row.start_source, row.sim_preset) == ("seeded", "table", ref.sim_preset)
    assert row.predicted_lift_force_n == pytest.approx(ref.lift_force_n)
    assert abs(row.lift_force_n - ref.lift_force_n) <= TOL * ref.lift_force_n
    assert row.attempts <= 3 < ref.attempts
    assert math.isfinite(row.start_force_n)


def run_table(coefficients: Path, lift: Path, out: Path) -> Any:
    from typer.testing import CliRunner

    from deformctl.cli import app

    result = CliRunner().invoke(app, ["table", str(coefficients), str(lift), "-o", str(out)])
    return result.exit_code
