"""Small numerical helpers shared by the estimators and the recording checks.

The estimators (:mod:`deformctl.characterize`) and the rupture and phase detection
(:mod:`deformctl.characterize.rupture`) work on one uniform time grid with Savitzky–Golay (SG)
smoothed compression ``d`` and rate ``d'``; these are the helpers both use, so a squeeze is
smoothed the same way wherever it is judged. Arrays are 1-D float64 ``[n]``.
"""

from __future__ import annotations

import math

import numpy as np

from deformctl.series import FloatArray

#: Relative spread of the sampling interval above which a series is resampled to a uniform grid.
UNIFORM_DT_RTOL = 1e-3


def noise_std(values: FloatArray) -> float:
    """Robust white-noise std of a densely sampled smooth signal, from its second differences.

    For a smooth signal the second difference is noise only: ``Δ²e`` has std ``√6 σ``; the
    median absolute deviation ignores the few corners.
    """
    dd = np.diff(values, 2)
    if dd.size == 0:
        return 0.0
    return float(np.median(np.abs(dd - np.median(dd))) / 0.6745 / math.sqrt(6.0))


def uniform_grid(
    time_s: FloatArray, *signals: FloatArray
) -> tuple[float, FloatArray, tuple[FloatArray, ...]]:
    """Return ``(dt_s, grid time [m], signals on the grid)``.

    A series whose sampling interval varies by more than :data:`UNIFORM_DT_RTOL` is linearly
    resampled onto ``t0 + k · median(dt)``; otherwise the samples are returned as they are.
    """
    dt = np.diff(time_s)
    dt_s = float(np.median(dt))
    if float(np.max(np.abs(dt - dt_s))) <= UNIFORM_DT_RTOL * dt_s:
        return dt_s, time_s, signals
    n = math.floor((time_s[-1] - time_s[0]) / dt_s) + 1
    grid = time_s[0] + dt_s * np.arange(n)
    return dt_s, grid, tuple(np.interp(grid, time_s, s) for s in signals)


def sg_window_length(window_s: float, dt_s: float, polyorder: int) -> int:
    """Odd SG window length in samples closest to ``window_s`` and at least ``polyorder + 2``."""
    n = round(window_s / dt_s)
    n = max(n, polyorder + 2)
    return n if n % 2 == 1 else n + 1


def sg_smooth(
    values: FloatArray, window_samples: int, polyorder: int, dt_s: float
) -> tuple[FloatArray, FloatArray]:
    """SG-smoothed ``values`` and their time derivative (per second), both ``[n]``.

    Requires ``n >= window_samples``.
    """
    from scipy.signal import savgol_filter  # deferred: ~1 s to import, only fits need it

    smooth = savgol_filter(values, window_samples, polyorder, deriv=0)
    rate = savgol_filter(values, window_samples, polyorder, deriv=1, delta=dt_s)
    return np.asarray(smooth, dtype=np.float64), np.asarray(rate, dtype=np.float64)
