"""The simulator's standard linear solid (deformctl.sim.sls, deformctl.sim.step.maxwell).

Known truth: ``characterize --model sls`` fitted to the simulated squeezes gives back the
catalog's D, k2 and τ (within 3 %, on the table as ``measure --sim`` squeezes); the energy of a
damped Zener lattice never rises; an arm with τ = inf is a spring, so the object is the Kelvin
object of stiffness D + k2 (to round-off), and one with k2 = 0 is the Kelvin object itself.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from deformctl.catalog import CatalogObject
from deformctl.characterize import characterize
from deformctl.errors import InputDataError
from deformctl.presets import sim_preset
from deformctl.sim import ObjectSpec, squeeze, squeeze_many
from deformctl.sim.engine import build_model, positions_m, run_model
from deformctl.sim.sls import arm_energy_j, unloaded

#: the paper preset on a small lattice (5 particles per side: the tests stay fast)
SMALL = dataclasses.replace(sim_preset("paper").settings, particles_per_side=5)


def _spec(k2: float, tau: float, damping: float = 0.0, d: float = 5.0) -> ObjectSpec:
    # W = 5 N, mu = 0.5: F_w = 5 N; D = 5 N/cm: 1 cm of static compression at F_w
    return ObjectSpec(
        "sls", (10.0, 10.0, 10.0), 5.0, 0.5, d, damping,
        arm_stiffness_n_per_cm=k2, relaxation_time_s=tau,
    )  # fmt: skip


@pytest.mark.parametrize(("k2", "tau"), [(5.0, 0.3), (1.5, 0.5), (15.0, 1.0)])
def test_squeeze_then_characterize_recovers_the_zener_solid(k2: float, tau: float) -> None:
    spec = _spec(k2, tau)
    squeezes = squeeze_many(
        spec, 3, peak_force_n=7.5, ramp_s=0.25, hold_s=1.0, settings=SMALL, gravity=True,
        noise_force_n=0.005, noise_position_m=5e-6, seed=3,
    )  # fmt: skip
    row = characterize(
        {"sls": squeezes}, model="sls", objects={"sls": {"weight_n": 5.0, "friction_mu": 0.5}}
    ).iloc[0]
    assert row["quality"] == "ok"
    assert row["sls_stiffness_n_per_cm"] == pytest.approx(5.0, rel=0.03)
    assert row["sls_arm_stiffness_n_per_cm"] == pytest.approx(k2, rel=0.03)
    assert row["sls_relaxation_time_s"] == pytest.approx(tau, rel=0.03)
    # not a test that cannot fail: the Kelvin lattice of the same D relaxes not at all
    kv = squeeze(_spec(0.0, tau), peak_force_n=7.5, ramp_s=0.25, hold_s=1.0, settings=SMALL)
    sls = squeezes[-1]
    assert abs(sls.compression_m[250] / kv.compression_m[250] - 1.0) > 0.1


def _energy(model: object, q: np.ndarray, v: np.ndarray, arm: object) -> float:
    lat = model.lattice  # type: ignore[attr-defined]
    x = positions_m(model, q)  # type: ignore[arg-type]
    e = lat.edges
    stretch = np.einsum("ij,ij->i", x[e[:, 1]] - x[e[:, 0]], lat.direction) - lat.rest_length_m
    springs = 0.5 * float(np.sum(model.stiffness_n_per_m * stretch**2))  # type: ignore[attr-defined]
    kinetic = 0.5 * float(np.sum(model.dof_mass_kg * v**2))  # type: ignore[attr-defined]
    return kinetic + springs + arm_energy_j(arm)  # type: ignore[arg-type]


@pytest.mark.parametrize("integrator", ["bdf2", "euler"])
def test_the_energy_of_a_damped_zener_lattice_never_rises(integrator: str) -> None:
    # a floating object (no gravity, table or palms) released from a seeded random deformation:
    # kinetic + springs + arms' springs is all the energy there is, and the arms only dissipate
    settings = dataclasses.replace(
        SMALL, integrator=integrator, min_shear_retardation_s=0.0, particles_per_side=4
    )
    spec = _spec(8.0, 0.02)
    model = build_model(spec, settings, gripped=False, gravity=False, table=False, resting=False)
    q0 = np.random.default_rng(7).normal(0.0, 2e-4, model.n_dof)
    energies = []
    for n in range(0, 160, 4):
        arm = unloaded(model.arm)
        zeros = np.zeros(n + 1)
        q, v, _ = run_model(model, zeros, zeros, q=q0, arm=arm) if n else (q0, 0 * q0, None)
        energies.append(_energy(model, q, v, arm))
    e = np.asarray(energies)
    assert np.all(np.diff(e) <= 1e-12 * e[0]), np.diff(e).max() / e[0]
    assert e[-1] < 0.5 * e[0]  # and it does dissipate: not a test that cannot fail
    # the undamped lattice (no arms, no dampers) keeps its energy within BDF2's/Euler's loss
    # far longer: the loss above is the arms'
    kv = build_model(_spec(0.0, 0.02), settings, gripped=False, gravity=False, table=False,
                     resting=False)  # fmt: skip
    zeros = np.zeros(157)
    q, v, _ = run_model(kv, zeros, zeros, q=q0)
    assert _energy(kv, q, v, kv.arm) > e[-1]


def test_an_arm_that_never_relaxes_is_a_spring_beside_the_kelvin_one() -> None:
    # τ = inf: the arm is a spring k2 (its force k_a s exactly); with no damper floor the object
    # is the Kelvin object of stiffness D + k2 and the same λ, to round-off (the direct solver:
    # the iterative one stops at its tolerance, not at round-off)
    settings = dataclasses.replace(SMALL, min_shear_retardation_s=0.0, solver="direct")
    sls = squeeze(_spec(3.0, math.inf, damping=1.0), peak_force_n=6.0, ramp_s=0.2, hold_s=0.3,
                  settings=settings, gravity=False)  # fmt: skip
    kv = squeeze(_spec(0.0, math.inf, damping=1.0, d=8.0), peak_force_n=6.0, ramp_s=0.2,
                 hold_s=0.3, settings=settings, gravity=False)  # fmt: skip
    scale = float(np.abs(kv.compression_m).max())
    assert np.abs(sls.compression_m - kv.compression_m).max() <= 1e-9 * scale
    # and a relaxing arm is not that (the comparison can fail)
    relaxing = squeeze(_spec(3.0, 0.05, damping=1.0), peak_force_n=6.0, ramp_s=0.2, hold_s=0.3,
                       settings=settings, gravity=False)  # fmt: skip
    assert np.abs(relaxing.compression_m - kv.compression_m).max() > 0.05 * scale


def test_no_arm_is_the_kelvin_object_bit_for_bit() -> None:
    kv = squeeze(_spec(0.0, math.inf, damping=1.0), peak_force_n=6.0, ramp_s=0.2, hold_s=0.3,
                 settings=SMALL)  # fmt: skip
    zero_arm = squeeze(_spec(0.0, 0.5, damping=1.0), peak_force_n=6.0, ramp_s=0.2, hold_s=0.3,
                       settings=SMALL)  # fmt: skip
    assert kv.compression_m.tobytes() == zero_arm.compression_m.tobytes()


def test_the_catalog_carries_the_arm(catalog_row: dict[str, object]) -> None:
    row = {**catalog_row, "material_arm_stiffness_n_per_cm": 4.0, "material_relaxation_time_s": 0.5}
    spec = CatalogObject.from_row(row).to_sim_spec()
    assert spec.standard_linear_solid
    assert (spec.arm_stiffness_n_per_cm, spec.relaxation_time_s) == (4.0, 0.5)
    # no arm: the relaxation time may be left empty
    plain = CatalogObject.from_row({**row, "material_arm_stiffness_n_per_cm": 0.0,
                                    "material_relaxation_time_s": float("nan")})  # fmt: skip
    assert not plain.to_sim_spec().standard_linear_solid
    # an arm needs its relaxation time; a material is not both stiffening and relaxing
    with pytest.raises(InputDataError, match="material_relaxation_time_s"):
        CatalogObject.from_row({**row, "material_relaxation_time_s": float("nan")})
    with pytest.raises(InputDataError, match="not both"):
        CatalogObject.from_row({**row, "material_stiffness_exponent": 2.0}).to_sim_spec()
    with pytest.raises(InputDataError, match="material_relaxation_time_s"):
        CatalogObject.from_row({**row, "material_relaxation_time_s": 0.0})


def test_a_standard_linear_solid_fit_is_lifted_as_that_solid() -> None:
    import pandas as pd

    from deformctl.lift.objects import catalog_from_coefficients

    common = {"size_x_cm": 6.0, "size_y_cm": 6.0, "size_z_cm": 4.0, "friction_mu": 0.5,
              "weight_n": 2.0, "deformability_n_per_cm": 9.0, "damping_ns_per_cm": 2.0,
              "sls_stiffness_n_per_cm": 9.0, "sls_arm_stiffness_n_per_cm": 4.0,
              "sls_relaxation_time_s": 0.5}  # fmt: skip
    table = pd.DataFrame([{"object_id": "dough", "model": "sls", **common},
                          {"object_id": "foam", "model": "kv", **common}])  # fmt: skip
    catalog = catalog_from_coefficients(table)
    dough, foam = (CatalogObject.from_row(catalog.iloc[i].to_dict()) for i in range(2))
    spec = dough.to_sim_spec()
    assert (spec.stiffness_n_per_cm, spec.damping_ns_per_cm) == (9.0, 0.0)
    assert (spec.arm_stiffness_n_per_cm, spec.relaxation_time_s) == (4.0, 0.5)
    # the Kelvin–Voigt object keeps its D and λ, and has no arm
    kv = foam.to_sim_spec()
    assert (kv.stiffness_n_per_cm, kv.damping_ns_per_cm) == (9.0, 2.0)
    assert not kv.standard_linear_solid
    # a table without a standard linear solid gains no columns
    assert "material_arm_stiffness_n_per_cm" not in catalog_from_coefficients(table.iloc[[1]])
