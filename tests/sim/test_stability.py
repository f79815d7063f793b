"""Stability over the paper's range: no NaN, no explosion, nothing through a palm or the table."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from deformctl.sim import LiftProfile, ObjectSpec, SimSettings, lift_attempt, rigid_lift_force_n

WEIGHTS_N = (0.5, 10.0, 60.0)
STIFFNESS_N_PER_CM = (5.0, 25.0, 60.0)
DAMPING_NS_PER_CM = (0.0, 3.0, 15.0)
MU = (0.2, 0.5, 1.0)
PROFILE = LiftProfile(hold_s=0.3)
MAX_SPEED_M_S = 10.0  # palms move at 0.25 m/s; a 0.5 m free fall reaches 3 m/s
PENETRATION_TOL_M = 1e-6  # velocity-level contacts: round-off-level drift only
GRID = list(itertools.product(WEIGHTS_N, STIFFNESS_N_PER_CM, DAMPING_NS_PER_CM))


@pytest.mark.parametrize(("weight_n", "stiffness", "damping"), GRID)
def test_lift_attempts_stay_physical_over_the_paper_range(
    weight_n: float, stiffness: float, damping: float
) -> None:
    """Each (W, D, lambda) cell at every mu: one grip above and one below the rigid limit."""
    for i, mu in enumerate(MU):
        spec = ObjectSpec("grid", (15.0, 15.0, 10.0), weight_n, mu, stiffness, damping)
        factor = (1.3, 0.9, 1.3)[i] if (weight_n + stiffness) % 2 else (0.9, 1.3, 0.9)[i]
        outcome = lift_attempt(spec, factor * rigid_lift_force_n(spec, PROFILE), profile=PROFILE)
        d = outcome.details
        assert outcome.series is not None
        assert np.all(np.isfinite(outcome.series.object_com_z_m))
        assert d["max_speed_m_s"] < MAX_SPEED_M_S  # type: ignore[operator]
        assert d["min_particle_z_m"] > -PENETRATION_TOL_M  # type: ignore[operator]
        assert d["max_palm_penetration_m"] < PENETRATION_TOL_M  # type: ignore[operator]


# the corners of the grid on a fine lattice (11 particles per longest side: the iterative solver)
CORNERS = list(itertools.product((0.5, 60.0), (5.0, 60.0), (0.0, 15.0)))


@pytest.mark.slow
@pytest.mark.parametrize(("weight_n", "stiffness", "damping"), CORNERS)
def test_lift_attempts_stay_physical_at_the_corners_on_a_fine_lattice(
    weight_n: float, stiffness: float, damping: float
) -> None:
    """The softest / stiffest, lightest / heaviest, undamped / most damped objects at mu 0.2 and
    1.0, one grip below and one above the rigid limit each."""
    fine = SimSettings(particles_per_side=11)
    for mu, factor in ((0.2, 0.9), (1.0, 1.3)):
        spec = ObjectSpec("corner", (15.0, 15.0, 10.0), weight_n, mu, stiffness, damping)
        grip = factor * rigid_lift_force_n(spec, PROFILE)
        outcome = lift_attempt(spec, grip, profile=PROFILE, settings=fine)
        d = outcome.details
        assert outcome.series is not None
        assert np.all(np.isfinite(outcome.series.object_com_z_m))
        assert d["max_speed_m_s"] < MAX_SPEED_M_S  # type: ignore[operator]
        assert d["min_particle_z_m"] > -PENETRATION_TOL_M  # type: ignore[operator]
        assert d["max_palm_penetration_m"] < PENETRATION_TOL_M  # type: ignore[operator]
