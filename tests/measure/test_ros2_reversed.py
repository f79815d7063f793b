"""A time-reversed ROS 2 bag is flagged ``energy_returned``.

Run backwards, a damped squeeze gives energy back (its force-compression loop runs the wrong way),
which no passive object does. The hostile run's reversed bag (truth λ = 1.5 N·s/cm) read λ = 1.02
with quality ``ok``; it now carries the flag into ``characterize``'s quality, with a warning line.
The same bag forwards, and an undamped one with noise, are not flagged.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_table
from deformctl.cli import app
from deformctl.measure import BagSource, read_recording
from deformctl.measure.ros2_bag import ENERGY_RETURNED_FRAC
from tests._helpers.ros2_bags import LEFT, POSE, write_bag

cli = CliRunner()


def _reverse(t: np.ndarray, values: np.ndarray) -> None:
    values[:] = values[::-1].copy()


def _bag(path: Path, lam: float, reverse: bool, seed: int = 1) -> Path:
    """A one-palm bag; the force at 250 Hz (the loop's sign does not depend on the rate)."""
    edit = _reverse if reverse else None
    write_bag(path, 30.0, lam, seed=seed, force_rate_hz=250.0, wrench_topics=(LEFT,),
              edit_force=edit, edit_pose=edit)  # fmt: skip
    return path


def _flags(path: Path) -> tuple[str, ...]:
    rec = read_recording(path, BagSource(wrench_topics=[LEFT], position_topic=POSE), "A")
    return rec.flags


@pytest.mark.parametrize("seed", [1, 2])
def test_reversed_is_flagged_forwards_is_not(seed: int, tmp_path: Path) -> None:
    assert "energy_returned" in _flags(_bag(tmp_path / "r.mcap", 1.5, True, seed))
    assert "energy_returned" not in _flags(_bag(tmp_path / "f.mcap", 1.5, False, seed))
    assert "energy_returned" not in _flags(_bag(tmp_path / "e.mcap", 0.0, False, seed))
    assert "energy_returned" not in _flags(_bag(tmp_path / "e.mcap", 0.0, True, seed))
    assert 0 < ENERGY_RETURNED_FRAC < 0.02


def test_the_flag_reaches_characterize(tmp_path: Path) -> None:
    bag, log, coef = _bag(tmp_path / "r.mcap", 1.5, True), tmp_path / "log.mcap", tmp_path / "c.pq"
    res = cli.invoke(app, ["measure", "bag", str(bag), "--wrench-topic", LEFT,
                           "--position-topic", POSE, "--object-id", "A", "--weight-n", "1",
                           "-o", str(log)])  # fmt: skip
    assert res.exit_code == 0, res.stderr
    assert "warning:" in res.stderr
    assert "give energy back" in res.stderr
    res = cli.invoke(app, ["characterize", str(log), "-o", str(coef)])
    assert res.exit_code == 0, res.stderr
    assert "energy_returned" in read_table(coef, "coefficients").loc[0, "quality"]
