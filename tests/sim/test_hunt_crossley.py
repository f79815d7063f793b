"""The simulator carries a stiffening material (deformctl.sim.hunt_crossley).

Known truth: the linear lattice's own calibration (n = 1), the homogeneity of the power-law
squeeze (any closing gives the same C_n), the object's law ``k dⁿ + λ_hc dⁿ ḋ`` for a slow
squeeze on the table (within 5 % over the loading range; a floating squeeze is softer by the
calibration's own table factor), a resting object that stays put, and the linear lattice just
above n = 1 (the elastic law is continuous there, its damping is not).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from numpy.typing import NDArray
from typer.testing import CliRunner

from deformctl.catalog import CatalogObject
from deformctl.cli import app
from deformctl.errors import InputDataError
from deformctl.presets import sim_preset
from deformctl.series import SqueezeSeries
from deformctl.sim import ObjectSpec, squeeze
from deformctl.sim import hunt_crossley as hc
from deformctl.sim.lattice import build_lattice
from deformctl.sim.statics import unit_squeeze_stiffness_n_per_m
from tests._helpers.hard_objects import P1224

runner = CliRunner()
#: the paper preset on a small lattice (5 particles per side: the tests stay fast)
SMALL = dataclasses.replace(sim_preset("paper").settings, particles_per_side=5)


def _spec(n: float, damping_ns_per_cm: float = 0.0) -> ObjectSpec:
    # W = 5 N, mu = 0.5: F_op = F_w = 5 N; D = 5 N/cm at F_op: d_op = 1 cm (10 % strain)
    return ObjectSpec("hc", (10.0, 10.0, 10.0), 5.0, 0.5, 5.0, damping_ns_per_cm, n)


def test_the_catalog_values_map_to_k_and_lambda_at_the_operating_force() -> None:
    spec = _spec(2.5, 2.0)
    f_op = 5.0 / (2 * 0.5)
    d_op = f_op / 500.0  # m
    assert spec.operating_compression_m == pytest.approx(d_op, rel=1e-15)
    assert spec.hc_stiffness_n_per_m_pow_n == pytest.approx(f_op / d_op**2.5, rel=1e-12)
    # D is the secant at F_op, lambda the equivalent damping there
    assert spec.elastic_force_n(d_op) / d_op == pytest.approx(500.0, rel=1e-12)
    assert spec.hc_damping_ns_per_m_pow_n_plus_1 * d_op**2.5 == pytest.approx(200.0, rel=1e-12)


def test_the_calibration_at_n_1_is_the_linear_calibration() -> None:
    for surface in (False, True):
        lattice = build_lattice((0.1, 0.08, 0.06), 0.025, palm_surface=surface)
        c_1, _ = hc.unit_squeeze_power(lattice, 1.0, on_table=False)
        assert c_1 == pytest.approx(unit_squeeze_stiffness_n_per_m(lattice), rel=1e-8)
        # the table holds the bottom layer in z: a stiffer squeeze, by a few per cent
        on_table, _ = hc.unit_squeeze_power(lattice, 1.0)
        assert 1.0 < on_table / c_1 < 1.10


@pytest.mark.parametrize("n", [1.5, 3.0])
def test_the_power_law_squeeze_is_homogeneous(n: float, monkeypatch: pytest.MonkeyPatch) -> None:
    lattice = build_lattice((0.1, 0.08, 0.06), 0.025, palm_surface=True)
    c_small, g_small = hc.unit_squeeze_power(lattice, n)
    monkeypatch.setattr(hc, "CALIBRATION_STRAIN", 0.2)
    c_big, g_big = hc.unit_squeeze_power(lattice, n)
    assert c_big == pytest.approx(c_small, rel=1e-8)
    assert g_big == pytest.approx(g_small, rel=1e-7)
    # and it is a stiffening law: the linear lattice's constant is not C_n
    assert abs(c_small / unit_squeeze_stiffness_n_per_m(lattice) - 1.0) > 0.5


def _law_error(sq: SqueezeSeries, spec: ObjectSpec, ramp_s: float) -> tuple[float, float]:
    """(largest relative miss of ``k dⁿ + λ_hc dⁿ ḋ`` over the loading samples from 10 % of the
    peak force, relative miss of ``k dⁿ`` at the end of the hold)."""
    n = spec.stiffness_exponent
    d = np.maximum(sq.compression_m, 0.0)
    rate = np.gradient(sq.compression_m, sq.time_s)
    law = spec.hc_stiffness_n_per_m_pow_n * d**n
    law = law + spec.hc_damping_ns_per_m_pow_n_plus_1 * d**n * rate
    f = sq.force_n
    loading = (sq.time_s <= ramp_s) & (f >= 0.1 * f.max())
    miss = float(np.max(np.abs(f[loading] - law[loading]) / law[loading]))
    end = abs(f[-1] - spec.hc_stiffness_n_per_m_pow_n * d[-1] ** n) / f[-1]
    return miss, float(end)


@pytest.mark.parametrize(("n", "damping"), [(1.5, 0.0), (2.0, 2.0), (3.0, 0.0), (3.0, 1.0)])
def test_the_simulated_squeeze_follows_the_fitted_law(n: float, damping: float) -> None:
    spec = _spec(n, damping)
    ramp = 2.0
    hold = 3.0 if damping else 0.2  # the damped object creeps to its static compression
    # on the table under gravity, as measure --sim squeezes: the weight is the resting state's
    # pre-stress, and the law holds from there
    sq = squeeze(spec, peak_force_n=7.5, ramp_s=ramp, hold_s=hold, settings=SMALL, gravity=True)
    miss, end = _law_error(sq, spec, ramp)
    assert miss <= 0.05, miss
    assert end <= 0.01, end
    # not a test that cannot fail: a linear spring of the same D misses by far more
    linear = spec.stiffness_n_per_m * sq.compression_m[-1]
    assert abs(linear / sq.force_n[-1] - 1.0) > 0.05


@pytest.mark.parametrize("n", [1.5, 3.0])
def test_a_floating_squeeze_is_softer_by_the_table_factor(n: float) -> None:
    # known truth: the calibration's two static solves (with and without the table); the
    # floating squeeze (no gravity, no table) reads k C_float / C_table
    spec = _spec(n)
    sq = squeeze(spec, peak_force_n=7.5, ramp_s=2.0, hold_s=0.2, settings=SMALL, gravity=False)
    el = hc.spec_elements(spec, SMALL)
    floating, _ = hc.unit_squeeze_power(el.lattice, n, on_table=False)
    d = sq.compression_m[-1]
    expected = spec.hc_stiffness_n_per_m_pow_n * floating / el.unit_force * d**n
    assert sq.force_n[-1] == pytest.approx(expected, rel=0.01)
    assert abs(el.unit_force / floating - 1.0) > 0.015  # the factor is not nothing


@pytest.mark.parametrize("n", [1.5, 3.0])
def test_a_resting_object_carries_its_weight_and_stays_put(n: float) -> None:
    from deformctl.sim.engine import build_model, run_model
    from deformctl.sim.step import record as K

    spec = _spec(n, 1.0)
    model = build_model(spec, SMALL, gripped=False, gravity=True, table=True)
    # it starts in its unloaded shape, the weight held by the elements' pre-stress
    assert np.array_equal(model.base_x, model.lattice.positions_m)
    assert np.abs(model.law.rest_force).max() > 0.0
    zeros = np.zeros(round(0.5 / SMALL.dt_s) + 1)
    q, _, rec = run_model(model, zeros, zeros)
    assert np.abs(q).max() < 1e-7  # m: no sag, no creep
    assert rec[-1, K.REC_TABLE_N] == pytest.approx(spec.weight_n, rel=1e-3)


def test_a_hard_squeeze_of_a_damped_object_stays_stable() -> None:
    # 5 F_op: the dampers are capped above DAMPING_CAP * DAMPING_REFERENCE F_op
    spec = _spec(3.0, 3.0)
    sq = squeeze(spec, peak_force_n=25.0, ramp_s=0.25, hold_s=1.0, settings=SMALL, gravity=True)
    assert np.all(np.isfinite(sq.compression_m))
    d_static = (25.0 / spec.hc_stiffness_n_per_m_pow_n) ** (1.0 / 3.0)
    assert float(sq.compression_m.max()) < 1.5 * d_static


#: population --grip --laws kv=1,hc=1,sls=1 -n 1500 --seed 1, object P1224 (W 1.28 N, D 30 N/cm
#: at F_w, n 2.92, d_op 0.02 cm): a squeeze to 1 % strain goes to 500 F_w (measure --sim's default
#: before it was capped at 3 F_w; --peak-force-n still can), where the law's tangent is 60 times
#: the one at F_w; built at F_w the step diverged ("non-finite state")
LIGHT_STIFF = P1224
#: population --grip --laws kv=1,hc=1,sls=1 -n 600 --seed 2, object P524: the linear solve of its
#: resting pre-stress (an 8 x 5 x 5 lattice with massless palm surfaces) stalled in the line search
RESTING_SOLVE = ObjectSpec(
    "P524",
    (19.572004569303626, 10.999909598556165, 10.317548848590075),
    6.8082023162896474,
    0.8094479615576795,
    53.80585036659134,
    0.04559956484017079,
    1.4410929780084056,
)


def test_a_light_stiff_object_squeezed_far_past_f_w_is_stable_and_follows_its_law() -> None:
    spec, paper = LIGHT_STIFF, sim_preset("paper").settings
    peak = spec.elastic_force_n(0.01 * spec.size_m[0])  # the law's force at 1 % strain
    assert peak > 400 * spec.operating_force_n
    reference = hc.implicit_reference_m(spec, peak)
    assert reference is not None  # the step is built above d_op, at the peak's tangent / room
    d_peak = (peak / spec.hc_stiffness_n_per_m_pow_n) ** (1.0 / spec.stiffness_exponent)
    tangent_ratio = (d_peak / reference) ** (spec.stiffness_exponent - 1.0)
    assert tangent_ratio == pytest.approx(hc.TANGENT_ROOM, rel=1e-12)
    sq = squeeze(spec, peak_force_n=peak, ramp_s=0.25, hold_s=1.0, settings=paper)
    assert np.all(np.isfinite(sq.compression_m))
    # known truth: the held compression is the law's static one, k dⁿ = F (within 1 %)
    held = spec.elastic_force_n(float(sq.compression_m[-1]))
    assert held == pytest.approx(peak, rel=0.01)
    # below the room nothing changes: the operating force's step, the same model
    assert hc.implicit_reference_m(spec, 1.5 * spec.operating_force_n) is None
    assert hc.implicit_reference_m(_spec(1.0), 1e6) is None  # a Kelvin object


def test_the_resting_solve_converges_and_carries_the_weight() -> None:
    from deformctl.sim.engine import build_model, run_model
    from deformctl.sim.step import record as K

    paper = sim_preset("paper").settings
    model = build_model(RESTING_SOLVE, paper, gripped=False, gravity=True, table=True)
    assert model.lattice.shape == (8, 5, 5)
    zeros = np.zeros(round(0.2 / paper.dt_s) + 1)
    q, _, rec = run_model(model, zeros, zeros)
    assert np.abs(q).max() < 1e-7  # m: the pre-stress balances gravity, no sag
    assert rec[-1, K.REC_TABLE_N] == pytest.approx(RESTING_SOLVE.weight_n, rel=1e-3)


def _n1_runs(spec: ObjectSpec, preset: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    p = sim_preset(preset)
    sq = squeeze(
        spec,
        peak_force_n=2.0,
        ramp_s=0.1,
        hold_s=0.1,
        settings=p.settings,
        noise_force_n=0.01,
        noise_position_m=1e-5,
        seed=7,
    )
    s = p.lift_attempt(spec, 2.5).series
    assert s is not None
    return (
        np.stack([sq.time_s, sq.force_n, sq.compression_m, sq.palm_left_x_m, sq.palm_right_x_m]),
        np.stack([s.time_s, s.palm_z_m, s.object_com_z_m, s.slip_m, s.normal_force_n]),
    )


def _linear_twin(near: ObjectSpec, preset: str) -> ObjectSpec:
    """The Kelvin–Voigt object whose lattice is the one of ``near`` (a Hunt–Crossley object at
    n → 1): k is stated at the squeeze on the table, a Kelvin–Voigt D at the floating squeeze, so
    the same lattice has ``D = k C_float / C_table``."""
    el = hc.spec_elements(near, sim_preset(preset).settings)
    floating, _ = hc.unit_squeeze_power(el.lattice, 1.0, on_table=False)
    d = near.stiffness_n_per_cm * floating / el.unit_force
    return dataclasses.replace(near, stiffness_n_per_cm=d, stiffness_exponent=1.0)


def _resting_strain(spec: ObjectSpec, preset: str) -> float:
    from deformctl.sim.engine import build_model

    model = build_model(spec, sim_preset(preset).settings, gripped=False)
    return float(np.abs(model.base_x - model.lattice.positions_m).max() / min(spec.size_m))


@pytest.mark.parametrize("preset", ["paper", "table"])
def test_n_1_is_the_linear_material_and_the_elastic_law_is_continuous_there(preset: str) -> None:
    """Without the material damper (λ = 0: both objects' dampers are the same floor), the
    Hunt–Crossley kernels just above n = 1 run the Kelvin–Voigt lattice of the same springs: the
    same squeeze and lift, each series from its start (the palms start where the resting shape
    puts the faces). Under small-strain kinematics (``paper``) within 1e-6 of each series' scale
    (measured 6e-9); with the exact spring geometry (``table``) the Hunt–Crossley object starts
    unloaded with its weight as a pre-stress and the Kelvin–Voigt one sagged, which differ by the
    resting strain's share of the geometry (measured 0.34 times the resting strain, 1.5 %).
    Compared in one run, never against digests from another machine."""
    near = ObjectSpec("seeded", (6.0, 5.0, 4.0), 1.5, 0.6, 4.0, 0.0, stiffness_exponent=1.0 + 1e-9)
    linear = _linear_twin(near, preset)
    assert near.hunt_crossley
    assert not linear.hunt_crossley
    assert abs(linear.stiffness_n_per_cm / near.stiffness_n_per_cm - 1.0) > 0.005  # the table
    tol = 1e-6 if preset == "paper" else 0.5 * _resting_strain(linear, preset)
    for got, want in zip(_n1_runs(near, preset), _n1_runs(linear, preset), strict=True):
        got, want = got - got[:, :1], want - want[:, :1]
        scale = np.abs(want).max(axis=1, keepdims=True)
        assert np.all(np.abs(got - want) <= tol * scale)


def test_near_n_1_the_damper_is_hunt_crossleys_not_kelvin_voigts() -> None:
    """The Hunt–Crossley damper ``λ_hc dⁿ ḋ`` at n → 1 is ``λ (d / d_op) ḋ``: λ at the operating
    compression only, and nothing at first contact. So the law is not continuous at n = 1 in its
    damping (docs/explanation/materials.md): under the same force ramp, below d_op, the
    Hunt–Crossley object closes faster than the Kelvin–Voigt one of the same springs (measured
    4.9×, 2.5× and 1.5× at 50, 100 and 200 ms)."""
    near = ObjectSpec("seeded", (6.0, 5.0, 4.0), 1.5, 0.6, 4.0, 1.2, stiffness_exponent=1.0 + 1e-9)
    (got, _), (want, _) = _n1_runs(near, "paper"), _n1_runs(_linear_twin(near, "paper"), "paper")
    assert np.array_equal(got[1], want[1])  # the same force
    for t_s in (0.05, 0.1, 0.2):
        i = int(np.searchsorted(want[0], t_s))
        assert want[2, i] < near.operating_compression_m
        assert got[2, i] > 1.3 * want[2, i]


# ---------------------------------------------------------------------------- the catalog column


@pytest.mark.parametrize(
    ("value", "words"),
    [
        ("0.5", "must be >= 1, got 0.5"),
        ("3.5", "must be <= 3, got 3.5"),
        ("stiff", "material_stiffness_exponent"),
        ("nan", "material_stiffness_exponent"),
        ("", "material_stiffness_exponent"),
    ],
)
@pytest.mark.parametrize("command", ["measure", "lift"])
def test_a_bad_exponent_is_one_data_error_naming_the_column(
    value: str,
    words: str,
    command: str,
    tmp_path: Path,
    catalog_row: dict[str, Any],
    write_catalog: Any,
) -> None:
    row = {**catalog_row, "material_stiffness_exponent": value}
    cat = write_catalog(tmp_path / "cat.csv", [row])
    out = tmp_path / ("sq.mcap" if command == "measure" else "lift.csv")
    result = runner.invoke(app, [command, "sim", str(cat), "-o", str(out)])
    assert result.exit_code == 65, result.output
    assert result.stderr.startswith("error: ")
    assert result.stderr.count("\n") == 1, result.stderr
    assert "material_stiffness_exponent" in result.stderr
    assert words in result.stderr
    assert not out.exists()


@pytest.mark.parametrize("value", [0.99, 3.01, math.nan, "two", None])
def test_the_row_parser_refuses_a_bad_exponent(value: object, catalog_row: dict[str, Any]) -> None:
    with pytest.raises(InputDataError, match="material_stiffness_exponent"):
        CatalogObject.from_row({**catalog_row, "material_stiffness_exponent": value})


def test_an_absent_exponent_is_linear_and_a_given_one_reaches_the_simulator(
    catalog_row: dict[str, Any],
) -> None:
    assert CatalogObject.from_row(catalog_row).to_sim_spec().stiffness_exponent == 1.0
    spec = CatalogObject.from_row({**catalog_row, "material_stiffness_exponent": 2.5}).to_sim_spec()
    assert spec.stiffness_exponent == 2.5
    assert spec.hunt_crossley
