"""deformctl.signals against known truth: SG smoothing of a polynomial and scipy's own filter,
the noise of a known white noise, the resampling of a jittered clock."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from deformctl.signals import noise_std, savgol, sg_smooth, sg_window_length, uniform_grid


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


@pytest.mark.parametrize("n", [7, 60, 1251])
def test_savgol_is_scipys_filter_without_its_import(n: int) -> None:
    # known truth: scipy.signal.savgol_filter (mode "interp", its default), the filter the
    # estimators used before; every window, order and derivative they use, ends included
    from scipy.signal import savgol_filter

    rng = np.random.default_rng(n)
    x = np.cumsum(rng.normal(size=n)) + 0.1 * rng.normal(size=n)
    for window in (5, 7, 21, 51, 201):
        for polyorder in (1, 2, 3):
            for deriv in range(polyorder + 1):
                if window > n:
                    continue
                want = savgol_filter(x, window, polyorder, deriv=deriv, delta=0.003)
                got = savgol(x, window, polyorder, deriv=deriv, delta=0.003)
                assert np.max(np.abs(got - want)) <= 1e-12 * np.max(np.abs(want))


@pytest.mark.parametrize(("window", "polyorder"), [(4, 2), (9, 9), (9, 2)])
def test_savgol_refuses_a_window_it_cannot_fit(window: int, polyorder: int) -> None:
    # an even window, an order as high as the window, a window longer than the 8 samples
    with pytest.raises(ValueError, match="odd window"):
        savgol(np.arange(8.0), window, polyorder)


def test_fitting_a_squeeze_never_imports_scipy_signal(tmp_path: Path) -> None:
    # scipy.signal costs a command 0.7 s of import: characterize (every law, the rupture and
    # relaxation checks) runs without it
    code = (
        "import sys\n"
        "import numpy as np\n"
        "from deformctl.characterize import characterize\n"
        "from deformctl.testing.kelvin_voigt import kelvin_voigt_response\n"
        "from deformctl.series import SqueezeSeries\n"
        "t = np.arange(0.0, 2.0, 1e-3)\n"
        "sq = []\n"
        "for i, peak in enumerate((3.0, 4.0, 5.0)):\n"
        "    f, d = kelvin_voigt_response(t, 20.0, 1.0, peak_force_n=peak,\n"
        "                                 profile='sine', duration_s=2.0)\n"
        "    sq.append(SqueezeSeries('a', i, t, f, d))\n"
        "row = characterize({'a': sq}, model='auto').iloc[0]\n"
        "assert abs(row['deformability_n_per_cm'] / 20.0 - 1) < 0.05, row\n"
        "print('scipy.signal' in sys.modules)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=tmp_path
    )
    assert out.stdout.strip() == "False", out.stderr
