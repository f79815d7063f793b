"""lift's objects from a coefficients table: a Hunt–Crossley fit becomes a Hunt–Crossley material
whose D and λ are restated at F_w."""

from __future__ import annotations

import math

import pandas as pd
import pytest

from deformctl.catalog import CatalogObject
from deformctl.lift.objects import catalog_from_coefficients


def _table() -> pd.DataFrame:
    common = {"size_x_cm": 6.0, "size_y_cm": 6.0, "size_z_cm": 4.0, "friction_mu": 0.5}
    return pd.DataFrame(
        [
            # hc, fitted with D stated at 10 N (not F_w): k = 2 N/cm^2.5, lambda_hc 0.3
            {"object_id": "gel", "weight_n": 4.0, "model": "hc", "deformability_n_per_cm": 9.9,
             "damping_ns_per_cm": 1.1, "hc_exponent": 2.5, "hc_stiffness_n_per_cm_pow_n": 2.0,
             "hc_damping_ns_per_cm_pow_n_plus_1": 0.3, **common},
            {"object_id": "foam", "weight_n": 2.0, "model": "kv", "deformability_n_per_cm": 20.0,
             "damping_ns_per_cm": 3.0, "hc_exponent": 1.7, "hc_stiffness_n_per_cm_pow_n": 8.0,
             "hc_damping_ns_per_cm_pow_n_plus_1": 0.1, **common},
        ]
    )  # fmt: skip


def test_a_hunt_crossley_fit_is_lifted_as_its_law_stated_at_f_w() -> None:
    catalog = catalog_from_coefficients(_table())
    gel, foam = (catalog.iloc[i] for i in range(2))
    f_w = 4.0 / (2 * 0.5)
    d_w = (f_w / 2.0) ** (1 / 2.5)  # cm, on k d^n
    assert gel["material_stiffness_exponent"] == 2.5
    assert gel["material_stiffness_n_per_cm"] == pytest.approx(f_w / d_w, rel=1e-12)
    assert gel["material_damping_ns_per_cm"] == pytest.approx(0.3 * d_w**2.5, rel=1e-12)
    # what a start model predicts from stays the table's own D and lambda
    assert gel["deformability_n_per_cm"] == 9.9
    # the Kelvin–Voigt object is untouched
    assert foam["material_stiffness_exponent"] == 1.0
    assert foam["material_stiffness_n_per_cm"] == 20.0
    assert foam["material_damping_ns_per_cm"] == 3.0
    # and the simulator's spec gives back k and lambda_hc (N/m^n from N/cm^n)
    spec = CatalogObject.from_row(gel.to_dict()).to_sim_spec()
    assert spec.hc_stiffness_n_per_m_pow_n == pytest.approx(2.0 / 0.01**2.5, rel=1e-12)
    assert spec.hc_damping_ns_per_m_pow_n_plus_1 == pytest.approx(0.3 / 0.01**3.5, rel=1e-12)


def test_a_table_without_hunt_crossley_objects_has_no_exponent_column() -> None:
    table = _table().iloc[[1]].reset_index(drop=True)
    assert "material_stiffness_exponent" not in catalog_from_coefficients(table).columns
    # an unfitted lambda stays NaN (the simulator then asks for one, as before)
    table = _table()
    table.loc[0, "hc_damping_ns_per_cm_pow_n_plus_1"] = math.nan
    assert math.isnan(catalog_from_coefficients(table).iloc[0]["material_damping_ns_per_cm"])
