"""Rupture as fruit breaks: the detector on seeded force-controlled squeezes to collapse.

The truth comes from :mod:`deformctl.testing.fruit` (the force at the onset of the collapse);
the full measurement is ``python -m deformctl.testing.fruit check --draws 500`` (numbers in
docs/explanation/materials.md). Here a share of it, with the same targets: a rupture on ≥ 90 %
of the collapses by more than half, its force within 10 % of the onset force (not the peak
before a yield, not the later peak of the crushed fruit), a safe force at or below the onset
force, no collapse flagged ``relaxation`` and no rupture in relaxation holds or back-offs.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from deformctl.characterize import characterize
from deformctl.measure import CsvOptions, read_recording
from deformctl.squeeze.rupture import SAFE_FORCE_MARGIN, cut_rupture, safe_force_n
from deformctl.squeeze.window import default_window_s
from deformctl.testing.fruit import SHAPES, check, fruit_squeeze, main, write_csv

DRAWS = 160


@pytest.fixture(scope="module")
def result():  # type: ignore[no-untyped-def]
    return check(DRAWS, seed=1)


def test_generator_is_seeded_and_covers_every_shape() -> None:
    a, b = fruit_squeeze(3, 7), fruit_squeeze(3, 7)
    np.testing.assert_array_equal(a.series.force_n, b.series.force_n)
    np.testing.assert_array_equal(a.series.time_s, b.series.time_s)
    assert not np.array_equal(a.series.force_n[:20], fruit_squeeze(3, 8).series.force_n[:20])
    assert {fruit_squeeze(0, i).shape for i in range(40)} == set(SHAPES)
    with pytest.raises(ValueError, match="unknown shape"):
        fruit_squeeze(0, 0, shape="banana")


@pytest.mark.parametrize("draw", range(6))
def test_truth_is_the_force_at_the_onset_of_the_collapse(draw: int) -> None:
    fs = fruit_squeeze(2, draw, shape="collapse")
    s = fs.series
    near = np.abs(s.time_s - fs.onset_time_s) < 0.03
    noise = fs.params["force_noise_n"]
    assert np.mean(s.force_n[near]) == pytest.approx(fs.onset_force_n, abs=4 * noise + 0.02)
    within = (s.time_s > fs.onset_time_s) & (s.time_s < fs.onset_time_s + 0.45)
    low = float(np.min(s.force_n[within]))
    assert low < (1.0 - fs.collapse_frac) * fs.onset_force_n + 4 * noise  # it collapses ...
    assert float(np.max(s.force_n[within])) < fs.onset_force_n + 5 * noise  # ... from the onset


def test_rupture_found_on_collapses_by_more_than_half(result) -> None:  # type: ignore[no-untyped-def]
    assert result.big >= 40
    assert result.big_found >= 0.9 * result.big
    assert result.big_force_ok >= 0.9 * result.big


def test_rupture_force_is_the_onset_not_a_peak(result) -> None:  # type: ignore[no-untyped-def]
    err = np.abs(result.force_errors)
    assert float(np.median(err)) < 0.03
    assert result.safe_above_onset == 0
    assert result.collapses_called_relaxation == 0


def test_no_rupture_in_relaxation_or_back_off(result) -> None:  # type: ignore[no-untyped-def]
    assert result.not_rupture.get("relaxation", 0) >= 20
    assert result.not_rupture.get("backoff", 0) >= 20
    bad = sum(result.false_rupture.values())
    assert bad <= 0.02 * sum(result.not_rupture.values())  # measured: 0 of 83; 2 of 1450 at 3000


def test_yield_then_collapse_reports_the_break_not_the_peak() -> None:
    # draw 9 of seed 0: a peak of 14.3 N, a slow yield, then the break at 5.75 N (73 % lost)
    fs = fruit_squeeze(0, 9)
    assert fs.params["peak_before_n"] > 2 * fs.onset_force_n
    cut, r = cut_rupture(fs.series, window_s=default_window_s(fs.rate_hz))
    assert r is not None
    assert r.force_n == pytest.approx(fs.onset_force_n, rel=0.1)
    assert r.time_s == pytest.approx(fs.onset_time_s, abs=0.15)
    assert cut.time_s[-1] < r.time_s  # the fit stops at the peak, where the yield began
    row = characterize({"kiwi": [fs.series]}, window_s=default_window_s(fs.rate_hz)).iloc[0]
    assert row["rupture_force_n"] == pytest.approx(fs.onset_force_n, rel=0.1)
    flags = row["quality"].split(",")
    assert "rupture" in flags
    assert "relaxation" not in flags


def test_safe_force_margin() -> None:
    assert 0 < SAFE_FORCE_MARGIN < 0.5
    assert safe_force_n(10.0) == pytest.approx(10.0 * (1.0 - SAFE_FORCE_MARGIN))
    assert math.isnan(safe_force_n(math.nan))


def test_through_the_csv_reader_the_same_rupture(tmp_path: Path) -> None:
    # draw 9 of seed 0 as a CSV export, read as measure --csv reads it: the same onset
    fs = fruit_squeeze(0, 9)
    write_csv(fs, str(tmp_path / "kiwi.csv"))
    rec = read_recording(tmp_path / "kiwi.csv", CsvOptions(), "kiwi")
    assert len(rec.ruptures) == 1
    assert rec.ruptures[0].force_n == pytest.approx(fs.onset_force_n, rel=0.1)
    res = check(6, seed=0, through_csv=True)
    assert res.draws == 6
    assert sum(res.not_rupture.values()) + res.big + res.small == 6


def test_check_command_prints_the_numbers(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    assert main(["check", "--draws", "8", "--seed", "4"]) == 0
    out = capsys.readouterr().out
    assert "draws: 8" in out
    assert "rupture found on" in out
    assert "false ruptures on" in out
    assert main(["show", "3"]) == 0
    assert "onset" in capsys.readouterr().out
    out_csv = tmp_path / "f.csv"
    assert main(["csv", "3", "-o", str(out_csv), "--shape", "backoff"]) == 0
    assert out_csv.read_text().startswith("Time (s),Load (N),Compression (mm)\n")
