"""ObjectSpec from catalog rows, and the closed-form helpers."""

from __future__ import annotations

import math

import pytest

from deformctl.errors import InputDataError
from deformctl.sim import LiftProfile, ObjectSpec, f_w_n, rigid_lift_force_n
from deformctl.units import GRAVITY_M_S2

ROW = {
    "object_id": "sponge",
    "size_x_cm": 17.8,
    "size_y_cm": 19.1,
    "size_z_cm": 9.2,
    "weight_n": 0.7,
    "friction_mu": 0.5,
    "material_stiffness_n_per_cm": 49.18,
    "material_damping_ns_per_cm": 6.47,
}


def test_from_catalog_row_reads_every_column() -> None:
    spec = ObjectSpec.from_catalog_row(ROW)
    assert spec.size_cm == (17.8, 19.1, 9.2)
    assert spec.stiffness_n_per_m == pytest.approx(4918.0)
    assert spec.damping_ns_per_m == pytest.approx(647.0)
    assert spec.mass_kg == pytest.approx(0.7 / GRAVITY_M_S2)


@pytest.mark.parametrize(
    ("column", "value", "message"),
    [
        ("material_stiffness_n_per_cm", math.nan, "material_stiffness_n_per_cm is missing"),
        ("material_damping_ns_per_cm", None, "material_damping_ns_per_cm is not a number"),
        ("friction_mu", 0.0, "friction_mu must be finite and > 0"),
        ("friction_mu", -0.3, "friction_mu must be finite and > 0"),
        ("weight_n", 0.0, "weight_n must be finite and > 0"),
    ],
)
def test_bad_rows_raise_one_line_input_errors(column: str, value: object, message: str) -> None:
    row = dict(ROW, **{column: value})
    with pytest.raises(InputDataError, match=message) as err:
        ObjectSpec.from_catalog_row(row)
    assert "\n" not in str(err.value)


def test_missing_column_is_named() -> None:
    row = {k: v for k, v in ROW.items() if k != "material_damping_ns_per_cm"}
    with pytest.raises(InputDataError, match="missing column 'material_damping_ns_per_cm'"):
        ObjectSpec.from_catalog_row(row)


def test_closed_form_helpers() -> None:
    spec = ObjectSpec.from_catalog_row(ROW)
    assert f_w_n(spec) == pytest.approx(0.7)
    profile = LiftProfile(accel_m_s2=3.0)
    expected = 0.7 / GRAVITY_M_S2 * (GRAVITY_M_S2 + 3.0) / 1.0
    assert rigid_lift_force_n(spec, profile) == pytest.approx(expected)
