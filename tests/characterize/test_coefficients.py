"""The ``below_squeezes`` flag (deformctl.characterize.coefficients): a stiffening law's D stated
where few loading samples are at or below its force is flagged, against known truth (a simulated
light, stiff Hunt–Crossley object whose D at F_w comes out wrong there), not for a linear law."""

from __future__ import annotations

import dataclasses

import pytest

from deformctl.characterize import characterize
from deformctl.characterize.quality import BELOW_SQUEEZES, parse_quality
from deformctl.presets import sim_preset
from deformctl.sim import ObjectSpec, squeeze_many
from tests._helpers.hard_objects import P1224


def _fit(spec: ObjectSpec, peak_force_n: float) -> dict[str, object]:
    squeezes = squeeze_many(
        spec,
        3,
        peak_force_n=peak_force_n,
        ramp_s=0.25,
        hold_s=1.0,
        settings=sim_preset("paper").settings,
        gravity=True,
    )
    objects = {spec.object_id: {"weight_n": spec.weight_n, "friction_mu": spec.friction_mu}}
    row: dict[str, object] = characterize({spec.object_id: squeezes}, objects=objects).iloc[0]
    return row


def test_a_stiffening_law_stated_far_below_its_squeezes_is_flagged() -> None:
    f_w = P1224.operating_force_n
    # 46 F_w: about 3 % of the loading samples are at or below F_w
    row = _fit(P1224, 30.0)
    assert row["model"] == "hc"
    assert BELOW_SQUEEZES in parse_quality(row["quality"])
    # the flag is deserved: D at F_w is far off the catalog's 30.05 N/cm there
    assert float(row["deformability_n_per_cm"]) > 2 * 30.04844412194788  # type: ignore[arg-type]
    # squeezed over the grip's range (3 F_w) the same object is not flagged, and D is right
    row = _fit(P1224, 3.0 * f_w)
    assert BELOW_SQUEEZES not in parse_quality(row["quality"])
    assert row["deformability_n_per_cm"] == pytest.approx(30.04844412194788, rel=0.03)


def test_a_linear_law_far_below_its_squeezes_is_not_flagged() -> None:
    # a Kelvin–Voigt object's D does not depend on the force: its law holds at F_w
    kv = dataclasses.replace(P1224, stiffness_exponent=1.0, damping_ns_per_cm=0.5)
    row = _fit(kv, 30.0)
    assert row["model"] == "kv"
    assert BELOW_SQUEEZES not in parse_quality(row["quality"])
    assert row["deformability_n_per_cm"] == pytest.approx(30.04844412194788, rel=0.03)
