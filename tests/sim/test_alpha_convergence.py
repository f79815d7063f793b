"""Refining alpha twice (5 -> 9 -> 17 particles along the longest side): the measured squeeze
stiffness and the lifting force move less at each refinement."""

from __future__ import annotations

import pytest

from deformctl.sim import ObjectSpec, SimSettings, f_w_n, lift_attempt, squeeze

from ._helpers import min_lift_force_n

CUBE = ObjectSpec("cube", (10.0, 10.0, 10.0), 5.0, 0.5, 30.0, 1.0)


def _stiffness_n_per_m(settings: SimSettings) -> float:
    peak = CUBE.stiffness_n_per_m * 0.01 * CUBE.size_m[0]
    series = squeeze(CUBE, peak_force_n=peak, ramp_s=0.2, hold_s=1.0, settings=settings)
    assert series.palm_left_x_m is not None
    assert series.palm_right_x_m is not None
    gap = series.palm_right_x_m - series.palm_left_x_m
    return float(series.force_n[-1] / (gap[0] - gap[-1]))


@pytest.mark.slow
def test_squeeze_stiffness_and_lifting_force_converge_as_alpha_is_halved() -> None:
    """At 5 and 9 particles L_f is bisected; at 17 two lift attempts decide the claim: a grip
    one last step (``|L_f(9) - L_f(5)|``) below L_f(9) slips and one that far above lifts, so
    L_f(17) moved less than that step. (Bisecting at 17 too costs four times as much.)"""
    fw = f_w_n(CUBE)
    d = [_stiffness_n_per_m(SimSettings(particles_per_side=n)) for n in (5, 9, 17)]
    lf = [
        min_lift_force_n(CUBE, 1.17 * fw, 1.24 * fw, rel_tol=2e-4, settings=settings)
        for settings in (SimSettings(particles_per_side=5), SimSettings(particles_per_side=9))
    ]
    step = abs(lf[1] - lf[0])
    fine = SimSettings(particles_per_side=17)
    below = lift_attempt(CUBE, lf[1] - step, settings=fine)
    above = lift_attempt(CUBE, lf[1] + step, settings=fine)
    print(f"D measured / catalog: {[x / CUBE.stiffness_n_per_m for x in d]}; L_f N: {lf}")
    assert abs(d[2] - d[1]) < abs(d[1] - d[0])
    assert not below.lifted, "L_f(17) is below L_f(9) by more than L_f(9) moved from L_f(5)"
    assert above.lifted, "L_f(17) is above L_f(9) by more than L_f(9) moved from L_f(5)"
    assert abs(d[2] / CUBE.stiffness_n_per_m - 1) < 0.05
