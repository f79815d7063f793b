"""Lift attempts: rigid limit, friction cone (stick without creep, slip outside), quasi-static
limit, determinism."""

from __future__ import annotations

import numpy as np
import pytest

from deformctl.sim import (
    LiftProfile,
    ObjectSpec,
    SimSettings,
    SlipCriterion,
    f_w_n,
    lift_attempt,
    rigid_lift_force_n,
)

from ._helpers import min_lift_force_n

PROFILE = LiftProfile()  # default S-curve, a_max = 2 m/s²
# the default lattice (5 particles along the longest side: a two-level V-cycle) and a fine one
# (9: three levels, level 1 swept as a block stencil, as on every finer lattice; 11 costs twice
# as much for the same solver path)
DEFAULT = SimSettings()
FINE = SimSettings(particles_per_side=9)
LATTICES = [
    pytest.param(DEFAULT, id="default"),
    pytest.param(FINE, id="fine", marks=pytest.mark.slow),
]


def stiff_object(mu: float) -> ObjectSpec:
    """A 'very stiff' object: 100x the stiffest paper material, 2.5 ms retardation time."""
    return ObjectSpec("stiff", (10.0, 10.0, 10.0), 5.0, mu, 5000.0, 12.5)


@pytest.mark.parametrize("settings", LATTICES)
@pytest.mark.parametrize("mu", [0.3, 0.8])
def test_rigid_limit_min_lifting_force_is_m_g_plus_a_over_2mu(
    mu: float, settings: SimSettings
) -> None:
    spec = stiff_object(mu)
    expected = rigid_lift_force_n(spec, PROFILE)
    found = min_lift_force_n(
        spec, 0.85 * expected, 1.15 * expected, rel_tol=0.002, settings=settings
    )
    assert abs(found / expected - 1) < 0.03


@pytest.mark.parametrize("settings", LATTICES)
def test_friction_cone_holds_inside_without_creep_and_slips_outside(settings: SimSettings) -> None:
    spec = stiff_object(0.5)
    profile = LiftProfile(hold_s=2.0)
    limit = rigid_lift_force_n(spec, profile)
    held = lift_attempt(spec, 1.05 * limit, profile=profile, settings=settings)
    assert held.lifted
    # stick is exact: the contacts do not slide at all, so the simulator's slip tolerance may be
    # 0 (quantities.SIM_SLIP_TOLERANCE_M), unlike a rig's frames, whose tracking jitters
    assert held.slip_m == 0.0
    assert held.series is not None
    # no creep during the 2 s hold: the object's height is constant to round-off
    hold = held.series.time_s >= held.series.time_s[-1] - 2.0
    com = held.series.object_com_z_m[hold]
    assert np.ptp(com) < 1e-6
    # the palms carry the weight through friction while held
    assert held.series.friction_force_n[-1] == pytest.approx(spec.weight_n, rel=1e-3)
    dropped = lift_attempt(spec, 0.95 * limit, profile=profile, settings=settings)
    assert not dropped.lifted
    assert dropped.slip_m > 0.5e-3
    # while sliding the palms carry exactly the kinetic friction 2 mu N
    assert dropped.series is not None
    assert dropped.details["peak_friction_n"] == pytest.approx(2 * 0.5 * 0.95 * limit, rel=1e-9)


@pytest.mark.parametrize("settings", LATTICES)
def test_far_below_f_w_the_object_stays_on_the_table(settings: SimSettings) -> None:
    spec = stiff_object(0.5)
    outcome = lift_attempt(spec, 0.5 * f_w_n(spec), settings=settings)
    assert not outcome.lifted
    assert outcome.details["off_table"] is False
    assert outcome.slip_m == pytest.approx(PROFILE.rise_m(spec), rel=0.02)


@pytest.mark.parametrize("settings", LATTICES)
def test_quasi_static_lift_of_a_soft_object_needs_only_f_w(settings: SimSettings) -> None:
    """Lifting force -> W/(2 mu) as the lift acceleration -> 0 (soft, lightly damped object)."""
    spec = ObjectSpec("soft", (15.0, 15.0, 10.0), 10.0, 0.5, 5.0, 0.3)
    fw = f_w_n(spec)
    forces = []
    for accel, speed, jerk in ((2.0, 0.25, 0.05), (0.5, 0.1, 0.1), (0.1, 0.05, 0.1)):
        profile = LiftProfile(accel_m_s2=accel, speed_m_s=speed, jerk_time_s=jerk)
        forces.append(
            min_lift_force_n(
                spec, 0.95 * fw, 1.5 * fw, rel_tol=0.003, profile=profile, settings=settings
            )
        )
    assert forces[0] > forces[1] > forces[2]
    assert abs(forces[-1] / fw - 1) < 0.05


@pytest.mark.parametrize("settings", LATTICES)
def test_shortfall_measure_includes_elastic_sag(settings: SimSettings) -> None:
    spec = ObjectSpec("soft", (15.0, 15.0, 10.0), 10.0, 0.5, 5.0, 0.3)
    grip = 1.5 * rigid_lift_force_n(spec, PROFILE)
    contact = lift_attempt(spec, grip, settings=settings)
    shortfall = lift_attempt(
        spec, grip, criterion=SlipCriterion(measure="shortfall"), settings=settings
    )
    assert contact.lifted
    assert contact.slip_m < 1e-9
    assert shortfall.slip_m == pytest.approx(contact.details["shortfall_m"])
    assert shortfall.slip_m > 1e-3  # the soft body hangs lower than it rested


# the sponge's flat lattice needs 11 particles along its longest side for three levels
@pytest.mark.parametrize(
    "settings",
    [
        pytest.param(DEFAULT, id="default"),
        pytest.param(SimSettings(particles_per_side=11), id="fine", marks=pytest.mark.slow),
    ],
)
def test_lift_attempt_is_bit_identical_for_the_same_inputs(settings: SimSettings) -> None:
    spec = ObjectSpec("sponge", (17.8, 19.1, 9.2), 0.7, 0.5, 49.18, 6.47)
    a = lift_attempt(spec, 0.9, settings=settings)
    b = lift_attempt(spec, 0.9, settings=settings)
    assert a.series is not None
    assert b.series is not None
    for name in ("time_s", "palm_z_m", "object_com_z_m", "slip_m", "friction_force_n"):
        assert getattr(a.series, name).tobytes() == getattr(b.series, name).tobytes()
    assert a.lifted == b.lifted
