"""measure --sim's default peak force (deformctl.measure.sim.default_peak_force_n), and a light,
stiff Hunt–Crossley object's D at F_w through measure --sim and characterize's defaults."""

from __future__ import annotations

import dataclasses

import pandas as pd
import pytest

from deformctl.measure.sim import (
    HC_MAX_PEAK_OVER_F_W,
    HC_MIN_PEAK_OVER_F_W,
    default_peak_force_n,
    simulate_squeezes,
)
from deformctl.series import SqueezeSeries
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


# ------------------------------------------- light, stiff Hunt–Crossley objects: the grip's range

#: population --grip --laws kv=1,hc=1,sls=1 -n 1500 --seed 1: two light, stiff Hunt–Crossley
#: objects whose 1 % strain is hundreds of F_w (catalog D and λ are stated at F_w: the truth)
LIGHT_STIFF_ROWS = [
    {
        "object_id": "P1224",  # W 1.28 N, F_w 0.65 N, n 2.92: 1 % strain is 500 F_w
        "size_x_cm": 18.266157255740307,
        "size_y_cm": 18.86999851884091,
        "size_z_cm": 13.783762496895122,
        "weight_n": 1.2823604904060122,
        "friction_mu": 0.9791332774328168,
        "material_stiffness_n_per_cm": 30.04844412194788,
        "material_damping_ns_per_cm": 0.03169091107723927,
        "material_stiffness_exponent": 2.923045909747441,
    },
    {
        "object_id": "P0689",  # F_w 0.63 N, n 2.53: 1 % strain is 680 F_w
        "size_x_cm": 16.271419110834366,
        "size_y_cm": 16.158690266125046,
        "size_z_cm": 18.55419467039555,
        "weight_n": 0.6274196740265708,
        "friction_mu": 0.5005312295200937,
        "material_stiffness_n_per_cm": 50.85482390325884,
        "material_damping_ns_per_cm": 2.3637912648544845,
        "material_stiffness_exponent": 2.5279567267268206,
    },
]


def _light_stiff_spec(row: dict[str, object]) -> ObjectSpec:
    from deformctl.catalog import catalog_objects

    return catalog_objects(pd.DataFrame([row]))[0].to_sim_spec()


def test_a_light_stiff_hunt_crossley_object_is_squeezed_over_the_grip_range_only() -> None:
    for row in LIGHT_STIFF_ROWS:
        spec = _light_stiff_spec(row)
        f_w = spec.operating_force_n
        assert spec.elastic_force_n(0.01 * spec.size_m[0]) > 400 * f_w  # the strain rule's force
        assert default_peak_force_n(spec, 0.01) == pytest.approx(HC_MAX_PEAK_OVER_F_W * f_w)
    # a Kelvin object of the same row keeps the strain rule (its D does not depend on the force)
    kv = dataclasses.replace(_light_stiff_spec(LIGHT_STIFF_ROWS[0]), stiffness_exponent=1.0)
    assert default_peak_force_n(kv, 0.01) == pytest.approx(3004.844412194788 * 0.01 * 0.18266, 1e-4)


def test_measure_sim_then_characterize_defaults_give_d_at_f_w_of_a_light_stiff_object() -> None:
    # known truth: the catalog's D at F_w. Before the cap the default squeeze (500 F_w) read
    # P1224's D as 664 N/cm (truth 30)
    from deformctl.characterize import characterize

    catalog = pd.DataFrame(LIGHT_STIFF_ROWS)
    objects, squeezes = simulate_squeezes(catalog, scene_hz=0.0)
    by_id: dict[str, list[SqueezeSeries]] = {}
    for s in squeezes:
        by_id.setdefault(s.object_id, []).append(s)
    table = characterize(by_id, objects={o["object_id"]: o for o in objects})
    for row, truth in zip(table.to_dict("records"), LIGHT_STIFF_ROWS, strict=True):
        assert row["model"] == "hc"
        assert "below_squeezes" not in row["quality"]
        assert row["operating_force_n"] == pytest.approx(
            truth["weight_n"] / (2 * truth["friction_mu"])
        )
        d_true = truth["material_stiffness_n_per_cm"]
        assert row["deformability_n_per_cm"] == pytest.approx(d_true, rel=0.03)
