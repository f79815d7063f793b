"""Closed forms of the grip: F_w, the damping ratio and the natural frequency in SI."""

from __future__ import annotations

import math

import numpy as np
import pytest

from deformctl.physics import damping_ratio, natural_frequency_rad_s, rigid_grip_force_n


def test_closed_forms_against_hand_computed_values() -> None:
    # W = 9.80665 N: m = 1 kg; D = 1 N/cm = 100 N/m; λ = 0.2 N·s/cm = 20 N·s/m
    assert rigid_grip_force_n(9.80665, 0.5) == pytest.approx(9.80665)
    assert natural_frequency_rad_s(9.80665, 1.0) == pytest.approx(10.0)
    assert damping_ratio(9.80665, 1.0, 0.2) == pytest.approx(20.0 / (2.0 * math.sqrt(100.0)))


def test_groups_work_elementwise() -> None:
    w = np.array([1.0, 4.0])
    omega = natural_frequency_rad_s(w, np.array([10.0, 10.0]))
    assert omega[0] / omega[1] == pytest.approx(2.0)  # ω ∝ 1/√m
    zeta = damping_ratio(w, np.array([10.0, 10.0]), np.array([1.0, 1.0]))
    assert zeta[0] / zeta[1] == pytest.approx(2.0)  # ζ ∝ 1/√m
