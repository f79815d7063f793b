"""Catalog rows as typed objects: parsing, the lift rule, the simulator's object."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import pytest

from deformctl.catalog import CatalogObject, rigid_grip_force_n
from deformctl.errors import InputDataError
from deformctl.units import GRAVITY_M_S2


def test_from_catalog_row_reads_every_column(sponge_row: dict[str, Any]) -> None:
    spec = CatalogObject.from_row(sponge_row).to_sim_spec()
    assert spec.size_cm == (17.8, 19.1, 9.2)
    assert spec.stiffness_n_per_m == pytest.approx(4918.0)
    assert spec.damping_ns_per_m == pytest.approx(647.0)
    assert spec.mass_kg == pytest.approx(0.7 / GRAVITY_M_S2)


@pytest.mark.parametrize(
    ("column", "value", "message"),
    [
        ("material_stiffness_n_per_cm", math.nan, "material_stiffness_n_per_cm is missing"),
        ("material_damping_ns_per_cm", None, "material_damping_ns_per_cm is not a number"),
        ("friction_mu", 0.0, r"friction_mu = 0 is outside its physical bounds \[0.01, 3\]"),
        ("friction_mu", -0.3, "friction_mu = -0.3 is outside its physical bounds"),
        ("weight_n", 0.0, "weight_n = 0 is outside its physical bounds"),
    ],
)
def test_bad_rows_raise_one_line_input_errors(
    column: str, value: object, message: str, sponge_row: dict[str, Any]
) -> None:
    row = dict(sponge_row, **{column: value})
    with pytest.raises(InputDataError, match=message) as err:
        CatalogObject.from_row(row).to_sim_spec()
    assert "\n" not in str(err.value)


def test_missing_column_is_named(sponge_row: dict[str, Any]) -> None:
    row = {k: v for k, v in sponge_row.items() if k != "material_damping_ns_per_cm"}
    with pytest.raises(InputDataError, match="missing column 'material_damping_ns_per_cm'"):
        CatalogObject.from_row(row).to_sim_spec()


def test_a_row_is_parsed_once_into_typed_values_and_kept_as_read(
    sponge_row: dict[str, Any],
) -> None:
    obj = CatalogObject.from_row({**sponge_row, "name": "sponge", "weight_n": "0.7"})
    assert (obj.object_id, obj.weight_n, obj.size_cm) == ("sponge", 0.7, (17.8, 19.1, 9.2))
    assert obj["name"] == "sponge"  # extra columns stay readable
    assert obj.f_w_n() == pytest.approx(rigid_grip_force_n(0.7, 0.5)) == pytest.approx(0.7)
    real = CatalogObject.from_row({**sponge_row, "material_stiffness_n_per_cm": math.nan,
                                   "material_damping_ns_per_cm": math.nan})  # fmt: skip
    assert not real.has_material
    assert real.record()["material_stiffness_n_per_cm"] is None
    with pytest.raises(InputDataError, match="'sponge' has no material values"):
        real.to_sim_spec()


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"object_id": ""}, "catalog row without 'object_id'"),
        ({"size_y_cm": "wide"}, "object 'sponge': size_y_cm is not a number: 'wide'"),
        ({"weight_n": math.inf}, "object 'sponge': weight_n is missing or not finite"),
    ],
)
def test_parse_errors_name_the_object_and_the_column(
    change: dict[str, object], message: str, sponge_row: dict[str, Any]
) -> None:
    with pytest.raises(InputDataError, match=message):
        CatalogObject.from_row({**sponge_row, **change})


def test_lifting_needs_positive_friction(sponge_row: dict[str, Any]) -> None:
    with pytest.raises(InputDataError, match="friction_mu = 0 is outside its physical bounds"):
        CatalogObject.from_row(
            {**sponge_row, "friction_mu": 0.0}
        )  # F_w = W / (2 mu) would be infinite
    outside = "object 'sponge': friction_mu = 0 is outside its physical bounds"
    with pytest.raises(InputDataError, match=outside):  # a built object is checked too
        dataclasses.replace(CatalogObject.from_row(sponge_row), friction_mu=0.0)
