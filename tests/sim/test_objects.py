"""The closed-form helpers of the simulator's object.

Catalog parsing is tested in tests/catalog/test_catalog.py.
"""

from __future__ import annotations

import pytest

from deformctl.catalog import CatalogObject, rigid_grip_force_n
from deformctl.sim import LiftProfile, rigid_lift_force_n
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


def test_closed_form_helpers() -> None:
    spec = CatalogObject.from_row(ROW).to_sim_spec()
    assert rigid_grip_force_n(spec.weight_n, spec.friction_mu) == pytest.approx(0.7)
    profile = LiftProfile(accel_m_s2=3.0)
    expected = 0.7 / GRAVITY_M_S2 * (GRAVITY_M_S2 + 3.0) / 1.0
    assert rigid_lift_force_n(spec, profile) == pytest.approx(expected)
