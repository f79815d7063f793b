"""A recording's defects are reported and flagged, never fitted over silently.

Each defect is made on a known Kelvin–Voigt squeeze: a 6 s logging gap, a force quantised to
0.1 N on a 2 N peak, repeated timestamps, a force that lags the position by 0.17 s. Each flag
fires on its defect with the numbers that make it, is silent on the clean squeeze, and reaches
``characterize``'s quality. The lag is estimated within a sample and ``--lag-s auto`` removes the
negative damping it causes; a lag given with ``--lag-s SECONDS`` keeps λ, an estimated one does not.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.artifacts.mcap import read_squeeze_log
from deformctl.characterize.objectfit import ObjectFit, fit_object
from deformctl.cli import app
from deformctl.measure import CsvOptions, read_recording
from deformctl.measure.defects import (
    coarse_force,
    estimate_lag,
    force_resolution,
    logging_gaps,
    merge_duplicate_times,
)
from deformctl.squeeze.window import default_window_s

from ._exports import Squeeze, kv_squeeze, write_export

runner = CliRunner()


def _characterize(csv: Path, *extra: str) -> tuple[pd.Series, str]:
    log, table = csv.with_suffix(".mcap"), csv.with_suffix(".parquet")
    res = runner.invoke(
        app, ["measure", "csv", str(csv), "--weight-n", "1", "-o", str(log), *extra]
    )
    assert res.exit_code == 0, res.stderr
    res2 = runner.invoke(
        app, ["characterize", str(log), "-o", str(table), "--model", "kv", "--force"]
    )
    assert res2.exit_code == 0, res2.stderr
    return pd.read_parquet(table).iloc[0], res.stderr + res2.stderr


def test_logging_gap_is_flagged_with_its_length_and_time(tmp_path: Path) -> None:
    s = kv_squeeze(duration_s=16.0)
    keep = (s.t <= 3.0) | (s.t >= 9.0)
    gap = Squeeze(s.t[keep], s.f[keep], s.d[keep])
    found = logging_gaps(gap.t)
    assert found is not None
    assert found.text == (
        "logging_gap: no sample for 6 s from 3 s (600× the median interval 0.01 s)"
    )
    assert logging_gaps(s.t) is None
    row, err = _characterize(write_export(tmp_path / "gap.csv", gap))
    assert "logging_gap" in row["quality"].split(",")
    assert f"warning: {tmp_path / 'gap.csv'}: object 'gap': logging_gap: no sample for 6 s" in err
    clean, _ = _characterize(write_export(tmp_path / "clean.csv", s))
    assert "logging_gap" not in clean["quality"]


def test_coarse_force_is_flagged(tmp_path: Path) -> None:
    """0.1 N steps on a 2 N peak (a kN column with 4 decimals, as one real export set has)."""
    s = kv_squeeze(peak_n=2.0, force_noise_n=0.005)
    path = write_export(
        tmp_path / "utm.csv", s, names=("Time (s)", "Force (kN)", "Compression (mm)"),
        units=("s", "kN", "mm"), digits=4,
    )  # fmt: skip
    rec = read_recording(path, CsvOptions(), "x")
    assert rec.flags == ("coarse_force",)
    assert rec.defects[0]["force_resolution_n"] == pytest.approx(0.1, rel=1e-6)
    text = rec.defects[0]["text"]
    assert text.startswith("coarse_force: the force moves in steps of 0.1 N, 5.0")
    assert text.endswith("% of its 2 N peak (20 levels; more than 2 %)")
    fine = write_export(tmp_path / "fine.csv", s, digits=3)  # 1 mN steps: 0.05 % of the peak
    assert read_recording(fine, CsvOptions(), "x").flags == ()
    assert force_resolution(np.round(s.f, 3)) == pytest.approx(0.001, rel=1e-6)
    assert coarse_force(np.zeros(10)) is None
    row, _ = _characterize(path)
    assert "coarse_force" in row["quality"].split(",")


def test_repeated_timestamps_are_merged_and_reported(tmp_path: Path) -> None:
    s = kv_squeeze()
    idx = np.sort(np.concatenate([np.arange(s.t.size), np.arange(0, s.t.size, 10)]))
    dup = Squeeze(s.t[idx], s.f[idx], s.d[idx])
    t, (f, d), merged = merge_duplicate_times(dup.t, dup.f, dup.d)
    np.testing.assert_allclose(d, s.d)
    assert merged == len(range(0, s.t.size, 10))
    np.testing.assert_array_equal(t, s.t)
    np.testing.assert_allclose(f, s.f)
    rec = read_recording(write_export(tmp_path / "dup.csv", dup), CsvOptions(), "x")
    assert rec.details["merged_timestamps"] == 81
    assert rec.warnings == (
        "81 sample(s) repeat the timestamp of the one before: merged (averaged)",
    )
    assert rec.squeezes[0].time_s.size == s.t.size


def _lagged(tau_s: float, d_n_per_cm: float = 20.0, lam: float = 0.0) -> Squeeze:
    """A force reading delayed by ``tau_s`` behind the position (sensor latency), 100 Hz."""
    s = kv_squeeze(d_n_per_cm, lam, force_noise_n=0.02, position_noise_m=1e-6)
    return Squeeze(s.t, np.interp(s.t - tau_s, s.t, s.f), s.d)


@pytest.mark.parametrize(
    ("tau", "d", "lam", "expected"),
    [(0.17, 20.0, 0.0, 0.17), (0.05, 20.0, 0.0, 0.05), (0.3, 5.0, 0.0, 0.3),
     (0.0, 20.0, 3.0, -0.15), (0.17, 20.0, 1.0, 0.12)],
    ids=["kiwi", "small", "soft", "damped_no_lag", "damped_and_lag"],
)  # fmt: skip
def test_lag_estimate_is_the_delay_minus_lambda_over_d(
    tau: float, d: float, lam: float, expected: float
) -> None:
    """Cross-correlating the rates finds τ − λ/D (module docstring): within a sample (0.01 s)."""
    s = _lagged(tau, d, lam)
    est = estimate_lag(s.t, s.f, s.d)
    assert est.lag_s == pytest.approx(expected, abs=0.01)
    assert est.correlation > 0.98


def test_constant_rate_lag_is_not_identifiable() -> None:
    t = np.arange(0.0, 120.0, 0.1)
    d = 1e-4 * t / 6.0  # 10 mm/min
    f = 2e4 * d + 1e6 * d**2
    est = estimate_lag(t, f, d)
    assert est.lag_s is None
    assert est.reason == "the compression rate is nearly constant on the loading ramp"
    slow = np.arange(0.0, 2000.0, 0.01)  # one haversine over 2000 s: no lag, none found
    f = 5.0 * (1.0 - np.cos(2.0 * np.pi * slow / 2000.0))
    est = estimate_lag(slow, np.round(f, 5), np.round(f / 2000.0, 8))
    assert est.lag_s is None
    assert est.reason.startswith("the rates change too slowly to be aligned within ±")


def test_force_lag_flag_and_lag_auto_remove_the_negative_damping(tmp_path: Path) -> None:
    """0.17 s of latency on D = 20 N/cm, λ = 0: an unshifted fit would give λ ≈ −3.4 N·s/cm;
    the bounded fit holds it at 0 and says so. The log records the lag ``measure`` took out and
    where it came from. Given (``--lag-s 0.17``, the rig's latency): no lag is fitted after it
    and λ ≈ 0 is ``ok``. Estimated (``--lag-s auto``): D is right, λ is withheld, because the
    estimate is the latency less λ/D: the same latency on λ = 1 N·s/cm is shifted by 0.12 s and
    then reads as λ ≈ 0 just as well (below), so no λ after the estimate can be ``ok``."""
    path = write_export(tmp_path / "kiwi.csv", _lagged(0.17))
    row, err = _characterize(path)
    assert "force_lag" in row["quality"].split(",")
    assert "at_bound" in row["quality"].split(",")
    assert row["damping_ns_per_cm"] == 0.0
    assert re.search(r"object 'kiwi': force_lag: the force lags the position by 0\.1[67]\d* s", err)
    assert math.isnan(row["force_lag_s"])
    assert row["force_lag_source"] == ""
    shifted, err = _characterize(path, "--lag-s", "auto", "--force")
    assert shifted["quality"] == "damping_unidentifiable", err
    assert shifted["deformability_n_per_cm"] == pytest.approx(20.0, rel=0.02)
    assert math.isnan(shifted["damping_ns_per_cm"])
    assert re.search(r"force shifted 0\.1[67]\d* s earlier \(--lag-s auto\)", err)
    assert "the force was shifted by the lag measure --lag-s auto estimated, 0.169 s" in err
    assert shifted["force_lag_source"] == "auto"
    assert shifted["force_lag_s"] == pytest.approx(0.17, abs=0.01)
    (obj,) = read_squeeze_log(path.with_suffix(".mcap"))[0]
    assert (obj["force_lag_source"], obj["force_lag_s"]) == ("auto", pytest.approx(0.17, abs=0.01))
    fixed, err = _characterize(path, "--lag-s", "0.17", "--force")
    assert fixed["quality"] == "ok", err
    assert fixed["damping_ns_per_cm"] == pytest.approx(0.0, abs=0.05)
    assert fixed["deformability_n_per_cm"] == pytest.approx(20.0, rel=0.02)
    assert (fixed["force_lag_source"], fixed["force_lag_s"], fixed["lag_s"]) == ("given", 0.17, 0.0)
    # why the estimate withholds λ: λ = 1 N·s/cm behind the same latency, shifted by its estimate
    damped_late = write_export(tmp_path / "damped_late.csv", _lagged(0.17, lam=1.0))
    late, err = _characterize(damped_late, "--lag-s", "auto")
    assert re.search(r"force shifted 0\.1[12]\d* s earlier", err)  # 0.17 − λ/D = 0.12 s
    assert late["quality"] == "damping_unidentifiable"
    assert math.isnan(late["damping_ns_per_cm"])
    kept = shifted_fit(damped_late, "auto")  # what the law says, before any rule withholds λ
    assert kept.chosen.params["damping_ns_per_m"] / 100.0 < 0.3  # λ = 1 reads as about 0
    given, _ = _characterize(damped_late, "--lag-s", "0.17", "--force")
    assert given["quality"] == "ok"
    assert given["damping_ns_per_cm"] == pytest.approx(1.0, rel=0.05)
    damped = write_export(tmp_path / "damped.csv", kv_squeeze(20.0, 3.0))
    row, err = _characterize(damped, "--lag-s", "auto")
    assert row["quality"] == "ok"
    assert row["damping_ns_per_cm"] == pytest.approx(3.0, rel=0.05)  # a lead is not shifted
    assert re.search(r"--lag-s auto: the force's lag is -0\.1[45]\d* s \(.*\): not shifted", err)
    assert row["force_lag_source"] == ""


def shifted_fit(csv: Path, lag: str) -> ObjectFit:
    """The Kelvin–Voigt fit ``characterize`` makes of ``measure csv --lag-s LAG``'s squeezes,
    its lag fitted."""
    rec = read_recording(csv, CsvOptions(lag_s=lag), "x")
    return fit_object(
        rec.squeezes, model="kv", window_s=default_window_s(rec.position_rate_hz),
        fit_preload=True, lag_s=None,
    )  # fmt: skip
