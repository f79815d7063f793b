"""The sample recordings of ``datasets/examples/``: made by ``examples/make_sample_recordings.py``,
installed with the package, and measured back to the coefficients they were written with."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from typer.testing import CliRunner

from deformctl.artifacts import read_table
from deformctl.cli import app
from deformctl.resources import dataset_path

REPO = Path(__file__).resolve().parents[2]
runner = CliRunner()
BAG_TOPICS = ["--wrench-topic", "/left/wrench", "--wrench-topic", "/right/wrench"]
CSV_COLUMNS = ["--columns", "time=Time,force=Force,compression=Crosshead"]


def _decoded(bag: Path) -> list[tuple[str, int, int, Any]]:
    """``(topic, log_time, header stamp ns, message)`` of every message of a ROS 2 bag."""
    with bag.open("rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        return [
            (c.topic, m.log_time, msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec, msg)
            for _, c, m, msg in reader.iter_decoded_messages()
        ]


def test_the_script_makes_the_shipped_files(tmp_path: Path) -> None:
    script = REPO / "examples" / "make_sample_recordings.py"
    subprocess.run([sys.executable, str(script), str(tmp_path)], check=True, capture_output=True)
    shipped = dataset_path("examples", "utm_export.csv")
    assert (tmp_path / "utm_export.csv").read_bytes() == shipped.read_bytes()
    made, ours = (
        _decoded(tmp_path / "gripper.mcap"),
        _decoded(dataset_path("examples", "gripper.mcap")),
    )
    assert [m[:3] for m in made] == [m[:3] for m in ours]
    assert [str(m[3]) for m in made] == [str(m[3]) for m in ours]


def test_the_bag_holds_two_palms_a_pose_and_joint_states_on_one_clock() -> None:
    messages = _decoded(dataset_path("examples", "gripper.mcap"))
    topics = {m[0] for m in messages}
    assert topics == {"/left/wrench", "/right/wrench", "/left/palm_pose", "/joint_states"}
    stamps = {t: [m[2] for m in messages if m[0] == t] for t in topics}
    assert all(s == stamps["/joint_states"] for s in stamps.values())
    span_s = (stamps["/joint_states"][-1] - stamps["/joint_states"][0]) / 1e9
    assert span_s == pytest.approx(9.0)  # a few seconds
    assert all(m[1] - m[2] == 3_000_000 for m in messages)  # received 3 ms after the stamp


@pytest.mark.parametrize(
    "position",
    [
        ["--position-topic", "/joint_states", "--joint", "gripper_width", "--position-is", "gap"],
        ["--position-topic", "/left/palm_pose"],
    ],
    ids=["joint_state", "pose"],
)
def test_the_bag_measures_back_to_its_sponge(tmp_path: Path, position: list[str]) -> None:
    bag = dataset_path("examples", "gripper.mcap")
    log, coef = tmp_path / "sponge.mcap", tmp_path / "sponge.parquet"
    res = runner.invoke(app, ["measure", "bag", str(bag), *BAG_TOPICS, *position,
                              "--object-id", "sponge", "--weight-n", "0.6",
                              "-o", str(log)])  # fmt: skip
    assert res.exit_code == 0, res.stderr
    assert "2 squeeze(s) of 'sponge'" in res.stderr
    res = runner.invoke(app, ["characterize", str(log), "-o", str(coef)])
    assert res.exit_code == 0, res.stderr
    row = read_table(coef).iloc[0]
    assert row["deformability_n_per_cm"] == pytest.approx(8.0, rel=0.02)
    assert row["damping_ns_per_cm"] == pytest.approx(1.5, rel=0.03)
    assert row["quality"] == "ok"


def test_the_whole_bag_keeps_its_stamp_range(tmp_path: Path) -> None:
    bag = dataset_path("examples", "gripper.mcap")
    stamps = [m[2] for m in _decoded(bag) if m[0] == "/left/wrench"]
    log = tmp_path / "whole.mcap"
    res = runner.invoke(app, ["measure", "bag", str(bag), *BAG_TOPICS, "--position-topic",
                              "/left/palm_pose", "--no-segment", "--object-id", "sponge",
                              "--weight-n", "0.6", "-o", str(log)])  # fmt: skip
    assert res.exit_code == 0, res.stderr
    with log.open("rb") as fh:
        times = [m.log_time for _, _, m in make_reader(fh).iter_messages()]
    assert (times[0], times[-1]) == (stamps[0], stamps[-1])


def test_the_csv_export_measures_back_to_its_foam(tmp_path: Path) -> None:
    csv = dataset_path("examples", "utm_export.csv")
    assert csv.read_text().splitlines()[:2] == ["Time,Force,Crosshead", "(s),[kN],(mm)"]
    log, coef = tmp_path / "foam.mcap", tmp_path / "foam.parquet"
    res = runner.invoke(app, ["measure", "csv", str(csv), *CSV_COLUMNS, "--object-id", "foam",
                              "--weight-n", "0.7", "-o", str(log)])  # fmt: skip
    assert res.exit_code == 0, res.stderr
    res = runner.invoke(app, ["characterize", str(log), "-o", str(coef)])
    assert res.exit_code == 0, res.stderr
    row = read_table(coef).iloc[0]
    assert row["deformability_n_per_cm"] == pytest.approx(20.0, rel=0.02)
    assert row["damping_ns_per_cm"] == pytest.approx(3.0, rel=0.03)


def test_the_script_refuses_a_file_as_its_folder(tmp_path: Path) -> None:
    script = REPO / "examples" / "make_sample_recordings.py"
    (tmp_path / "taken").write_text("")
    proc = subprocess.run([sys.executable, str(script), str(tmp_path / "taken")],
                          capture_output=True, text=True, check=False)  # fmt: skip
    assert proc.returncode != 0
    assert proc.stderr.strip().splitlines()[-1].startswith("error:")
