"""Small numerical helpers shared by the estimators and the recording checks.

The estimators (:mod:`deformctl.characterize`) and the rupture and phase detection
(:mod:`deformctl.squeeze.rupture`) work on one uniform time grid with Savitzky–Golay (SG)
smoothed compression ``d`` and rate ``d'``; these are the helpers both use, so a squeeze is
smoothed the same way wherever it is judged. Arrays are 1-D float64 ``[n]``.
"""

from __future__ import annotations

import math
from functools import lru_cache

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


def quarter_window_length(window_samples: int) -> int:
    """The short cubic Savitzky–Golay window of the estimators: a quarter of ``window_samples``,
    at least 5 samples, odd (the damping terms' end points, the corners' rate)."""
    length = max(5, window_samples // 4)
    return length if length % 2 == 1 else length + 1


@lru_cache(maxsize=64)
def _sg_coefficients(window: int, polyorder: int, deriv: int, delta: float) -> FloatArray:
    """The convolution weights of the Savitzky–Golay filter: the least-squares polynomial of
    ``polyorder`` over ``window`` samples, its ``deriv``-th derivative at the centre (per
    ``delta``), reversed for :func:`numpy.convolve`."""
    half = window // 2
    x = np.arange(half, -half - 1, -1, dtype=np.float64)  # reversed: convolution weights
    vander = x[None, :] ** np.arange(polyorder + 1)[:, None]
    target = np.zeros(polyorder + 1)
    target[deriv] = math.factorial(deriv) / delta**deriv
    solution, *_ = np.linalg.lstsq(vander, target, rcond=None)
    coef = np.asarray(solution, dtype=np.float64)
    coef.setflags(write=False)
    return coef


def savgol(
    values: FloatArray, window: int, polyorder: int, *, deriv: int = 0, delta: float = 1.0
) -> FloatArray:
    """Savitzky–Golay filter of ``values`` ``[n]``: what ``scipy.signal.savgol_filter`` returns
    with ``mode="interp"`` (its default), without importing ``scipy.signal`` (0.7 s of a
    command's start; tests/signals/test_signals.py compares the two to 1e-12).

    Each sample at least ``window // 2`` from the ends is the centre of a least-squares
    polynomial of ``polyorder`` over ``window`` samples (its ``deriv``-th derivative per
    ``delta``); the first and last ``window // 2`` come from the polynomial fitted to the first
    and last ``window`` samples, evaluated where they lie (one-sided at the ends).

    Requires an odd ``window`` with ``polyorder < window <= n``.
    """
    v = np.asarray(values, dtype=np.float64)
    n, half = v.shape[0], window // 2
    if window % 2 != 1 or not polyorder < window <= n:
        raise ValueError(f"need an odd window in ({polyorder}, {n}], got {window}")
    out = np.convolve(v, _sg_coefficients(window, polyorder, deriv, float(delta)), mode="same")
    at = np.arange(window, dtype=np.float64)
    for lo, where in ((0, slice(0, half)), (n - window, slice(window - half, window))):
        poly = np.asarray(np.polyfit(at, v[lo : lo + window], polyorder), dtype=np.float64)
        if deriv:
            poly = np.asarray(np.polyder(poly, deriv), dtype=np.float64)
        out[lo + where.start : lo + where.stop] = np.polyval(poly, at[where]) / delta**deriv
    return out


def sg_smooth(
    values: FloatArray, window_samples: int, polyorder: int, dt_s: float
) -> tuple[FloatArray, FloatArray]:
    """SG-smoothed ``values`` and their time derivative (per second), both ``[n]``
    (:func:`savgol`).

    Requires ``n >= window_samples``.
    """
    smooth = savgol(values, window_samples, polyorder)
    rate = savgol(values, window_samples, polyorder, deriv=1, delta=dt_s)
    return smooth, rate
