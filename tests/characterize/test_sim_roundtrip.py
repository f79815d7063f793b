"""Squeeze a simulated Hunt–Crossley object, fit it with ``--model hc``, and get
back the law the catalog gave the simulator (k and n within 3 %, D at F_w within 3 %)."""

from __future__ import annotations

import dataclasses

import pytest

from deformctl.characterize import characterize
from deformctl.presets import sim_preset
from deformctl.sim import ObjectSpec, squeeze_many
from deformctl.units import CM

#: the paper preset on a small lattice (5 particles per side: seconds, not minutes)
SMALL = dataclasses.replace(sim_preset("paper").settings, particles_per_side=5)


@pytest.mark.parametrize(("n", "damping"), [(1.5, 3.0), (2.0, 2.0), (3.0, 1.0)])
def test_squeeze_then_characterize_recovers_k_and_n(n: float, damping: float) -> None:
    # W = 5 N, mu = 0.5: F_w = 5 N; D = 5 N/cm and lambda at F_w (d_op = 1 cm)
    spec = ObjectSpec("hc", (10.0, 10.0, 10.0), 5.0, 0.5, 5.0, damping, n)
    squeezes = squeeze_many(
        spec,
        3,
        peak_force_n=1.5 * spec.operating_force_n,
        ramp_s=0.25,
        hold_s=1.0,
        settings=SMALL,
        gravity=True,  # on the table, as measure --sim squeezes
        noise_force_n=0.005,
        noise_position_m=5e-6,
        seed=3,
    )
    row = characterize(
        {"hc": squeezes}, model="hc", objects={"hc": {"weight_n": 5.0, "friction_mu": 0.5}}
    ).iloc[0]
    k_true = spec.hc_stiffness_n_per_m_pow_n * CM**n  # N/cmⁿ
    assert row["quality"] == "ok"
    assert row["hc_exponent"] == pytest.approx(n, rel=0.03)
    assert row["hc_stiffness_n_per_cm_pow_n"] == pytest.approx(k_true, rel=0.03)
    # the catalog's own numbers come back: D and lambda at F_w
    assert row["operating_force_n"] == pytest.approx(5.0)
    assert row["deformability_n_per_cm"] == pytest.approx(5.0, rel=0.03)
    assert row["damping_ns_per_cm"] == pytest.approx(damping, rel=0.05)
