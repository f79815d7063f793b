"""``--scene-hz`` of ``measure --sim`` and ``lift --sim``: the scene topics, rates, bad rates."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from deformctl.artifacts.mcap import load_mcap
from deformctl.cli import app

REPO = Path(__file__).resolve().parents[2]
PAPER = str(REPO / "datasets" / "paper" / "objects.csv")
FAST_LIFT = ["--objects", "A", "--alpha-cm", "10", "--dt-s", "0.002", "--lift-hold-s", "0.05",
             "--lift-height-m", "0.01", "--protocol", "paper", "--sim-preset", "table"]  # fmt: skip
FAST_SQUEEZE = ["--objects", "A", "--squeezes", "1", "--ramp-s", "0.05", "--hold-s", "0.05",
                "--dt-s", "0.002", "--alpha-cm", "10"]  # fmt: skip
runner = CliRunner()


def _topics(path: Path) -> dict[str, int]:
    return load_mcap(path.read_bytes(), path).message_counts()


def test_lift_log_has_the_scene_by_default_and_none_at_zero(tmp_path: Path) -> None:
    out = tmp_path / "lift.parquet"
    for hz, log in ((None, "on.mcap"), ("0", "off.mcap")):
        args = ["lift", "sim", PAPER, *FAST_LIFT, "-o", str(out), "--force"]
        args += ["--log", str(tmp_path / log)] + ([] if hz is None else ["--scene-hz", hz])
        result = runner.invoke(app, args)
        assert result.exit_code == 0, result.stderr
    on, off = _topics(tmp_path / "on.mcap"), _topics(tmp_path / "off.mcap")
    assert on["/scene"] == on["/palms"] > 0
    assert "/scene" not in off
    assert "/palms" not in off
    samples = on["/lift/A/attempt_sample"]
    # 30 Hz of 2 ms steps: a frame every 17 steps, plus each attempt's last sample
    attempts = on["/lift/A/attempt_result"]
    assert samples / 17 <= on["/scene"] <= samples / 17 + 2 * attempts
    assert {k: v for k, v in on.items() if k not in ("/scene", "/palms")} == off


def test_measure_log_scene_rate(tmp_path: Path) -> None:
    log = tmp_path / "squeeze.mcap"
    args = ["measure", "sim", PAPER, *FAST_SQUEEZE, "--scene-hz", "100", "-o", str(log)]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.stderr
    counts = _topics(log)
    steps = counts["/squeeze/A"] - 1  # 0.1 s at 2 ms: 50 steps, samples from t = 0
    every = 5  # 100 Hz at 2 ms
    # the start, steps 0, 5, ..., 45, and the last step
    assert counts["/scene"] == 1 + -(-steps // every) + (1 if (steps - 1) % every else 0) == 12


@pytest.mark.parametrize(
    ("value", "text"),
    [
        ("-1", ">= 0"),
        ("501", "above the simulator's step rate 500"),
        ("nan", ">= 0"),
        ("ten", "invalid value for '--scene-hz'"),
    ],
)
@pytest.mark.parametrize("command", ["lift", "measure"])
def test_bad_rates_exit_2_and_write_nothing(
    tmp_path: Path, command: str, value: str, text: str
) -> None:
    out = tmp_path / ("lift.parquet" if command == "lift" else "squeeze.mcap")
    fast = FAST_LIFT if command == "lift" else FAST_SQUEEZE
    args = [command, "sim", PAPER, *fast, "--scene-hz", value, "-o", str(out)]
    if command == "lift":
        args += ["--log", str(tmp_path / "lift.mcap")]
    result = runner.invoke(app, args)
    assert result.exit_code == 2, result.stderr
    err = result.stderr.strip()
    assert err.startswith("error: ")
    assert "\n" not in err
    assert text in err
    assert list(tmp_path.iterdir()) == []


def test_scene_hz_needs_the_simulator(tmp_path: Path) -> None:
    rig = f"python3 {REPO / 'examples' / 'threshold_rig.py'}"
    args = [
        "lift",
        "rig",
        PAPER,
        "--command",
        rig,
        "--scene-hz",
        "10",
        "-o",
        str(tmp_path / "x.parquet"),
    ]
    result = runner.invoke(app, args)
    assert result.exit_code == 2
    assert "lift rig: no such option: --scene-hz" in result.stderr


def test_scene_hz_needs_a_log(tmp_path: Path) -> None:
    out = tmp_path / "x.parquet"
    args = ["lift", "sim", PAPER, *FAST_LIFT, "--scene-hz", "10", "-o", str(out)]
    result = runner.invoke(app, args)
    assert result.exit_code == 2
    assert "--scene-hz needs --log" in result.stderr
    assert list(tmp_path.iterdir()) == []
