"""Quality flags of a fit: each fires on the synthetic log made to trip it and stays silent on
clean ones (``tests/_helpers/doubtful_logs.py`` builds the logs; thresholds in
``deformctl.characterize.quality``).

Silence on the good paths is checked here for clean position-controlled squeezes and in the
tests of each path: the synthetic grid (``tests/characterize/test_fit.py``), the simulator and
Table II (``tests/sim/test_pipeline.py``), bags and CSV exports (``tests/cli/test_measure.py``).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from deformctl.characterize import (
    characterize,
    fit_lsq,
    fit_paper,
    kelvin_voigt_piecewise_linear,
)
from deformctl.characterize.quality import (
    DAMPING_EXCITATION_MIN,
    DAMPING_PRELOAD_SENSITIVITY,
    FEW_SAMPLES_WINDOWS,
    FLAGS,
    LOW_R2,
    PAPER_MONOTONIC_FRAC,
    assess,
    damping_identifiable,
    describe_row,
    enforce,
    parse_quality,
    quality_text,
    thresholds_help,
)
from deformctl.errors import InputDataError, UsageError
from deformctl.series import SqueezeSeries
from deformctl.testing.kelvin_voigt import synthetic_kelvin_voigt_squeeze
from tests._helpers.doubtful_logs import constant_rate, position_controlled, rupture


def _two(**kw: float) -> list[SqueezeSeries]:
    return [position_controlled(seed=i, index=i, **kw) for i in range(2)]  # type: ignore[arg-type]


def test_clean_squeezes_are_ok_with_every_option() -> None:
    squeezes = _two(d_n_per_cm=20.0, lam_ns_per_cm=3.0)
    for preload in ("zero", "fit"):
        fit = fit_lsq(squeezes, preload=preload)
        assert fit.quality == "ok", (preload, fit)
        assert fit.deformability_n_per_cm == pytest.approx(20.0, rel=0.01)
        assert fit.damping_ns_per_cm == pytest.approx(3.0, rel=0.01)
        assert not fit.damping_bound_active
        # a haversine's rate is 85 % explained by its direction of motion, the rest excites λ
        assert fit.damping_excitation > 3 * DAMPING_EXCITATION_MIN
    assert fit_paper(squeezes).quality == "ok"


def test_negative_damping_is_held_at_the_bound() -> None:
    # λ is never negative with ok; the lsq fits are bounded (λ >= 0) and say so
    squeezes = _two(d_n_per_cm=20.0, lam_ns_per_cm=-2.0)
    fit = fit_lsq(squeezes)
    assert fit.damping_ns_per_cm == 0.0
    assert fit.damping_bound_active
    assert math.isnan(fit.damping_se_ns_per_cm)
    assert fit.flags == ("at_bound",)
    assert fit.material["params_at_bound"] == "damping_ns_per_m"
    assert fit.deformability_n_per_cm == pytest.approx(20.0, rel=0.02)


def test_a_negative_damping_is_flagged_whatever_its_standard_error() -> None:
    # the paper estimator is not bounded: any λ < 0 is flagged (the rule before the bounded fits
    # needed λ < -0.1 N·s/cm and 2 standard errors, and let 11 of 14 fruit loadings through as ok)
    assert assess(
        deformability_n_per_cm=20.0, damping_ns_per_cm=-0.01, damping_se_ns_per_cm=5.0,
        r2=0.99, n_samples=1000, window_samples=10,
    ) == ("negative_damping",)  # fmt: skip
    assert assess(
        deformability_n_per_cm=20.0, damping_ns_per_cm=0.0, damping_se_ns_per_cm=5.0,
        r2=0.99, n_samples=1000, window_samples=10,
    ) == ()  # fmt: skip


def test_a_lambda_zero_object_is_ok_or_at_bound_never_negative() -> None:
    # λ = 0 objects: the free fit lands either side of 0; the bounded one at 0 or above
    for seed in range(4):
        sq = [position_controlled(60.0, 0.0, seed=10 * seed + i, index=i) for i in range(2)]
        fit = fit_lsq(sq)
        assert fit.damping_ns_per_cm >= 0.0
        assert fit.quality in ("ok", "at_bound")
        assert (fit.quality == "at_bound") == (fit.damping_ns_per_cm == 0.0)


def test_negative_stiffness_from_a_force_of_the_wrong_sign() -> None:
    s = position_controlled(20.0, 3.0)
    flipped = SqueezeSeries("obj", 0, s.time_s, -s.force_n, s.compression_m)
    fit = fit_lsq([flipped])
    assert fit.deformability_n_per_cm == 0.0  # held at its bound: the force falls as d grows
    assert fit.flags[0] == "negative_stiffness"
    assert "at_bound" in fit.flags


def test_low_r2_when_the_force_is_sensor_noise() -> None:
    # a wrong force axis: what is left is cross-talk (2 %) under the sensor's noise
    s = synthetic_kelvin_voigt_squeeze(20.0, 3.0, seed=4)
    rng = np.random.default_rng(0)
    weak = SqueezeSeries(
        "obj", 0, s.time_s, 0.02 * s.force_n + rng.normal(0, 0.1, len(s)), s.compression_m
    )
    fit = fit_lsq([weak])
    assert fit.r2 < LOW_R2
    assert "low_r2" in fit.flags


def test_constant_rate_makes_damping_unidentifiable() -> None:
    for preload_n, mode in ((0.0, "zero"), (0.5, "zero"), (0.5, "fit")):
        fit = fit_lsq([constant_rate(20.0, 3.0, preload_n=preload_n)], preload=mode)  # type: ignore[arg-type]
        assert math.isnan(fit.damping_ns_per_cm), (preload_n, mode, fit)
        assert math.isnan(fit.damping_se_ns_per_cm)
        assert fit.damping_excitation < DAMPING_EXCITATION_MIN
        assert fit.flags == ("damping_unidentifiable",)
        assert fit.deformability_n_per_cm == pytest.approx(20.0, rel=0.02)  # D is still fine
        assert math.isnan(fit.material["hysteresis_energy_j"])  # a ramp: no loop closes


def test_slow_heavily_damped_creep_stays_identifiable() -> None:
    # a 1 s force ramp and 1 s hold at λ/D = 3 s: the rate barely changes (excitation ~0.04)
    # but λ is determined; the preload sensitivity guard keeps it
    t = np.arange(0.0, 2.0, 1e-3)
    kt, kf = np.array([0.0, 1.0, 2.0]), np.array([0.0, 10.0, 10.0])
    d = kelvin_voigt_piecewise_linear(t, kt, kf, 500.0, 1500.0)
    rng = np.random.default_rng(3)
    squeezes = [
        SqueezeSeries(
            "obj",
            i,
            t,
            np.interp(t, kt, kf) + rng.normal(0, 0.1, t.size),
            d + rng.normal(0, 5e-5, t.size),
        )
        for i in range(3)
    ]
    fit = fit_lsq(squeezes)
    assert fit.damping_excitation < 2 * DAMPING_EXCITATION_MIN  # measured 0.061
    assert fit.quality == "ok"
    assert fit.damping_ns_per_cm == pytest.approx(15.0, rel=0.03)


def test_identifiability_rule() -> None:
    assert damping_identifiable(0.5, 10.0)
    assert damping_identifiable(0.01, 0.05)
    assert not damping_identifiable(0.01, 0.5)
    assert not damping_identifiable(0.01, math.nan)
    assert not damping_identifiable(math.nan, 0.0)


def test_paper_method_flags_a_monotonic_loading() -> None:
    t = np.arange(0.0, 2.0, 1e-3)
    kt, kf = np.array([0.0, 2.0]), np.array([0.0, 10.0])
    d = kelvin_voigt_piecewise_linear(t, kt, kf, 2000.0, 300.0)
    rng = np.random.default_rng(1)
    ramps = [
        SqueezeSeries(
            "obj",
            i,
            t,
            np.interp(t, kt, kf) + rng.normal(0, 0.1, t.size),
            d + rng.normal(0, 1e-5, t.size),
        )
        for i in range(2)
    ]
    fit = fit_paper(ramps)
    assert math.isnan(fit.damping_ns_per_cm)
    assert "damping_unidentifiable" in fit.flags
    row = characterize({"obj": ramps}, "paper").iloc[0]
    assert "not identifiable by the paper estimator" in describe_row(row)
    # lsq on the same ramps: one speed cannot tell a material's rate dependence from
    # a preload, however exactly the start's transient pins a Kelvin-Voigt λ; D is still right
    lsq = fit_lsq(ramps)
    assert lsq.quality == "damping_unidentifiable"
    assert math.isnan(lsq.damping_ns_per_cm)
    assert lsq.deformability_n_per_cm == pytest.approx(20.0, rel=0.05)


def test_rupture_is_cut_and_flagged() -> None:
    whole = rupture(13.0, 0.33)
    fit = fit_lsq([whole])
    (r,) = fit.ruptures
    assert r.time_s == pytest.approx(2.0, abs=0.02)
    assert r.force_n == pytest.approx(10.0, rel=0.05)
    assert "rupture" in fit.flags
    # fitted up to the rupture: D is right (whole, the collapse would halve it)
    assert fit.deformability_n_per_cm == pytest.approx(13.0, rel=0.02)
    row = characterize({"obj": [whole]}).iloc[0]
    assert row["ruptures"] == 1
    assert row["rupture_force_n"] == pytest.approx(r.force_n)


def test_few_samples() -> None:
    short = synthetic_kelvin_voigt_squeeze(20.0, 3.0, duration_s=0.5, profile="sine")
    fit = fit_lsq([short])
    assert fit.n_samples < 4 * fit.window_samples
    assert fit.flags == ("few_samples",)


def test_preload_fit_recovers_d_that_zero_biases() -> None:
    squeezes = _two(d_n_per_cm=20.0, lam_ns_per_cm=3.0, preload_n=0.5)
    zero, fit = fit_lsq(squeezes), fit_lsq(squeezes, preload="fit")
    assert zero.deformability_n_per_cm > 21.0  # +11 %: the preload leaks into D
    assert math.isnan(zero.preload_n)
    assert fit.preload_n == pytest.approx(0.5, abs=0.01)
    assert fit.deformability_n_per_cm == pytest.approx(20.0, rel=0.01)
    with pytest.raises(UsageError, match="--preload must be fit or zero"):
        fit_lsq(squeezes, preload="auto")  # type: ignore[arg-type]


def test_table_columns_carry_the_diagnostics() -> None:
    df = characterize({"a": _two(d_n_per_cm=20.0, lam_ns_per_cm=3.0)}, preload="fit")
    row = df.iloc[0]
    assert row["quality"] == "ok"
    assert row["preload_n"] == pytest.approx(0.0, abs=0.02)
    assert row["compression_max_cm"] == pytest.approx(0.3, rel=0.05)  # 3 mm peak
    assert row["force_max_n"] > row["force_min_n"]
    assert row["design_condition"] >= 1.0
    assert row["window_samples"] == 201
    assert not row["damping_bound_active"]
    assert row["ruptures"] == 0
    assert math.isnan(row["rupture_time_s"])
    with pytest.raises(UsageError, match="paper estimator has no preload"):
        characterize({"a": _two(d_n_per_cm=20.0, lam_ns_per_cm=3.0)}, "paper", preload="fit")


def _table(*qualities: str) -> pd.DataFrame:
    return pd.DataFrame(
        {
            "object_id": [f"o{i}" for i in range(len(qualities))],
            "deformability_n_per_cm": [
                -16.0 if "negative_stiffness" in q else 20.0 for q in qualities
            ],
            "damping_ns_per_cm": [-2.0] * len(qualities),
            "damping_se_ns_per_cm": [0.1] * len(qualities),
            "r2": [0.5] * len(qualities),
            "quality": list(qualities),
        }
    )


def test_policy_warns_once_per_object_and_refuses() -> None:
    lines = enforce(_table("ok", "negative_damping,low_r2"), path="log.mcap")
    assert lines == [
        "log.mcap: object 'o1': negative_damping (λ = -2 ± 0.1 N·s/cm < 0), low_r2 (R² = 0.5 < 0.9)"
    ]
    with pytest.raises(InputDataError, match=r"--strict: object 'o1' is flagged: negative_damp"):
        enforce(_table("ok", "negative_damping"), strict=True, path="log.mcap")
    with pytest.raises(InputDataError, match=r"object 'o0': negative_stiffness \(D = -16 N/cm"):
        enforce(_table("negative_stiffness"))
    assert len(enforce(_table("negative_stiffness"), allow_flagged=True)) == 1
    with pytest.raises(UsageError, match="--strict or --allow-flagged, not both"):
        enforce(_table("ok"), strict=True, allow_flagged=True)
    # tables written before quality existed are not judged
    assert enforce(_table("ok").drop(columns="quality"), strict=True) == []


def test_quality_text_round_trip() -> None:
    assert quality_text(()) == "ok"
    assert parse_quality("ok") == ()
    assert parse_quality(None) == ()
    assert parse_quality(quality_text(FLAGS)) == FLAGS


def test_thresholds_are_stated_in_the_docs_and_the_help() -> None:
    guide = Path(__file__).resolve().parents[2] / "docs" / "guide" / "testing-machine.md"
    section = (
        guide.read_text(encoding="utf-8")
        .split("## When the numbers are doubtful", 1)[1]
        .split("\n## ", 1)[0]
    )
    stated = {
        "low_r2": f"R² < {LOW_R2:g}",
        "negative_damping": "λ < 0",
        "excitation": f"{DAMPING_EXCITATION_MIN:g}",
        "sensitivity": f"{100 * DAMPING_PRELOAD_SENSITIVITY:g} %",
        "monotonic": f"{100 * PAPER_MONOTONIC_FRAC:g} %",
        "few_samples": f"{FEW_SAMPLES_WINDOWS:g}",
    }
    for name, text in stated.items():
        assert text in section, name
        assert text in thresholds_help(), name
    for flag in FLAGS:
        assert f"`{flag}`" in section
        assert flag in thresholds_help()


def test_swapped_force_and_position_columns_are_flagged_when_damped() -> None:
    # an export read with force and position swapped (mm as N, N as mm): the damping term turns
    # negative and the fit poor. (A nearly elastic object swapped is just another elastic object,
    # D' = 1/D in those units: no flag can tell, only the units and size checks of measure.)
    s = synthetic_kelvin_voigt_squeeze(5.0, 6.47, seed=1, profile="sine")
    swapped = SqueezeSeries("obj", 0, s.time_s, s.compression_m * 1e3, s.force_n * 1e-3)
    fit = fit_lsq([swapped])
    assert fit.r2 < 0
    assert fit.flags == ("low_r2", "at_bound")  # λ held at 0: the free fit was negative
