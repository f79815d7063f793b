"""Convergence: halving dt barely moves the lifting force; halving alpha barely moves the squeeze
stiffness measured from the force felt and the palm positions."""

from __future__ import annotations

from deformctl.sim import ObjectSpec, SimSettings, f_w_n, squeeze

from ._helpers import min_lift_force_n

# Table I "water" bag: undamped, the most step-sensitive dynamics in the paper's objects
WATER = ObjectSpec("water", (10.8, 11.4, 8.9), 4.9, 0.5, 10.52, 0.0)
SPONGE = ObjectSpec("sponge", (17.8, 19.1, 9.2), 0.7, 0.5, 49.18, 6.47)


def test_halving_the_time_step_changes_the_lifting_force_by_less_than_2_percent() -> None:
    fw = f_w_n(WATER)
    coarse = SimSettings()
    fine = SimSettings(dt_s=coarse.dt_s / 2)
    l_coarse = min_lift_force_n(WATER, fw, 2 * fw, rel_tol=0.002, settings=coarse)
    l_fine = min_lift_force_n(WATER, fw, 2 * fw, rel_tol=0.002, settings=fine)
    assert abs(l_coarse / l_fine - 1) < 0.02


def _measured_stiffness_n_per_m(settings: SimSettings) -> float:
    series = squeeze(SPONGE, peak_force_n=8.0, ramp_s=0.2, hold_s=1.0, settings=settings)
    assert series.palm_left_x_m is not None
    assert series.palm_right_x_m is not None
    gap = series.palm_right_x_m - series.palm_left_x_m
    return float(series.force_n[-1] / (gap[0] - gap[-1]))


def test_halving_alpha_changes_the_measured_squeeze_stiffness_by_less_than_5_percent() -> None:
    default = SimSettings()
    alpha_cm = default.alpha_m(SPONGE) * 100
    d_coarse = _measured_stiffness_n_per_m(default)
    d_fine = _measured_stiffness_n_per_m(SimSettings(alpha_cm=alpha_cm / 2))
    assert abs(d_fine / d_coarse - 1) < 0.05
    assert abs(d_fine / SPONGE.stiffness_n_per_m - 1) < 0.05
