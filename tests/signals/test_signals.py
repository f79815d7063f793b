"""deformctl.signals against known truth: SG smoothing of a polynomial, the noise of a known
white noise, the resampling of a jittered clock."""

from __future__ import annotations

import numpy as np
import pytest

from deformctl.signals import noise_std, sg_smooth, sg_window_length, uniform_grid


@pytest.mark.parametrize("polyorder", [2, 3])
def test_sg_is_exact_on_a_polynomial_of_its_order(polyorder: int) -> None:
    dt_s = 1e-3
    t = np.arange(400) * dt_s
    coeffs = [0.5, -2.0, 3.0, 7.0][: polyorder + 1]  # c0 + c1 t + c2 t² (+ c3 t³)
    values = sum(c * t**k for k, c in enumerate(coeffs))
    rate = sum(k * c * t ** (k - 1) for k, c in enumerate(coeffs) if k)
    smooth, d_dt = sg_smooth(values, 31, polyorder, dt_s)
    np.testing.assert_allclose(smooth, values, rtol=0, atol=1e-12)
    np.testing.assert_allclose(d_dt, rate, rtol=0, atol=1e-9)  # per second, edges included
    assert smooth.dtype == d_dt.dtype == np.float64


def test_sg_of_a_lower_order_does_not_follow_a_cubic() -> None:
    t = np.arange(400) * 1e-3
    smooth, _ = sg_smooth(t**3, 101, 1, 1e-3)
    assert np.max(np.abs(smooth - t**3)) > 1e-4  # the exactness above is not for free


def test_window_length_is_odd_and_long_enough() -> None:
    assert sg_window_length(0.1, 0.01, 3) == 11  # 10 samples -> the next odd
    assert sg_window_length(0.11, 0.01, 3) == 11
    assert sg_window_length(0.001, 0.01, 3) == 5  # at least polyorder + 2, made odd
    assert sg_window_length(0.001, 0.01, 2) == 5


def test_noise_std_finds_a_known_white_noise_on_a_smooth_signal() -> None:
    rng = np.random.default_rng(7)
    t = np.linspace(0.0, 2.0, 20_000)
    signal = 3.0 * np.sin(2 * np.pi * t)
    assert noise_std(signal) < 1e-6
    noisy = signal + rng.normal(0.0, 0.01, t.size)
    assert noise_std(noisy) == pytest.approx(0.01, rel=0.05)
    assert noise_std(np.array([1.0, 2.0])) == 0.0  # no second difference


def test_uniform_grid_keeps_a_uniform_clock_and_resamples_a_jittered_one() -> None:
    t = np.arange(100) * 0.01
    y = 2.0 * t + 1.0
    dt_s, grid, (same,) = uniform_grid(t, y)
    assert dt_s == pytest.approx(0.01)
    assert grid is t
    assert same is y
    jittered = t + np.random.default_rng(1).uniform(-2e-3, 2e-3, t.size)
    jittered[0], jittered[-1] = 0.0, 0.99
    dt_s, grid, (line,) = uniform_grid(jittered, 2.0 * jittered + 1.0)
    np.testing.assert_allclose(np.diff(grid), dt_s, rtol=1e-9)
    assert grid[0] == 0.0
    np.testing.assert_allclose(line, 2.0 * grid + 1.0, rtol=1e-12)  # linear: interpolation exact
