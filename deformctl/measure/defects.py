"""Defects of a recording, reported rather than fitted over: gaps, coarse force, a lagging force.

``measure`` looks for each of these in a rig recording before it cuts it into squeezes; a defect
found is one warning line on stderr and a flag in the squeeze log's object row
(``recording_flags``, with the numbers in ``recording_defects``), which ``characterize`` adds to
the object's ``quality``, so the coefficients of a doubtful recording are never ``ok``.

================ ==================================================================================
``logging_gap``  an interval longer than :data:`GAP_INTERVALS` × the median sample interval (its
                 length and time are named); the smoothing then spans time with no samples
``coarse_force`` the force's resolution (its smallest step between distinct values) is coarser
                 than :data:`COARSE_FORCE_FRAC` of the peak: each smoothing window sees a few
                 levels, and the rate the damping rests on is mostly quantisation
``force_lag``    the force lags the position by :data:`LAG_FLAG_S` or more (and two samples), by
                 cross-correlation of their rates on the loading ramp (:func:`estimate_lag`); a
                 lag τ makes a Kelvin–Voigt fit find λ − D·τ, negative for a stiff object.
                 ``--lag-s auto`` shifts the estimated lag out before the fit
================ ==================================================================================

Timestamps that repeat are merged (their samples averaged) and reported; time that goes back is
an error naming the row.

**The lag and the damping.** On a ramp the force of a Kelvin–Voigt object leads its compression
by about λ/D (``D d + λ ḋ ≈ D d(t + λ/D)``) while a sensor or controller latency τ delays it, so
the cross-correlation finds ``τ − λ/D``: a lower bound on the latency when λ ≥ 0. Shifting it out
removes the negative damping the latency causes and leaves λ near zero; it cannot give λ back
(one ramp cannot tell a latency from a damping). The estimate is only made when both rates vary
along the ramp (a constant-rate test has no rate to align: ``not identifiable``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from deformctl.series import FloatArray
from deformctl.signals import sg_smooth, sg_window_length
from deformctl.squeeze.flags import COARSE_FORCE, FORCE_LAG, LOGGING_GAP

#: ``logging_gap``: an interval longer than this many median intervals.
GAP_INTERVALS = 5.0
#: ``coarse_force``: a resolution coarser than this fraction of the peak force (0.1 N on a 2 N
#: peak is 5 %: 20 levels up the ramp).
COARSE_FORCE_FRAC = 0.02
#: ``force_lag`` from this lag on, s (a lag τ moves λ by −D·τ: −0.4 N·s/cm at D = 20 N/cm) ...
LAG_FLAG_S = 0.02
#: ... and at least this many sample intervals.
LAG_FLAG_SAMPLES = 2.0
#: The lag is searched within ± this, s, and within a quarter of the loading ramp.
LAG_MAX_S = 1.0
#: The rates must correlate at least this well at the best lag for the lag to be reported.
LAG_MIN_CORRELATION = 0.8
#: ... and each rate's standard deviation must be at least this fraction of its mean magnitude
#: along the ramp (a constant-rate test cannot be aligned).
LAG_MIN_RATE_VARIATION = 0.1
#: ... and the correlation at the ends of the search must be lower than at the lag by at least
#: this (rates that change too slowly to be aligned within the search correlate everywhere).
LAG_MIN_CONTRAST = 0.05
#: Smoothing window for the rates, s (the same filter on both keeps their relative delay).
LAG_WINDOW_S = 0.1
#: The ramp is decimated to at most this many samples for the search.
LAG_MAX_SAMPLES = 20_000


@dataclass(frozen=True)
class Defect:
    """One defect of a recording: its flag, one line naming it, and its numbers."""

    flag: str
    text: str
    numbers: dict[str, float] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """What the squeeze log records."""
        return {"flag": self.flag, "text": self.text, **self.numbers}


@dataclass(frozen=True)
class LagEstimate:
    """The lag of the force behind the position on the loading ramp.

    Attributes:
        lag_s: the lag, s (positive: the force follows the position); None when it cannot
            be estimated (``reason`` says why).
        correlation: the rates' correlation at that lag.
        reason: why there is no estimate ('' when there is one).
    """

    lag_s: float | None
    correlation: float = math.nan
    reason: str = ""

    def describe(self) -> str:
        """``0.17 s (rate correlation 0.98 on the loading ramp)`` or the reason."""
        if self.lag_s is None:
            return f"not identifiable ({self.reason})"
        return (
            f"{self.lag_s:.3g} s (force-rate vs compression-rate correlation "
            f"{self.correlation:.2f} on the loading ramp)"
        )

    def as_dict(self) -> dict[str, Any]:
        """What the squeeze log records."""
        return {"lag_s": self.lag_s, "correlation": self.correlation, "reason": self.reason}


def merge_duplicate_times(
    time_s: FloatArray, *signals: FloatArray
) -> tuple[FloatArray, tuple[FloatArray, ...], int]:
    """Average the samples that share a timestamp (time must not decrease).

    Returns:
        The distinct times, each signal averaged over them, and how many samples were merged
        away (0: the input arrays, unchanged).
    """
    if time_s.shape[0] < 2 or not np.any(np.diff(time_s) == 0):
        return time_s, signals, 0
    times, start, counts = np.unique(time_s, return_index=True, return_counts=True)
    merged = tuple(np.add.reduceat(s, start) / counts for s in signals)
    return times, merged, int(time_s.shape[0] - times.shape[0])


def first_backwards(time_s: FloatArray) -> int | None:
    """The first sample whose time is before the previous one's, or None."""
    back = np.flatnonzero(np.diff(time_s) < 0)
    return int(back[0]) + 1 if back.size else None


def logging_gaps(time_s: FloatArray) -> Defect | None:
    """``logging_gap`` when an interval exceeds :data:`GAP_INTERVALS` × the median one."""
    dt = np.diff(time_s)
    if dt.size < 2:
        return None
    median = float(np.median(dt))
    if not median > 0:
        return None
    gaps = np.flatnonzero(dt > GAP_INTERVALS * median)
    if not gaps.size:
        return None
    longest = int(gaps[np.argmax(dt[gaps])])
    length = float(dt[longest])
    at = float(time_s[longest] - time_s[0])
    more = f" ({gaps.size} gaps)" if gaps.size > 1 else ""
    return Defect(
        LOGGING_GAP,
        f"{LOGGING_GAP}: no sample for {length:.3g} s from {at:.4g} s ({length / median:.0f}× the "
        f"median interval {median:.3g} s){more}",
        {"gap_s": length, "gap_at_s": at, "gaps": float(gaps.size)},
    )


def force_resolution(force_n: FloatArray) -> float:
    """The force's smallest step between distinct values, N (0 for a constant force).

    Values closer than 1e-9 of the largest magnitude are one value (float noise of a unit
    conversion).
    """
    scale = float(np.max(np.abs(force_n))) if force_n.size else 0.0
    if not scale > 0:
        return 0.0
    tol = 1e-9 * scale
    levels = np.unique(np.round(force_n / tol))
    if levels.size < 2:
        return 0.0
    return float(np.min(np.diff(levels))) * tol


def coarse_force(force_n: FloatArray) -> Defect | None:
    """``coarse_force`` when the resolution exceeds :data:`COARSE_FORCE_FRAC` of the peak."""
    peak = float(np.max(force_n)) if force_n.size else 0.0
    if not peak > 0:
        return None
    step = force_resolution(force_n)
    if step <= COARSE_FORCE_FRAC * peak:
        return None
    levels = round(peak / step)
    return Defect(
        COARSE_FORCE,
        f"{COARSE_FORCE}: the force moves in steps of {step:.3g} N, {100 * step / peak:.1f} % of "
        f"its {peak:.3g} N peak ({levels} levels; more than {100 * COARSE_FORCE_FRAC:g} %)",
        {"force_resolution_n": step, "peak_force_n": peak},
    )


def _uniform(time_s: FloatArray, *signals: FloatArray) -> tuple[float, list[FloatArray]]:
    dt = float(np.median(np.diff(time_s)))
    n = math.floor((time_s[-1] - time_s[0]) / dt) + 1
    q = max(1, math.ceil(n / LAG_MAX_SAMPLES))
    grid = time_s[0] + dt * q * np.arange(math.ceil(n / q))
    return dt * q, [np.interp(grid, time_s, s) for s in signals]


def estimate_lag(time_s: FloatArray, force_n: FloatArray, compression_m: FloatArray) -> LagEstimate:
    """The lag of the force behind the compression, by cross-correlating their rates on the
    loading ramp (the samples up to the peak force; see the module docstring)."""
    if time_s.shape[0] < 8:
        return LagEstimate(None, reason="too few samples")
    peak = int(np.argmax(force_n))
    if peak < 8 or time_s[peak] - time_s[0] <= 0:
        return LagEstimate(None, reason="no loading ramp before the peak force")
    dt, (f, d) = _uniform(time_s[: peak + 1], force_n[: peak + 1], compression_m[: peak + 1])
    n = f.shape[0]
    wl = sg_window_length(LAG_WINDOW_S, dt, 2)
    if n < 4 * wl:
        return LagEstimate(None, reason="loading ramp shorter than 4 smoothing windows")
    _, vf = sg_smooth(f, wl, 2, dt)
    _, vd = sg_smooth(d, wl, 2, dt)
    core = slice(wl, n - wl)  # the filter's edges are extrapolations
    vf, vd = vf[core], vd[core]
    for name, v in (("compression", vd), ("force", vf)):
        mean = abs(float(np.mean(v)))
        if not float(np.std(v)) >= LAG_MIN_RATE_VARIATION * mean or mean == 0:
            return LagEstimate(
                None, reason=f"the {name} rate is nearly constant on the loading ramp"
            )
    k_max = max(2, min(int(LAG_MAX_S / dt), vf.shape[0] // 4))
    lags = np.arange(-k_max, k_max + 1)
    corr = np.array([_pearson(vf, vd, int(k)) for k in lags])
    best = int(np.nanargmax(corr)) if np.any(np.isfinite(corr)) else -1
    if best < 0 or not corr[best] >= LAG_MIN_CORRELATION:
        r = float(corr[best]) if best >= 0 else math.nan
        return LagEstimate(None, r, f"the rates correlate at most {r:.2f} < {LAG_MIN_CORRELATION}")
    if best in (0, lags.shape[0] - 1):
        return LagEstimate(
            None, float(corr[best]), f"the best lag is at the search limit ±{k_max * dt:.3g} s"
        )
    contrast = float(corr[best]) - float(np.nanmax(corr[[0, -1]]))
    if not contrast >= LAG_MIN_CONTRAST:
        return LagEstimate(
            None,
            float(corr[best]),
            f"the rates change too slowly to be aligned within ±{k_max * dt:.3g} s (correlation "
            f"{float(corr[best]):.3f} at best, {float(np.nanmax(corr[[0, -1]])):.3f} at the ends)",
        )
    y0, y1, y2 = corr[best - 1], corr[best], corr[best + 1]
    denom = y0 - 2 * y1 + y2
    frac = 0.5 * (y0 - y2) / denom if denom < 0 else 0.0
    return LagEstimate(float((lags[best] + frac) * dt), float(y1))


def _pearson(vf: FloatArray, vd: FloatArray, k: int) -> float:
    """Correlation of ``vf[i]`` with ``vd[i − k]`` over their overlap."""
    a, b = (vf[k:], vd[: vd.shape[0] - k]) if k >= 0 else (vf[: vf.shape[0] + k], vd[-k:])
    if a.shape[0] < 3:
        return math.nan
    a = a - a.mean()
    b = b - b.mean()
    den = math.sqrt(float(a @ a) * float(b @ b))
    return float(a @ b) / den if den > 0 else math.nan


def lag_defect(estimate: LagEstimate, sample_interval_s: float) -> Defect | None:
    """``force_lag`` when the estimated lag reaches :data:`LAG_FLAG_S` and two samples."""
    lag = estimate.lag_s
    if lag is None or lag < max(LAG_FLAG_S, LAG_FLAG_SAMPLES * sample_interval_s):
        return None
    return Defect(
        FORCE_LAG,
        f"{FORCE_LAG}: the force lags the position by {estimate.describe()}; a Kelvin–Voigt fit "
        "finds λ − D·lag (pass --lag-s auto to shift it out)",
        {"lag_s": lag, "correlation": estimate.correlation},
    )


def shift_force(
    time_s: FloatArray, force_n: FloatArray, position: FloatArray, lag_s: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Move the force ``lag_s`` earlier (it lagged the position by that): ``f'(t) = f(t + lag)``.

    The samples whose shifted time falls outside the recording are dropped.
    """
    if lag_s == 0:
        return time_s, force_n, position
    keep = (time_s + lag_s >= time_s[0]) & (time_s + lag_s <= time_s[-1])
    t = time_s[keep]
    return t, np.interp(t + lag_s, time_s, force_n), position[keep]
