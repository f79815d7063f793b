"""``characterize_arrays``: the coefficients row of time, force and compression arrays, with the
command's defaults: the same columns and numbers as ``measure csv`` then ``characterize`` on the
same samples, and D and λ of a Kelvin–Voigt recording with known truth."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_table
from deformctl.characterize import (
    COEFFICIENT_COLUMNS,
    CoefficientsWarning,
    characterize_arrays,
)
from deformctl.cli import app
from deformctl.errors import InputDataError, UsageError
from deformctl.testing.kelvin_voigt import synthetic_kelvin_voigt_squeeze
from deformctl.testing.synthetic import synthetic_rupture_backoff

D_TRUE, LAMBDA_TRUE = 20.0, 3.0  # N/cm, N·s/cm
runner = CliRunner()


@pytest.fixture(scope="module")
def recording() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    s = synthetic_kelvin_voigt_squeeze(D_TRUE, LAMBDA_TRUE, peak_force_n=15.0, seed=4)
    return s.time_s, s.force_n, s.compression_m


def test_the_row_has_the_table_s_columns_and_the_true_d_and_lambda(recording: tuple) -> None:  # type: ignore[type-arg]
    row = characterize_arrays(*recording, object_id="foam", weight_n=2.9, friction_mu=0.5)
    assert list(row.columns) == list(COEFFICIENT_COLUMNS)
    assert len(row) == 1
    r = row.iloc[0]
    assert r["object_id"] == "foam"
    assert r["weight_n"] == 2.9
    assert r["friction_mu"] == 0.5
    assert r["source"] == "arrays"
    assert r["deformability_n_per_cm"] == pytest.approx(D_TRUE, rel=0.03)
    assert r["damping_ns_per_cm"] == pytest.approx(LAMBDA_TRUE, rel=0.15)


def test_the_row_is_what_the_cli_writes_for_the_same_samples(
    recording: tuple,  # type: ignore[type-arg]
    tmp_path: Path,
) -> None:
    t, f, d = recording
    csv = tmp_path / "r.csv"
    pd.DataFrame({"time_s": t, "force_n": f, "compression_m": d}).to_csv(
        csv, index=False, float_format="%.17g"
    )
    log, table = tmp_path / "r.mcap", tmp_path / "r.parquet"
    args = ["measure", "csv", str(csv), "--object-id", "foam", "--weight-n", "2.9",
            "--friction-mu", "0.5", "-q", "-o", str(log)]  # fmt: skip
    assert runner.invoke(app, args).exit_code == 0
    done = runner.invoke(app, ["characterize", str(log), "-q", "-o", str(table)])
    assert done.exit_code == 0, done.stderr
    cli = read_table(table, "coefficients")
    zeroed = d - d[0]  # measure csv reads a compression column from its first row
    mine = characterize_arrays(t, f, zeroed, object_id="foam", weight_n=2.9, friction_mu=0.5)
    assert list(mine.columns) == list(cli.columns)
    numbers = ["deformability_n_per_cm", "damping_ns_per_cm", "r2", "at_force_n", "lag_s"]
    for column in [c for c in numbers if c in cli.columns]:
        assert mine[column].iloc[0] == pytest.approx(cli[column].iloc[0], rel=1e-9, nan_ok=True)
    for column in cli.columns:
        want, got = cli[column].iloc[0], mine[column].iloc[0]
        if column == "source":
            assert (want, got) == ("csv", "arrays")
        elif isinstance(want, float):
            assert got == pytest.approx(want, rel=1e-9, nan_ok=True), column
        else:
            assert got == want, column


def test_lists_work_as_arrays_and_a_time_offset_changes_nothing(recording: tuple) -> None:  # type: ignore[type-arg]
    t, f, d = recording
    a = characterize_arrays(t, f, d)
    b = characterize_arrays(list(t + 1000.0), list(f), list(d))
    assert b["deformability_n_per_cm"].iloc[0] == pytest.approx(
        a["deformability_n_per_cm"].iloc[0], rel=1e-6
    )
    assert np.isnan(a["weight_n"].iloc[0])  # not given: not known


def test_a_flagged_row_warns_and_strict_refuses(recording: tuple) -> None:  # type: ignore[type-arg]
    t, f, d = recording
    ramp = slice(0, 600)  # the loading ramp alone: one speed, 600 samples
    with pytest.warns(CoefficientsWarning, match="damping_unidentifiable") as caught:
        row = characterize_arrays(t[ramp], f[ramp], d[ramp], object_id="ramp")
    assert len(caught) == 1
    assert "object 'ramp'" in str(caught[0].message)
    assert "damping_unidentifiable" in row["quality"].iloc[0].split(",")
    assert np.isnan(row["damping_ns_per_cm"].iloc[0])  # not a number a robot could act on
    with pytest.raises(InputDataError, match="ramp"):
        characterize_arrays(t[ramp], f[ramp], d[ramp], object_id="ramp", strict=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the whole recording: ok, no warning
        assert characterize_arrays(t, f, d)["quality"].iloc[0] == "ok"


@pytest.mark.parametrize(
    ("change", "error", "text"),
    [
        (lambda t, f, d: (t[:-1], f, d), InputDataError, "differ in length"),
        (lambda t, f, d: (t[:1], f[:1], d[:1]), InputDataError, "at least 2 samples"),
        (lambda t, f, d: (t[::-1], f, d), InputDataError, "time_s must increase"),
        (lambda t, f, d: (t, np.where(t > 1, np.nan, f), d), InputDataError, "not finite"),
        (lambda t, f, d: (t, f, -np.abs(d)), InputDataError, "never exceeds 0"),
        (lambda t, f, d: (t, f, np.stack([d, d])), InputDataError, "one-dimensional"),
        (lambda t, f, d: (t, ["a"] * len(t), d), InputDataError, "not numeric"),
    ],
)
def test_bad_arrays_are_one_clear_error(recording: tuple, change, error, text) -> None:  # type: ignore[no-untyped-def,type-arg]
    with pytest.raises(error, match=text):
        characterize_arrays(*change(*recording))


@pytest.mark.parametrize(
    ("option", "text"),
    [
        ({"weight_n": 0.0}, "weight"),
        ({"friction_mu": -1.0}, "friction"),
        ({"method": "best"}, "method"),
        ({"model": "spring"}, "model"),
        ({"window_s": 0.0}, "window"),
        ({"object_id": ""}, "object_id"),
    ],
)
def test_bad_options_are_usage_errors(recording: tuple, option: dict, text: str) -> None:  # type: ignore[type-arg]
    with pytest.raises(UsageError, match=text):
        characterize_arrays(*recording, **option)


def test_a_rupture_is_cut_off_recorded_and_warned() -> None:
    s = synthetic_rupture_backoff(rupture_force_n=12.0, seed=1)
    with pytest.warns(CoefficientsWarning, match="rupture") as caught:
        row = characterize_arrays(s.time_s, s.force_n, s.compression_m, object_id="crushed")
    assert any("cut off" in str(w.message) for w in caught)
    assert row["rupture_force_n"].iloc[0] == pytest.approx(12.0, rel=0.02)  # the true one
    assert "rupture" in row["quality"].iloc[0].split(",")
