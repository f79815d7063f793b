"""Identify before choosing: the law ``auto`` reports on short textbook recordings with known truth.

The recording (:func:`deformctl.testing.synthetic.synthetic_ramp_hold`): one ramp of 0.6 cm
at 0.6 cm/s, a 1 s hold, 100 Hz, force noise 0.02 N, fitted as ``characterize`` fits a CSV export
(a preload and a lag fitted, the window of a 100 Hz recording). The laws nest Kelvin–Voigt, so a
richer law is reported only when its extra parameters are identified and its BIC is lower by
:data:`~deformctl.characterize.materials.BIC_MARGIN` (the rule:
:func:`~deformctl.characterize.materials.choose`, docs/explanation/materials.md).

Measured (``DEFORMCTL_MATERIAL_DRAWS=400``; ``make materials``): the confusion matrix in
docs/explanation/materials.md. The default runs 5 draws per law.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_table
from deformctl.characterize import fit_object
from deformctl.characterize.coefficients import CoefficientFit
from deformctl.characterize.laws import secant_stiffness
from deformctl.characterize.material_options import MODELS
from deformctl.characterize.materials import degenerate
from deformctl.characterize.objectfit import ObjectFit
from deformctl.cli import app
from deformctl.series import SqueezeSeries
from deformctl.squeeze.window import default_window_s
from deformctl.testing.synthetic import (
    FORCE_HOLD_SHAPES,
    synthetic_force_hold_squeeze,
    synthetic_ramp_hold,
)
from deformctl.units import N_PER_CM, NS_PER_CM

DRAWS = int(os.environ.get("DEFORMCTL_MATERIAL_DRAWS", "5"))
PEAK_M = 0.006
#: f = 20 d + 1.0 ḋ in N, cm, s.
KV = {"stiffness_n_per_m": 20.0 * N_PER_CM, "damping_ns_per_m": 1.0 * NS_PER_CM}
#: The textbook truth of each law: the same secant, 20 N/cm, at the peak compression.
TEXTBOOK: dict[str, dict[str, float]] = {
    "kv": KV,
    "hc": {
        "stiffness_n_per_m_pow_n": 2000.0 / PEAK_M**0.6,
        "exponent": 1.6,
        "damping_ns_per_m_pow_n_plus_1": 100.0 / PEAK_M**1.6,
    },
    "sls": {"stiffness_n_per_m": 1200.0, "arm_stiffness_n_per_m": 1500.0, "relaxation_time_s": 0.8},
    "exp": {"stiffness_n_per_m": 1000.0, "stiffening_per_m": 300.0, "damping_ns_per_m": 100.0},
}
WINDOW_S = default_window_s(100.0)


def _fit(squeeze: SqueezeSeries, rate_hz: float = 100.0) -> ObjectFit:
    return fit_object(
        [squeeze], model="auto", window_s=default_window_s(rate_hz), fit_preload=True, lag_s=None
    )


def test_textbook_kelvin_voigt_is_kv_with_d_and_lambda() -> None:
    for seed in range(DRAWS):
        obj = _fit(synthetic_ramp_hold("kv", KV, seed=seed))
        d = obj.deformability_n_per_m / N_PER_CM
        lam = obj.damping_ns_per_m / NS_PER_CM
        print(f"\nseed {seed}: {obj.chosen.model}, D {d:.4f} N/cm, λ {lam:.4f} N·s/cm")
        assert obj.chosen.model == "kv"
        assert d == pytest.approx(20.0, rel=0.01)
        assert lam == pytest.approx(1.0, rel=0.05)
        # the nested laws reach Kelvin–Voigt at a bound, or gain less than the margin
        hc = obj.fit("hc")
        assert hc is not None
        assert "exponent" in hc.at_bound or obj.chosen.bic - hc.bic < 10.0


def test_textbook_kelvin_voigt_through_the_cli(tmp_path: Path) -> None:
    s = synthetic_ramp_hold("kv", KV, seed=0)
    csv = tmp_path / "textbook.csv"
    rows = np.column_stack([s.time_s, 1e3 * s.compression_m, s.force_n])
    np.savetxt(csv, rows, delimiter=",", header="Time (s),Compression (mm),Load (N)", comments="")
    runner = CliRunner()
    log, out = tmp_path / "x.mcap", tmp_path / "c.parquet"
    res = runner.invoke(app, ["measure", "csv", str(csv), "--weight-n", "1", "-o", str(log)])
    assert res.exit_code == 0, res.stderr
    res = runner.invoke(app, ["characterize", str(log), "-o", str(out)])
    assert res.exit_code == 0, res.stderr
    (row,) = read_table(out, "coefficients").to_dict("records")
    print(f"\nCLI: {row['model']}, D {row['deformability_n_per_cm']:.4f}, λ "
          f"{row['damping_ns_per_cm']:.4f}, {row['quality']}")  # fmt: skip
    assert row["model"] == "kv"
    assert row["deformability_n_per_cm"] == pytest.approx(20.0, rel=0.01)
    assert row["damping_ns_per_cm"] == pytest.approx(1.0, rel=0.05)
    assert row["quality"] == "ok"


def test_hunt_crossley_ramp_hold_is_hc_with_its_exponent() -> None:
    truth = TEXTBOOK["hc"]
    for seed in range(DRAWS):
        obj = _fit(synthetic_ramp_hold("hc", truth, seed=seed))
        n = obj.chosen.params.get("exponent", math.nan)
        d_true = secant_stiffness("hc", truth, obj.operating_force_n)
        print(f"\nseed {seed}: {obj.chosen.model}, n {n:.4f}, D {obj.deformability_n_per_m:.1f} "
              f"vs {d_true:.1f} N/m")  # fmt: skip
        assert obj.chosen.model == "hc"
        assert n == pytest.approx(1.6, abs=0.03)
        assert obj.deformability_n_per_m == pytest.approx(d_true, rel=0.01)
        assert obj.damping_identifiable


def test_relaxing_solid_is_sls_with_its_relaxation_time() -> None:
    truth = TEXTBOOK["sls"]
    for seed in range(DRAWS):
        obj = _fit(synthetic_ramp_hold("sls", truth, seed=seed))
        assert obj.chosen.model == "sls"
        assert obj.chosen.params["relaxation_time_s"] == pytest.approx(0.8, rel=0.05)
        assert obj.chosen.params["stiffness_n_per_m"] == pytest.approx(1200.0, rel=0.02)


def test_a_single_ramp_does_not_identify_damping() -> None:
    """No hold: one monotone ramp at one speed. λ is not invented: NaN and flagged."""
    obj = _fit(synthetic_ramp_hold("kv", KV, hold_s=0.0, seed=1))
    assert not obj.damping_identifiable
    assert math.isnan(obj.damping_ns_per_m)
    assert obj.chosen.model == "kv"
    assert "damping_unidentifiable" in CoefficientFit.from_object(obj).flags


@pytest.mark.parametrize("shape", sorted(FORCE_HOLD_SHAPES))
def test_a_solid_with_no_stiffness_is_never_chosen(shape: str) -> None:
    """Force-controlled squeezes whose force falls while the jaws hold: the standard linear solid
    fits them best with its stiffness at 0 (so BIC alone would choose a fluid); it is never
    reported."""
    obj = _fit(synthetic_force_hold_squeeze(shape), rate_hz=77.0)
    sls = obj.fit("sls")
    assert sls is not None
    assert degenerate(sls)
    assert sls.bic < min(f.bic for f in obj.fits if f.model != "sls")
    assert not degenerate(obj.chosen)
    assert obj.chosen.model != "sls"
    assert obj.deformability_n_per_m > 0


def test_textbook_confusion_matrix() -> None:
    """Rows: the true law of the textbook recording; columns: the law ``auto`` chose."""
    lines = [f"\ntextbook ramp-and-hold, {DRAWS} draws per law (rows true, columns chosen)"]
    lines.append("true   " + " ".join(f"{m:>5}" for m in MODELS))
    wrong = 0
    for law in MODELS:
        chosen = [
            _fit(synthetic_ramp_hold(law, TEXTBOOK[law], seed=100 + seed)).chosen.model
            for seed in range(DRAWS)
        ]
        counts = [chosen.count(m) for m in MODELS]
        wrong += DRAWS - counts[MODELS.index(law)]
        lines.append(f"{law:<6} " + " ".join(f"{c:>5}" for c in counts))
    print("\n".join(lines))
    assert wrong <= 0.05 * DRAWS * len(MODELS)


def test_single_ramp_confusion_matrix() -> None:
    """The same recordings without the hold: one monotone ramp at one speed. The curve's shape
    is still identified (hc, exp), damping never is (λ NaN for every draw), so a relaxing solid,
    whose relaxation the ramp cannot show, is reported as the simpler law, Kelvin–Voigt."""
    expected = {"kv": "kv", "hc": "hc", "sls": "kv", "exp": "exp"}
    lines = [f"\nsingle ramp, no hold, {DRAWS} draws per law (rows true, columns chosen)"]
    lines.append("true   " + " ".join(f"{m:>5}" for m in MODELS))
    wrong = 0
    for law in MODELS:
        fits = [
            _fit(synthetic_ramp_hold(law, TEXTBOOK[law], hold_s=0.0, seed=200 + seed))
            for seed in range(DRAWS)
        ]
        assert not any(f.damping_identifiable for f in fits)
        assert all(math.isnan(f.damping_ns_per_m) for f in fits)
        chosen = [f.chosen.model for f in fits]
        counts = [chosen.count(m) for m in MODELS]
        wrong += DRAWS - chosen.count(expected[law])
        lines.append(f"{law:<6} " + " ".join(f"{c:>5}" for c in counts))
    print("\n".join(lines))
    assert wrong <= 0.05 * DRAWS * len(MODELS)


def test_textbook_kelvin_voigt_piped_to_predict_grip_matches_lift_sim(tmp_path: Path) -> None:
    """The textbook recording of a 10 N object (μ 0.5) through measure csv, characterize and
    predict grip gives the L_f that lift sim finds for that material (within 3 %; the wrong law
    once gave +17 %)."""
    s = synthetic_ramp_hold("kv", KV, seed=0)
    csv = tmp_path / "textbook.csv"
    rows = np.column_stack([s.time_s, 1e3 * s.compression_m, s.force_n])
    np.savetxt(csv, rows, delimiter=",", header="Time (s),Compression (mm),Load (N)", comments="")
    runner = CliRunner()
    log, coef, pred = tmp_path / "x.mcap", tmp_path / "c.parquet", tmp_path / "p.parquet"
    measure = ["measure", "csv", str(csv), "--weight-n", "10", "--friction-mu", "0.5"]
    assert runner.invoke(app, [*measure, "--object-id", "kv", "-o", str(log)]).exit_code == 0
    assert runner.invoke(app, ["characterize", str(log), "-o", str(coef)]).exit_code == 0
    res = runner.invoke(app, ["predict", "grip", str(coef), "-o", str(pred)])
    assert res.exit_code == 0, res.stderr
    (predicted,) = read_table(pred, "predictions")["predicted_lift_force_n"]
    catalog = tmp_path / "catalog.csv"
    catalog.write_text(
        "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu,"
        "material_stiffness_n_per_cm,material_damping_ns_per_cm\nkv,10,10,10,10,0.5,20,1.0\n"
    )
    lifted = tmp_path / "l.parquet"
    res = runner.invoke(app, ["lift", "sim", str(catalog), "-o", str(lifted)])
    assert res.exit_code == 0, res.stderr
    (truth,) = read_table(lifted, "lift_results")["lift_force_n"]
    print(f"\npredict grip {predicted:.4f} N, lift sim {truth:.4f} N")
    assert predicted == pytest.approx(truth, rel=0.03)
