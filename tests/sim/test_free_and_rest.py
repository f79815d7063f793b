"""A free object: free fall at g, rest on the table with reaction W, energy never rising."""

from __future__ import annotations

import numpy as np
import pytest

from deformctl.sim import ObjectSpec, SimSettings, free_run
from deformctl.sim.engine import build_model, positions_m, run_model
from deformctl.units import GRAVITY_M_S2

SPONGE = ObjectSpec("sponge", (17.8, 19.1, 9.2), 0.7, 0.5, 49.18, 6.47)
# the default lattice (direct solver) and a fine one (11 particles per longest side: iterative)
LATTICES = [
    pytest.param(SimSettings(), id="default"),
    pytest.param(SimSettings(particles_per_side=11), id="fine", marks=pytest.mark.slow),
]


@pytest.mark.parametrize("settings", LATTICES)
def test_free_fall_accelerates_at_g_before_contact(settings: SimSettings) -> None:
    run = free_run(SPONGE, duration_s=0.3, drop_height_m=1.0, settings=settings)
    assert run.min_z_m.min() > 0.0  # never touched the table
    assert np.all(run.table_force_n == 0.0)
    coeffs = np.polyfit(run.time_s, run.com_m[:, 2], 2)
    accel = 2.0 * coeffs[0]
    assert abs(accel + GRAVITY_M_S2) < 0.005 * GRAVITY_M_S2


@pytest.mark.parametrize("settings", LATTICES)
def test_object_settled_on_table_gets_its_weight_and_stays_put(settings: SimSettings) -> None:
    run = free_run(SPONGE, duration_s=3.0, settings=settings)
    settled = run.time_s >= 1.0
    reaction = run.table_force_n[settled].mean()
    assert abs(reaction - SPONGE.weight_n) < 0.01 * SPONGE.weight_n
    com = run.com_m[settled]
    drift = np.linalg.norm(com - com[0], axis=1).max()
    assert drift < 1e-4
    assert run.min_z_m.min() > -1e-9


@pytest.mark.parametrize("settings", LATTICES)
def test_damped_lattice_energy_never_rises_without_external_work(settings: SimSettings) -> None:
    """Gravity off, no table, no palms: kinetic + spring energy is non-increasing."""
    spec = ObjectSpec("cube", (10.0, 10.0, 10.0), 5.0, 0.5, 20.0, 0.5)
    model = build_model(spec, settings, gripped=False, gravity=False, table=False)
    rng = np.random.default_rng(7)
    q = np.zeros(model.n_dof)
    v = rng.normal(0.0, 0.05, model.n_dof)
    lat = model.lattice

    def energy(q: np.ndarray, v: np.ndarray) -> float:
        x = positions_m(model, q)
        length = np.linalg.norm(x[lat.edges[:, 1]] - x[lat.edges[:, 0]], axis=1)
        spring = 0.5 * np.sum(model.stiffness_n_per_m * (length - lat.rest_length_m) ** 2)
        return float(0.5 * model.particle_mass_kg * np.sum(v**2) + spring)

    energies = [energy(q, v)]
    zeros = np.zeros(2)
    for _ in range(300):
        q, v, _ = run_model(model, zeros, zeros, q=q, v=v)
        energies.append(energy(q, v))
    e = np.array(energies)
    assert np.all(np.diff(e) <= 1e-12 * e[0])
    assert e[-1] < 0.5 * e[0]  # and the dampers really dissipate
