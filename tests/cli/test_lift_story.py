"""The log of a seeded lift tells each object's story.

``lift --start-model`` stores with each object of its log the prediction, its bound, the attempts
and the outcome, and the attempts a search from F_w would have taken (the refine search replayed
against the L_f found); ``inspect`` prints them. Checked against the truth on the example rig
(a threshold: the replayed count is what ``lift`` from F_w really takes there) and against
``predict`` for the prediction and the bound.
"""

from __future__ import annotations

import io
import sys
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner, Result

from deformctl.artifacts import read_table, write_table
from deformctl.artifacts.mcap import load_mcap
from deformctl.artifacts.mcap.contents import decode_objects
from deformctl.cli import app

ROOT = Path(__file__).resolve().parents[2]
RIG = f"{sys.executable} {ROOT / 'examples' / 'threshold_rig.py'} --extra-n 1.2"
runner = CliRunner()


def _ok(result: Result) -> Result:
    assert result.exit_code == 0, (result.exit_code, result.stderr)
    return result


@pytest.fixture(scope="module")
def seeded(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("story")
    table = pd.DataFrame({
        "object_id": ["A", "C"], "deformability_n_per_cm": [49.2, 30.0],
        "damping_ns_per_cm": [6.5, 0.47], "weight_n": [0.7, 2.9], "size_x_cm": [17.8, 11.4],
        "size_y_cm": [19.1, 11.4], "size_z_cm": [9.2, 9.5], "friction_mu": [0.5, 0.5],
    })  # fmt: skip
    write_table(table, d / "coef.parquet", "coefficients", provenance=None)
    for name, extra in (("seeded", ["--start-model", "grip"]), ("plain", [])):
        out = ["-o", str(d / f"{name}.parquet"), "--log", str(d / f"{name}.mcap")]
        _ok(
            runner.invoke(
                app, ["lift", "rig", str(d / "coef.parquet"), "--command", RIG, *extra, *out]
            )
        )
    return {"dir": d, "coef": d / "coef.parquet"}


def _story(path: Path) -> pd.DataFrame:
    objects = decode_objects(load_mcap(path.read_bytes(), str(path)))
    rows = [{"object_id": o["object_id"], **o["start"]} for o in objects if "start" in o]
    return pd.DataFrame(rows).set_index("object_id") if rows else pd.DataFrame()


def test_the_log_records_prediction_bound_attempts_and_outcome(seeded: dict[str, Path]) -> None:
    story = _story(seeded["dir"] / "seeded.mcap")
    lift = read_table(seeded["dir"] / "seeded.parquet", "lift_results").set_index("object_id")
    pred = _ok(runner.invoke(app, ["predict", "grip", str(seeded["coef"]), "--coverage", "0.9"]))
    predicted = pd.read_csv(io.StringIO(pred.stdout)).set_index("object_id")
    assert list(story.index) == ["A", "C"]
    for oid in story.index:
        s = story.loc[oid]
        assert s["predicted_lift_force_n"] == pytest.approx(
            predicted.loc[oid, "predicted_lift_force_n"], rel=1e-5
        )
        assert s["lift_force_upper_n"] == pytest.approx(
            predicted.loc[oid, "lift_force_upper_n"], rel=1e-5
        )
        assert s["coverage"] == 0.9
        assert s["attempts"] == lift.loc[oid, "attempts"]
        assert s["lift_force_n"] == lift.loc[oid, "lift_force_n"]
        assert bool(s["converged"])
        assert s["attempts_saved"] == s["attempts_from_f_w"] - s["attempts"]
    assert _story(seeded["dir"] / "plain.mcap").empty  # an unseeded log has no story


def test_attempts_from_f_w_are_what_a_search_from_f_w_takes(seeded: dict[str, Path]) -> None:
    story = _story(seeded["dir"] / "seeded.mcap")
    plain = read_table(seeded["dir"] / "plain.parquet", "lift_results").set_index("object_id")
    assert story["attempts_from_f_w"].tolist() == plain.loc[story.index, "attempts"].tolist()


def test_inspect_shows_each_object(seeded: dict[str, Path]) -> None:
    text = _ok(runner.invoke(app, ["inspect", str(seeded["dir"] / "seeded.mcap")])).stdout
    story = _story(seeded["dir"] / "seeded.mcap")
    for oid, s in story.iterrows():
        line = next(ln for ln in text.splitlines() if ln.startswith(f"  {oid}: predicted L_f"))
        assert f"predicted L_f {s['predicted_lift_force_n']:.4g} N" in line
        assert f"bound {s['lift_force_upper_n']:.4g} N (P = 0.9)" in line
        assert f"found L_f {s['lift_force_n']:.4g} N" in line
        assert f"{s['attempts']} attempts (converged)" in line
        assert line.endswith(f"from F_w {s['attempts_from_f_w']}, saved {s['attempts_saved']}")
