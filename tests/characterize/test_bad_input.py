"""Bad input to ``characterize``: refused or flagged, never an ``ok`` number.

* A constant force, a compression that never grows: refused (exit 65, one line, nothing written).
* A force that falls as the compression grows: ``negative_stiffness`` (exit 65 unless
  ``--allow-flagged``, which writes it flagged).
* A recording shorter than the filter window: refused; with a window that fits it, flagged
  ``few_samples``.
* ``--model`` with an unknown name, ``--at-force-n`` ≤ 0 or not a number, or above the recording's
  peak force: exit 2, one line, nothing written.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_table, write_squeeze_log
from deformctl.cli import app
from deformctl.series import SqueezeSeries

runner = CliRunner()
RATE_HZ = 100.0


def _squeeze(force: np.ndarray, compression_m: np.ndarray, *, seed: int = 0) -> SqueezeSeries:
    rng = np.random.default_rng(seed)
    t = np.arange(force.size) / RATE_HZ
    return SqueezeSeries(
        "obj", 0, t, force + rng.normal(0.0, 0.01, t.size),
        compression_m + rng.normal(0.0, 2e-6, t.size),
    )  # fmt: skip


def _ramp(seconds: float = 4.0) -> np.ndarray:
    """A load–unload triangle to 10 mm (a loading and an unloading speed), m."""
    t = np.arange(round(seconds * RATE_HZ) + 1) / RATE_HZ
    return 0.01 * (1.0 - np.abs(2.0 * t / seconds - 1.0))


def _run(tmp_path: Path, s: SqueezeSeries, *extra: str) -> tuple[int, str, Path]:
    log, out = tmp_path / "log.mcap", tmp_path / "c.parquet"
    if not log.exists():
        write_squeeze_log(log, [{"object_id": "obj", "weight_n": 1.0}], [s], provenance=None)
    res = runner.invoke(app, ["characterize", str(log), "-o", str(out), *extra])
    return res.exit_code, res.stderr, out


def _one_error_line(stderr: str) -> str:
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    assert lines[0].startswith("error: "), stderr
    assert "Traceback" not in stderr
    return lines[0]


@pytest.mark.parametrize("seed", range(5))
def test_constant_force_is_refused(tmp_path: Path, seed: int) -> None:
    d = _ramp()
    code, err, out = _run(tmp_path, _squeeze(np.full(d.size, 5.0), d, seed=seed))
    assert code == 65
    assert "the force does not change" in _one_error_line(err)
    assert not out.exists()


def test_compression_that_never_grows_is_refused(tmp_path: Path) -> None:
    f = 10.0 * _ramp() / 0.01
    code, err, out = _run(tmp_path, _squeeze(f, np.full(f.size, 0.005)))
    assert code == 65
    assert "the compression never grows" in _one_error_line(err)
    assert not out.exists()


def test_force_falling_with_compression_is_negative_stiffness(tmp_path: Path) -> None:
    d = _ramp()
    s = _squeeze(20.0 - 1000.0 * d, d)
    code, err, out = _run(tmp_path, s)
    assert code == 65
    assert "negative_stiffness" in _one_error_line(err)
    assert not out.exists()
    code, err, out = _run(tmp_path, s, "--allow-flagged", "--model", "kv", "--force")
    assert code == 0, err
    (row,) = read_table(out, "coefficients").to_dict("records")
    assert "negative_stiffness" in row["quality"].split(",")
    assert any(ln.startswith("warning: ") and "negative_stiffness" in ln for ln in err.splitlines())


def test_a_recording_shorter_than_the_filter_window_is_refused(tmp_path: Path) -> None:
    d = _ramp(0.3)  # 31 samples; the default window at 100 Hz is 0.43 s (21 samples)
    code, err, out = _run(tmp_path, _squeeze(1000.0 * d, d))
    assert code == 65
    assert "need at least 42 for a 21-sample window" in _one_error_line(err)
    assert not out.exists()
    # a window that fits: a number, flagged few_samples (fewer than 4 windows), never ok
    code, err, out = _run(tmp_path, _squeeze(1000.0 * d, d), "--window-s", "0.1", "--force")
    assert code == 0, err
    (row,) = read_table(out, "coefficients").to_dict("records")
    assert "few_samples" in row["quality"].split(",")


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--model", "maxwell"], "--model"),
        (["--at-force-n", "0"], "--at-force-n"),
        (["--at-force-n", "-2"], "--at-force-n"),
        (["--at-force-n", "nan"], "--at-force-n"),
        (["--at-force-n", "1e4"], "above the peak force"),
    ],
)
def test_bad_options_are_usage_errors(tmp_path: Path, extra: list[str], message: str) -> None:
    d = _ramp()
    code, err, out = _run(tmp_path, _squeeze(1000.0 * d, d), *extra)
    assert code == 2, err
    assert message in _one_error_line(err)
    assert not out.exists()
