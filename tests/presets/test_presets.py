"""Simulator presets: the calibrated paper preset, the table preset, their record in artifacts."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from deformctl.artifacts.mcap import decode_provenance, load_mcap
from deformctl.cli import app
from deformctl.errors import UsageError
from deformctl.presets import (
    CALIBRATED_PARAMETERS,
    DEFAULT_PRESET,
    paper_calibration,
    paper_preset,
    sim_preset,
)
from deformctl.repro.calibrate import SEARCH_TOLERANCE, published_points, simulated_lift_force_n

PAPER = Path(__file__).resolve().parents[2] / "datasets" / "paper"
CALIBRATION = Path(__file__).resolve().parents[2] / "datasets" / "calibration" / "paper.json"
runner = CliRunner()


def test_paper_preset_reads_the_checked_in_calibration() -> None:
    record = json.loads(CALIBRATION.read_text())
    assert paper_calibration()["fitted"] == record["fitted"]
    preset = paper_preset()
    assert preset.settings.shear_damping_ratio == record["fitted"]["shear_damping_ratio"]
    assert preset.profile.accel_m_s2 == record["fitted"]["lift_accel_m_s2"]
    for key, (low, high) in CALIBRATED_PARAMETERS.items():
        assert low <= record["fitted"][key] <= high
    assert sim_preset().name == DEFAULT_PRESET == "paper"


def test_calibration_record_meets_the_paper_targets() -> None:
    """The checked-in fit: every point within 14 %, leave-one-out within 20 %, density <= 3 %."""
    record = json.loads(CALIBRATION.read_text())
    assert len(record["points"]) == 13
    assert record["worst_error"] == max(abs(p["error"]) for p in record["points"])
    assert record["worst_error"] <= 0.14
    assert record["leave_one_out"]["worst"] <= 0.20
    assert record["density_check"]["worst_move"] <= 0.03


@pytest.mark.parametrize("label", ["sponge", "T3-9"])
def test_calibration_record_is_what_the_code_simulates(label: str) -> None:
    """The recorded L_f is reproduced by today's simulator (the file is not stale)."""
    record = {p["point"]: p for p in json.loads(CALIBRATION.read_text())["points"]}
    point = next(p for p in published_points() if p.label == label)
    ours = simulated_lift_force_n(point.spec, paper_preset(), SEARCH_TOLERANCE)
    assert ours == pytest.approx(record[label]["lift_force_ours_n"], rel=SEARCH_TOLERANCE)


def test_unknown_preset_is_a_usage_error() -> None:
    with pytest.raises(UsageError, match="unknown sim preset 'mujoco'"):
        sim_preset("mujoco")


def test_override_renames_the_preset() -> None:
    table = sim_preset("table")
    assert table.replace(profile={"accel_m_s2": None}).name == "table"
    assert table.replace(profile={"accel_m_s2": 1.0}).name == "table+overrides"


def _lift(tmp_path: Path, runner_name: str, *args: str) -> tuple[int, str, Path]:
    out = tmp_path / "lift.parquet"
    res = runner.invoke(
        app,
        ["lift", runner_name, str(PAPER / "objects.csv"), "--objects", "A", "-o", str(out), *args],
    )
    return res.exit_code, res.stderr, out


def test_lift_records_the_default_preset_in_row_and_log(tmp_path: Path) -> None:
    log = tmp_path / "lift.mcap"
    code, err, out = _lift(tmp_path, "sim", "--log", str(log))
    assert code == 0, err
    row = pd.read_parquet(out).iloc[0]
    assert row["sim_preset"] == "paper"
    assert row["lift_accel_m_s2"] == pytest.approx(paper_preset().profile.accel_m_s2)
    # the log's and the table's provenance name the preset and hold its full settings
    prov = decode_provenance(load_mcap(log.read_bytes(), log))
    assert prov is not None
    assert prov.settings["sim_preset"] == "paper"
    assert prov.settings["support_release"]["mode"] == "support"
    assert prov.settings["sim_settings"]["integrator"] == "bdf2"
    table_meta = json.loads(pq.read_schema(out).metadata[b"deformctl"])
    assert table_meta["provenance"]["settings"]["sim_preset"] == "paper"


def test_lift_single_option_overrides_and_names_it(tmp_path: Path) -> None:
    code, err, out = _lift(tmp_path, "sim", "--sim-preset", "table", "--lift-accel-m-s2", "1")
    assert code == 0, err
    row = pd.read_parquet(out).iloc[0]
    assert row["sim_preset"] == "table+overrides"
    assert row["lift_accel_m_s2"] == 1.0


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["sim", "--sim-preset", "mujoco"], "unknown sim preset 'mujoco'"),
        (
            ["rig", "--command", "python3 x.py", "--sim-preset", "table"],
            "lift rig: no such option: --sim-preset",
        ),
    ],
)
def test_bad_preset_options_exit_2_with_nothing_written(
    tmp_path: Path, args: list[str], message: str
) -> None:
    code, err, out = _lift(tmp_path, *args)
    assert code == 2
    assert err.startswith("error: ")
    assert err.count("\n") == 1
    assert message in err
    assert not out.exists()


def test_measure_records_the_preset(tmp_path: Path) -> None:
    out = tmp_path / "sq.mcap"
    res = runner.invoke(
        app,
        ["measure", "sim", str(PAPER / "objects.csv"), "--objects", "A", "--squeezes", "1",
         "--sim-preset", "table", "-o", str(out)],
    )  # fmt: skip
    assert res.exit_code == 0, res.stderr
    prov = decode_provenance(load_mcap(out.read_bytes(), out))
    assert prov is not None
    assert prov.settings["sim_preset"] == "table"
