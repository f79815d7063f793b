"""measure --sim's default peak force (deformctl.measure.sim.default_peak_force_n)."""

from __future__ import annotations

import pytest

from deformctl.measure.sim import HC_MIN_PEAK_OVER_F_W, default_peak_force_n
from deformctl.sim import ObjectSpec


def test_the_strain_rule_of_a_kelvin_object_is_d_strain_width() -> None:
    spec = ObjectSpec("kv", (8.0, 8.0, 6.0), 2.0, 0.5, 4.0, 0.8)
    assert default_peak_force_n(spec, 0.01) == 400.0 * 0.01 * 0.08


def test_a_hunt_crossley_object_is_squeezed_past_its_operating_force() -> None:
    # F_w = 2 N, D = 4 N/cm at F_w: d_w = 0.5 cm; at 1 % of 8 cm the law gives 2 (0.16)^2.2 N
    spec = ObjectSpec("hc", (8.0, 8.0, 6.0), 2.0, 0.5, 4.0, 0.8, 2.2)
    assert spec.elastic_force_n(0.0008) == pytest.approx(2.0 * 0.16**2.2, rel=1e-12)
    assert default_peak_force_n(spec, 0.01) == pytest.approx(HC_MIN_PEAK_OVER_F_W * 2.0)
    # a strain whose force is above that is the rule's own
    assert default_peak_force_n(spec, 0.1) == pytest.approx(2.0 * 1.6**2.2, rel=1e-12)
