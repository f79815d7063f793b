"""What a grip needs from a fit: the stiffness at its force, how it changes, and whether the
damping can be told at all.

* :func:`operating_force_n`: the force the deformability is stated at (``--at-force-n``, else the
  object's F_w = W/(2μ) when its weight and friction are known, else the median loading force).
* :func:`loading_stiffness`: the force–compression slope of the loading samples, with the
  fitted law's rate-dependent force taken out, fitted by a straight line in each of
  :data:`STIFFNESS_BINS` equal slices of the loading compression range: the first slice is the
  small-strain stiffness, last over first is the stiffening ratio, and a largest-over-smallest
  slope above :data:`NONLINEAR_RATIO` (among the slopes known to :data:`SLOPE_REL_SE`) flags
  ``nonlinear_stiffness``.
* :func:`speed_summary`: whether the squeezes move at more than one speed; a single speed
  (a constant-rate ramp, a load–unload cycle at one rate, without a hold) cannot separate a
  rate-dependent force from a rate-independent one, so damping is not identifiable.
* :func:`hysteresis_energy_j`: the energy a closed load–unload loop dissipates, ``∮ f dd``.
* :func:`damping_excitation`: the share of the rate a constant force and the compression cannot
  explain (:func:`deformctl.characterize.quality.damping_identifiable`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from deformctl.series import FloatArray

#: Slices of the loading compression range for the tangent stiffness (the first is the small
#: strain: 0–10 % of the largest loading compression).
STIFFNESS_BINS = 10
#: ``nonlinear_stiffness`` when the largest slice slope exceeds the smallest by this factor ...
NONLINEAR_RATIO = 2.0
#: ... among the slices whose slope has a standard error below this fraction of it (under heavy
#: damping the small-strain force is mostly the damping taken out, and its error with it).
SLOPE_REL_SE = 0.2
#: Slices with fewer samples are not used.
MIN_BIN_SAMPLES = 5
#: A window moves when its speed exceeds this fraction of the 95th percentile speed.
MOVING_FRAC = 0.1
#: ... and holds when below this fraction.
HOLD_FRAC = 0.02
#: The squeezes move at one speed when the 90th over the 10th percentile of the moving windows'
#: speeds is below this (a testing machine's constant crosshead rate: 1.00–1.05 on the shared
#: phantom recordings; the synthetic squeezes' two speeds: 2.5).
SINGLE_SPEED_SPREAD = 1.5
#: A hold counts when it lasts at least this many windows under at least this fraction of the
#: peak compression (a hold under load, not the rest before contact).
HOLD_WINDOWS = 2
HOLD_MIN_COMPRESSION_FRAC = 0.1
#: A squeeze is a closed loop when it ends below this fraction of its peak compression.
CLOSED_LOOP_FRAC = 0.1


def operating_force_n(
    at_force_n: float | None,
    weight_n: float | None,
    friction_mu: float | None,
    loading_force_n: FloatArray,
) -> tuple[float, str]:
    """The force the deformability is stated at, N, and where it came from.

    Returns:
        ``(force, source)``: ``"option"`` (``at_force_n``), ``"f_w"`` (W/(2μ)) or
        ``"median_loading"`` (the median force of the loading samples).
    """
    if at_force_n is not None:
        return float(at_force_n), "option"
    if (
        weight_n is not None
        and friction_mu is not None
        and math.isfinite(weight_n)
        and math.isfinite(friction_mu)
        and weight_n > 0
        and friction_mu > 0
    ):
        from deformctl.physics import rigid_grip_force_n

        return float(rigid_grip_force_n(weight_n, friction_mu)), "f_w"
    return float(np.median(loading_force_n)), "median_loading"


@dataclass(frozen=True)
class LoadingStiffness:
    """The loading curve's slopes (N/m).

    Attributes:
        small_strain_n_per_m: slope of the first slice (0–10 % of the loading compression).
        large_strain_n_per_m: slope of the last slice (90–100 %).
        slopes_n_per_m: every slice's slope (NaN where too few samples).
        slope_se_n_per_m: their standard errors: the slice's scatter and the fitted damping's
            standard error carried through the rate-dependent force taken out.
    """

    small_strain_n_per_m: float
    large_strain_n_per_m: float
    slopes_n_per_m: tuple[float, ...]
    slope_se_n_per_m: tuple[float, ...] = ()

    @property
    def stiffening_ratio(self) -> float:
        """Last slice over first slice (NaN when either is not positive)."""
        a, b = self.small_strain_n_per_m, self.large_strain_n_per_m
        return b / a if a > 0 and b > 0 else math.nan

    def _known_slopes(self) -> FloatArray:
        """The slopes known to :data:`SLOPE_REL_SE`."""
        se = self.slope_se_n_per_m or tuple(0.0 for _ in self.slopes_n_per_m)
        return np.asarray(
            [
                x
                for x, e in zip(self.slopes_n_per_m, se, strict=True)
                if math.isfinite(x) and math.isfinite(e) and e <= SLOPE_REL_SE * abs(x)
            ],
            dtype=np.float64,
        )

    @property
    def falling(self) -> bool:
        """A slice whose slope is known falls or is flat: the loading curve has a falling
        stretch (a squeeze that slips or yields before its peak, a buckling plateau-then-dip)."""
        s = self._known_slopes()
        return bool(s.size >= 2 and np.any(s <= 0))

    @property
    def tangent_spread(self) -> float:
        """Largest over smallest slope of the slices whose slope is known to
        :data:`SLOPE_REL_SE` (NaN: fewer than two, or one of them not positive: see
        :attr:`falling`; a ratio of slopes of both signs is no spread)."""
        s = self._known_slopes()
        if s.size < 2 or np.any(s <= 0):
            return math.nan
        return float(np.max(s) / np.min(s))

    @property
    def nonlinear(self) -> bool:
        """The tangent stiffness varies by more than :data:`NONLINEAR_RATIO` over the loading,
        or falls over a stretch of it (:attr:`falling`)."""
        spread = self.tangent_spread
        return self.falling or (not math.isnan(spread) and spread > NONLINEAR_RATIO)


def loading_stiffness(
    compression_m: FloatArray,
    elastic_force_n: FloatArray,
    *,
    rate_force_per_unit: FloatArray | None = None,
    rate_unit_se: float = 0.0,
    correlated_samples: int = 1,
) -> LoadingStiffness:
    """Straight-line slopes of the elastic force over :data:`STIFFNESS_BINS` slices of the
    loading compression ``[0, max]`` (module docstring).

    Args:
        compression_m: the loading samples' compression, m ``[n]``.
        elastic_force_n: their force with the fitted rate-dependent part taken out, N ``[n]``.
        rate_force_per_unit: the rate-dependent force taken out, per unit of its fitted
            coefficient, ``[n]`` (None: none was taken out).
        rate_unit_se: that coefficient's standard error.
        correlated_samples: samples over which the elastic force's errors are correlated (the
            smoothing window of the rate taken out); the scatter's error is inflated by its root.
    """
    top = float(np.max(compression_m))
    edges = np.linspace(0.0, top, STIFFNESS_BINS + 1)
    slopes: list[float] = []
    ses: list[float] = []
    for i in range(STIFFNESS_BINS):
        sel = (compression_m >= edges[i]) & (compression_m <= edges[i + 1])
        count = int(np.count_nonzero(sel))
        if count < MIN_BIN_SAMPLES:
            slopes.append(math.nan)
            ses.append(math.nan)
            continue
        d, f = compression_m[sel], elastic_force_n[sel]
        dc = d - d.mean()
        den = float(dc @ dc)
        if not den > 0:
            slopes.append(math.nan)
            ses.append(math.nan)
            continue
        slope = float(dc @ (f - f.mean())) / den
        resid = f - f.mean() - slope * dc
        var = float(resid @ resid) / max(count - 2, 1) / den * max(correlated_samples, 1)
        if rate_force_per_unit is not None and rate_unit_se > 0:
            r = rate_force_per_unit[sel]
            var += (float(dc @ (r - r.mean())) / den * rate_unit_se) ** 2
        slopes.append(slope)
        ses.append(math.sqrt(var))
    return LoadingStiffness(slopes[0], slopes[-1], tuple(slopes), tuple(ses))


@dataclass(frozen=True)
class SpeedSummary:
    """How the squeezes move.

    Attributes:
        speeds_m_per_s: each squeeze's median moving speed, m/s.
        spread: 90th over 10th percentile of all moving windows' speeds.
        holds: squeezes with a hold under load of at least :data:`HOLD_WINDOWS` windows.
    """

    speeds_m_per_s: tuple[float, ...]
    spread: float
    holds: int

    @property
    def single_speed(self) -> bool:
        """One speed and no hold: damping cannot be told from a rate-independent force."""
        return self.spread < SINGLE_SPEED_SPREAD and self.holds == 0


def speed_summary(
    rates: Sequence[FloatArray], compressions: Sequence[FloatArray], window_samples: int
) -> SpeedSummary:
    """Speeds of each squeeze from its window-mean rates and compressions (module docstring).

    Args:
        rates: per squeeze, the window-mean rates, m/s ``[m_i]``.
        compressions: per squeeze, the window-mean compressions, m ``[m_i]``.
        window_samples: the window (windows start every quarter window).
    """
    speeds = np.abs(np.concatenate(list(rates))) if rates else np.zeros(0)
    if speeds.size == 0:
        return SpeedSummary((), math.nan, 0)
    top = float(np.percentile(speeds, 95))
    moving = speeds > MOVING_FRAC * top
    if not np.any(moving):
        return SpeedSummary(tuple(0.0 for _ in rates), math.nan, 0)
    q10, q90 = np.percentile(speeds[moving], [10, 90])
    spread = float(q90 / q10) if q10 > 0 else math.inf
    per: list[float] = []
    holds = 0
    stride_windows = HOLD_WINDOWS * 4  # windows start every quarter window
    peak = max(float(np.max(c)) for c in compressions if c.size) if compressions else 0.0
    for v, c in zip(rates, compressions, strict=True):
        s = np.abs(v)
        mv = s > MOVING_FRAC * top
        per.append(float(np.median(s[mv])) if np.any(mv) else 0.0)
        if not np.any(mv):
            continue
        first = int(np.argmax(mv))
        still = (s < HOLD_FRAC * top) & (c > HOLD_MIN_COMPRESSION_FRAC * peak)
        still[:first] = False
        run = 0
        for flag in still:
            run = run + 1 if flag else 0
            if run >= stride_windows:
                holds += 1
                break
    return SpeedSummary(tuple(per), spread, holds)


def hysteresis_energy_j(compressions: Sequence[FloatArray], forces: Sequence[FloatArray]) -> float:
    """Mean energy dissipated per closed load–unload loop, J (NaN when no squeeze closes).

    ``∮ f dd`` over a squeeze that ends below :data:`CLOSED_LOOP_FRAC` of its peak compression
    (trapezoid rule on the raw samples): the work done on the object that it did not return.
    """
    loops = []
    for d, f in zip(compressions, forces, strict=True):
        if d.size < 3:
            continue
        peak = float(np.max(d))
        if not peak > 0 or float(d[-1]) > CLOSED_LOOP_FRAC * peak:
            continue
        loops.append(float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(d))))
    return float(np.mean(loops)) if loops else math.nan


def damping_excitation(compression_m: FloatArray, rate_m_per_s: FloatArray) -> float:
    """Share of the rate's mean square not explained by a constant and by d, in [0, 1].

    ``‖d' − P d'‖² / ‖d'‖²`` with ``P`` the projection onto ``[1, d]``: 0 for a constant rate
    (``λ d'`` is then a constant force) or a rate that follows d, 1 for a rate independent of
    both (a load–unload cycle). See :func:`deformctl.characterize.quality.damping_identifiable`.
    """
    total = float(rate_m_per_s @ rate_m_per_s)
    if not total > 0:
        return 0.0
    a = np.column_stack([np.ones_like(compression_m), compression_m])
    coef, *_ = np.linalg.lstsq(a, rate_m_per_s, rcond=None)
    resid = rate_m_per_s - a @ coef
    return float(min(1.0, (resid @ resid) / total))
